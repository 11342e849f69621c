"""harvester_sweep: steady states of a piezoelectric harvester striking a Hertz bump stop."""

from .parameters import PARAMETERS, PRESETS, ParameterError, resolve_parameters
from .scene import SceneResult, run_scene
from .sweep import run_sweep
from .sweep_file import SweepSpec, load_sweep

__version__ = "0.1.0"

__all__ = [
    "PARAMETERS",
    "PRESETS",
    "ParameterError",
    "SceneResult",
    "SweepSpec",
    "__version__",
    "load_sweep",
    "resolve_parameters",
    "run_scene",
    "run_sweep",
]
