"""Results: packed points solved to their periodic orbits, and what comes back, named.

:func:`solve` hands packed points to the periodic-orbit solver
(:mod:`harvester_sweep.orbits`), which runs them through the engine to their steady
states, with Floquet multipliers and, for the points chosen, a step-halving error
estimate. Columns are read by name through the registry (:mod:`harvester_sweep.outputs`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ._engine import METRIC, STATUS
from .orbits import compile_solver, solve_orbits
from .outputs import RUN_OUTPUTS, STATUS_NAMES
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
    multipliers : numpy.ndarray
        complex128 (n, 3): Floquet multipliers of the orbit [-], largest modulus first;
        NaN where not settled.
    steps : numpy.ndarray
        int64 (n,): steps per period of the orbit reported (finer than asked where the
        accuracy target called for it).
    rk4_steps : numpy.ndarray
        int64 (n,): RK4 steps taken for each point, all runs included.
    run_time : float
        Wall-clock time of the solve, error estimates included [s].
    """

    metrics: np.ndarray
    strobes: np.ndarray
    finals: np.ndarray
    errors: np.ndarray
    multipliers: np.ndarray
    steps: np.ndarray
    rk4_steps: np.ndarray
    run_time: float

    def point(self, i: int) -> dict:
        """Metrics of point ``i`` by name, as plain Python values: ``status`` by name,
        integers for counts, None for a missing value (no impact, not estimated)."""
        out = {name: float(self.metrics[i, k]) for k, name in enumerate(METRIC._fields)}
        out["error_estimate"] = float(self.errors[i])
        for name, values in self.run_outputs().items():
            value = values[i]
            out[name] = value.tolist() if value.ndim else value.item()
        status = int(out["status"])
        out["status"] = STATUS_NAMES[status]
        out["converged"] = status == STATUS.settled
        for name in ("orbit_period", "periods_run"):
            out[name] = int(out[name])
        for name, value in out.items():
            if isinstance(value, float) and not math.isfinite(value):
                out[name] = None  # JSON null: no impact (approach_velocity) or diverged
            elif isinstance(value, list):
                out[name] = [v if math.isfinite(v) else None for v in value]
        return out

    def run_outputs(self) -> dict:
        """The solver's outputs (outputs.RUN_OUTPUTS) by name: arrays of n points, each
        with its own dimensions after the first."""
        values = {"spectral_radius": np.abs(self.multipliers[:, 0]),
                  "floquet_multipliers_real": self.multipliers.real,
                  "floquet_multipliers_imag": self.multipliers.imag,
                  "steps_per_period": self.steps, "rk4_steps": self.rk4_steps}
        assert tuple(values) == RUN_OUTPUTS
        return values


def solve(packed: Packed, successors=None, estimated=None, samples: int = 0,
          on_points=None) -> Results:
    """Solve packed points to their periodic orbits (:func:`harvester_sweep.orbits.solve_orbits`).

    Parameters
    ----------
    packed : Packed
        Points from :func:`harvester_sweep.packing.pack_points`; ``packed.states`` are
        not modified.
    successors : numpy.ndarray, optional
        int (n,): the point that starts from each point's orbit, -1 for none (frequency
        continuation; see the engine's ``run_points``).
    estimated : numpy.ndarray, optional
        bool (n,): the points given a step-halving error estimate (default: none); those
        whose step was automatic are solved again at a finer step until the estimate
        meets their ``accuracy``.
    samples : int
        Stroboscopic samples kept per point.
    on_points : callable, optional
        Called with the number of points newly finished, as they finish.
    """
    n = len(packed)
    chosen = np.zeros(n, dtype=bool) if estimated is None else estimated & ~packed.refused
    compile_solver()  # compile or load from the on-disk cache outside the timing
    start = time.perf_counter()
    orbits = solve_orbits(packed.rows, packed.states, successors, chosen, packed.accuracy,
                          packed.max_steps, samples, on_points)
    run_time = time.perf_counter() - start
    return Results(orbits.metrics, orbits.strobes, orbits.finals, orbits.errors,
                   orbits.multipliers, orbits.steps, orbits.rk4_steps, run_time)
