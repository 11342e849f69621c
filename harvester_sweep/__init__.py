"""harvester_sweep: steady states of a piezoelectric harvester striking a Hertz bump stop."""

from .parameters import PARAMETERS, PRESETS, ParameterError, resolve_parameters
from .scene import SceneResult, run_scene

__version__ = "0.1.0"

__all__ = [
    "PARAMETERS",
    "PRESETS",
    "ParameterError",
    "SceneResult",
    "__version__",
    "resolve_parameters",
    "run_scene",
]
