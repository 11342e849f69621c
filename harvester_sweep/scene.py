"""One scene: a single parameter point run to steady state, its metrics and its orbit."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import period_map
from .packing import check_runnable, pack_parameters, pack_points
from .parameters import DEFAULT_PRESET, PRESET_NOTES, ParameterError, resolve_parameters
from .results import solve


@dataclass(frozen=True)
class SceneSpec:
    """A checked scene (:func:`check_scene`), which :func:`run_scene` takes as it is.

    Attributes
    ----------
    preset : str or None
        The preset the parameters start from (``None``: ``DEFAULT_PRESET``).
    parameters : dict
        The full, validated parameter set (SI units, see ``PARAMETERS``), runnable (not
        too stiff).
    """

    preset: str | None
    parameters: dict


def check_scene(preset: str | None = DEFAULT_PRESET, **parameters) -> SceneSpec:
    """Check a scene's input once: the preset with ``parameters`` (SI units) resolved, and
    the point refused if too stiff.

    Raises
    ------
    ParameterError
        For an unknown name or a value out of range; TooStiffError for a point whose step
        would exceed max_steps_per_period.
    """
    values = resolve_parameters(preset, **parameters)
    check_runnable(values)  # too stiff: refused before integration
    return SceneSpec(preset, values)


@dataclass
class SceneResult:
    """The steady state of one parameter point.

    Attributes
    ----------
    parameters : dict
        The full, validated parameter set (SI units, see ``PARAMETERS``).
    metrics : dict
        Metric name -> value (units: ``outputs.OUTPUTS``); ``status`` is one of
        ``"settled"``, ``"not settled"``, ``"diverged"``; ``approach_velocity`` is None when
        the orbit has no impact; ``error_estimate`` (step halving, see
        ``orbits.halving_error``) is None when the point did not settle.
    state : numpy.ndarray
        State at the last period boundary, in the engine's order (``_engine.STATE``):
        ``(x [m], v [m/s], voltage [V], stop_x [m], stop_v [m/s], approach_velocity [m/s])``,
        the stop's 0 for a rigid stop and the approach velocity the one latched at the
        last first touch.
    notes : list of str
        Assumptions of the preset.
    """

    parameters: dict
    metrics: dict
    state: np.ndarray
    notes: list = field(default_factory=list)

    @property
    def converged(self) -> bool:
        return self.metrics["converged"]

    def series(self, periods: int | None = None):
        """Time series over ``periods`` forcing periods from the final state.

        Once settled, these are the last periods of the steady orbit. By default a whole
        number of orbits covering at least 4 forcing periods.

        Returns
        -------
        xarray.Dataset
            ``displacement`` [m], ``velocity`` [m/s], ``voltage`` [V],
            ``instantaneous_power`` [W] (V^2/R), ``contact_force`` [N] on a ``time`` [s] axis.
        """
        from .datasets import series_dataset

        if periods is None:
            orbit = max(int(self.metrics["orbit_period"]), 1)
            periods = orbit * math.ceil(4 / orbit)
        values = period_map.record(pack_parameters(self.parameters), self.state, periods)
        t0 = self.metrics["periods_run"] / self.parameters["frequency"]
        return series_dataset(values, t0, self.parameters)

    def dataset(self, periods: int | None = None):
        """Metrics, time series of the last orbit periods and parameters as one Dataset."""
        from .datasets import scene_dataset

        return scene_dataset(self, self.series(periods))

    def to_netcdf(self, path, periods: int | None = None) -> None:
        """Write :meth:`dataset` to a netCDF file (written aside, then renamed)."""
        from .datasets import write_netcdf

        write_netcdf(self.dataset(periods), path)

    def plot(self, path=None, periods: int | None = None):
        """Four panels like the paper's Fig. 3; saved to ``path`` when given."""
        from .plots import plot_scene

        return plot_scene(self.dataset(periods), path)


def run_scene(preset: str | SceneSpec | None = DEFAULT_PRESET, **parameters) -> SceneResult:
    """Run one scene to steady state.

    Parameters
    ----------
    preset : str, SceneSpec or None
        A preset name (``"paper"``, ``"strong_coupling"``); ``None`` is
        ``DEFAULT_PRESET``, the paper's. Or a scene already checked (:func:`check_scene`),
        taken as it is, with no other argument.
    **parameters
        Overrides by name in SI units, e.g. ``gap=2e-6`` [m], ``resistance=1e5`` [Ohm].

    Returns
    -------
    SceneResult

    Raises
    ------
    ParameterError
        Before any integration, for an unknown name or a value out of range; TooStiffError
        for a point whose step would exceed max_steps_per_period.
    """
    if not isinstance(preset, SceneSpec):
        spec = check_scene(preset, **parameters)
    elif parameters:  # (a checked scene holds every value: another beside it would be ignored)
        raise ParameterError("a SceneSpec is the whole problem: give no other argument "
                             "beside it")
    else:
        spec = preset
    values = dict(spec.parameters)  # (the result's own copy)
    packed = pack_points([values])
    results = solve(packed, estimated=np.ones(1, dtype=bool))
    out = results.point(0)
    out["run_time"] = results.run_time
    notes = PRESET_NOTES.get(spec.preset or DEFAULT_PRESET, [])
    return SceneResult(values, out, results.finals[0], notes)
