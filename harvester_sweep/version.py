"""The package's version, as installed (pyproject.toml is its one source)."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("harvester_sweep")
except PackageNotFoundError:  # (a source tree on sys.path, not installed)
    __version__ = "0+unknown"
