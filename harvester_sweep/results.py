"""Results: packed points run through the engine, and what comes back, named.

:func:`solve` runs the engine on packed points and gives each point chosen for it an
error estimate by step halving: the point is run again from its final state at twice the
steps per period, and the estimate is the largest relative change of its metrics
(:func:`halving_error`). Columns are read by name through the registry
(:mod:`harvester_sweep.outputs`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from . import _engine
from ._engine import METRIC, N_STROBE, PARAM, STATUS
from .outputs import STATUS_NAMES
from .packing import Packed


@dataclass
class Results:
    """What the engine gives back for n points.

    Attributes
    ----------
    metrics : numpy.ndarray
        float64 (n, len(layouts.METRIC)): the engine's metric rows (SI units, see
        :mod:`harvester_sweep.outputs`).
    strobes : numpy.ndarray
        float64 (n, samples, 3): the last stroboscopic samples y(nT), columns x [m],
        v [m/s], V [V].
    finals : numpy.ndarray
        float64 (n, 4): each point's final state (layouts.STATE).
    errors : numpy.ndarray
        float64 (n,): step-halving error estimates [-], NaN where not estimated or not
        settled.
    run_time : float
        Wall-clock time of the engine run, error estimates not included [s].
    """

    metrics: np.ndarray
    strobes: np.ndarray
    finals: np.ndarray
    errors: np.ndarray
    run_time: float

    def point(self, i: int) -> dict:
        """Metrics of point ``i`` by name, as plain Python values: ``status`` by name,
        integers for counts, None for a missing value (no impact, not estimated)."""
        out = {name: float(self.metrics[i, k]) for k, name in enumerate(METRIC._fields)}
        out["error_estimate"] = float(self.errors[i])
        status = int(out["status"])
        out["status"] = STATUS_NAMES[status]
        out["converged"] = status == STATUS.settled
        for name in ("orbit_period", "periods_run"):
            out[name] = int(out[name])
        for name, value in out.items():
            if isinstance(value, float) and not math.isfinite(value):
                out[name] = None  # JSON null: no impact (approach_velocity) or diverged
        return out


def solve(packed: Packed, successors=None, estimated=None, samples: int = 0,
          on_points=None) -> Results:
    """Run packed points to steady state.

    Parameters
    ----------
    packed : Packed
        Points from :func:`harvester_sweep.packing.pack_points`; ``packed.states`` are
        not modified.
    successors : numpy.ndarray, optional
        int (n,): the point that starts from each point's final state, -1 for none
        (frequency continuation; see the engine's ``run_points``).
    estimated : numpy.ndarray, optional
        bool (n,): the points given a step-halving error estimate (default: none).
    samples : int
        Stroboscopic samples kept per point.
    on_points : callable, optional
        Called with the number of points newly finished, as they finish.
    """
    n = len(packed)
    states = packed.states.copy()
    metrics = np.empty((n, len(METRIC)))
    strobes = np.empty((n, samples, N_STROBE))
    _engine.warm_up()  # compile or load from the on-disk cache outside the timing
    start = time.perf_counter()
    _engine.run_points(packed.rows, states, metrics, strobes, successors, on_points)
    run_time = time.perf_counter() - start
    errors = np.full(n, np.nan)
    chosen = np.zeros(n, dtype=bool) if estimated is None else estimated & ~packed.refused
    if chosen.any():
        halved = packed.rows[chosen].copy()
        halved[:, PARAM.steps] *= 2
        fine = np.empty((len(halved), len(METRIC)))
        _engine.run_points(halved, states[chosen].copy(), fine,
                           np.empty((len(halved), 0, N_STROBE)))
        errors[chosen] = halving_error(metrics[chosen], fine)
    return Results(metrics, strobes, states, errors, run_time)


def halving_error(coarse: np.ndarray, fine: np.ndarray) -> np.ndarray:
    """Error estimate [-] of metric rows from a run and its rerun at twice the steps per
    period (same points, engine metric rows).

    The largest relative change of ``power`` and ``v_peak`` and of ``x_max`` and ``x_min``
    (relative to the displacement amplitude): with RK4's 4th order the coarse run's own
    error is about 16/15 of it. NaN where either run did not settle.
    """
    coarse, fine = np.asarray(coarse), np.asarray(fine)

    def change(index, scale):
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.abs(coarse[..., index] - fine[..., index]) / scale
        return np.where(scale > 0, ratio, 0.0)

    amplitude = 0.5 * (fine[..., METRIC.x_max] - fine[..., METRIC.x_min])
    error = np.maximum.reduce([
        change(METRIC.power, np.abs(fine[..., METRIC.power])),
        change(METRIC.v_peak, np.abs(fine[..., METRIC.v_peak])),
        change(METRIC.x_max, amplitude),
        change(METRIC.x_min, amplitude),
    ])
    settled = ((coarse[..., METRIC.status] == STATUS.settled)
               & (fine[..., METRIC.status] == STATUS.settled))
    return np.where(settled, error, np.nan)
