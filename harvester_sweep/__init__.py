"""harvester_sweep: steady states of a piezoelectric harvester striking a Hertz bump stop.

Data flows one way: parameters (validated, SI units) -> packing (the engine's rows) ->
the engine (``_engine``, private) -> results -> datasets (xarray, CF netCDF) -> plots and
the command line. The registry of outputs (``outputs``) names every metric and status.
"""

from .environment import check_threads

check_threads()  # (before numba is imported: numba's import fails on a bad thread count)

from .basins import basin_fractions, basin_map
from .continuation import NoOrbitError, continue_branch
from .outputs import OUTPUTS, STATUSES
from .parameters import PARAMETERS, PRESETS, ParameterError, TooStiffError, resolve_parameters
from .scene import SceneResult, run_scene
from .sweep import run_sweep
from .sweep_file import SweepSpec, load_sweep
from .version import __version__

__all__ = [
    "OUTPUTS",
    "PARAMETERS",
    "PRESETS",
    "STATUSES",
    "NoOrbitError",
    "ParameterError",
    "SceneResult",
    "SweepSpec",
    "TooStiffError",
    "__version__",
    "basin_fractions",
    "basin_map",
    "continue_branch",
    "load_sweep",
    "resolve_parameters",
    "run_scene",
    "run_sweep",
]
