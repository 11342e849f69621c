"""numba's on-disk cache of the engine, kept in step with the engine's source.

numba checks a cached function against the stamp of the file that defines it, but the
engine's entry points inline functions of every file of this package, of the models it
runs (harvester_sweep.models) and of the compile flags (harvester_sweep.jit): after an edit of
one of those alone (an editable install), they would run the old code. A digest of the
whole engine's source is kept beside the cache; when it differs, every cached function of
the engine is dropped and compiled again. The orbit solver keeps its own digest the same
way (engine and solver sources: orbits.SOURCE_DIGEST), which also identifies the solver in
a tip-mass sweep's hash, so that a partial result is never resumed by another one.

Each engine has its own digest, of the files its machine code is made from: the lane
engine of the tip-mass model is not recompiled when the beam's modal engine is edited, and
a run compiles only the engine of the model it uses.
"""

from __future__ import annotations

import hashlib
import pickle
from pathlib import Path

import numba

_HERE = Path(__file__).parent
PACKAGE = _HERE.parent
#: The source the lane engine's machine code is made from: its own files, the models it
#: runs, the flags.
ENGINE_SOURCES = (_HERE, PACKAGE / "models" / "hertz.py", PACKAGE / "models" / "state.py",
                  PACKAGE / "models" / "tip_mass.py", PACKAGE / "jit.py")


def source_digest(sources=ENGINE_SOURCES) -> str:
    """SHA-256 of source files (folders: their ``*.py``, not below), in the order given
    and name order within a folder."""
    digest = hashlib.sha256()
    files = [p for s in sources for p in (sorted(s.glob("*.py")) if s.is_dir() else [s])]
    for path in files:
        digest.update(path.relative_to(PACKAGE).as_posix().encode() + b"\0"
                      + path.read_bytes())
    return digest.hexdigest()


SOURCE_DIGEST = source_digest()
_FLUSHED: list = []  # not empty once this process dropped the cache


def _dispatchers(modules):
    for module in modules:
        for value in vars(module).values():
            if isinstance(value, numba.core.registry.CPUDispatcher):
                yield value


def flush_if_changed(entry, modules, digest=SOURCE_DIGEST) -> None:
    """Drop the cached machine code of every jitted function of ``modules`` when their
    source (``digest``: the engine's by default) has changed since ``entry`` (a
    dispatcher) was cached."""
    cache = getattr(entry, "_cache", None)
    if cache is None or not hasattr(cache, "cache_path"):
        return
    marker = Path(cache.cache_path) / "engine-source-sha256"
    try:
        if marker.exists() and marker.read_text() == digest:
            return
        for dispatcher in _dispatchers(modules):
            dispatcher._cache.flush()
        marker.write_text(digest)
        _FLUSHED.append(True)
    except OSError:  # an unwritable cache: numba recompiles or falls back by itself
        pass


def holds(entry) -> bool:
    """Whether numba's on-disk cache holds machine code of ``entry`` (a dispatcher) for its
    present source. Unlike is_warm it reads the index, which a flush leaves empty, so it
    answers the same in a process that flushed the cache; True where it cannot be told
    (another numba's internals, an index being written)."""
    try:
        return bool(entry._cache._cache_file._load_index())
    except (AttributeError, OSError, EOFError, pickle.UnpicklingError):
        return True


def is_warm(entry) -> bool:
    """Whether ``entry`` (a dispatcher) is in numba's on-disk cache; if not, its first call
    compiles it (the engine, or the orbit solver)."""
    if _FLUSHED:
        return False
    try:
        return Path(entry._cache._cache_file._index_path).exists()
    except AttributeError:  # another numba's internals: say nothing
        return True
