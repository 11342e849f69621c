"""The accuracy of an orbit: its error estimate by step halving, and the step that meets
a target.

A settled point's ``error_estimate`` is the change of its metrics when its orbit is solved
again at twice the steps per period; with RK4's fourth order, the coarse orbit's own error
is about 16/15 of it. Where the estimate is above the point's ``accuracy``, the point is
solved again at the step the fourth order asks for (:func:`refined_steps`).
"""

from __future__ import annotations

import numpy as np

from ._engine import METRIC

#: Re-solves at a finer step for the accuracy target [-].
REFINEMENTS = 3
#: A re-solve whose error estimate fell slower than this order of the step asks for
#: twice the steps next, not for the fourth order's: near grazing the estimate wanders
#: about its trend from one step to the next (docs/numerics.md) [-].
SLOW_ORDER = 2.0
#: The steps per period of a re-solve are a multiple of this [-].
STEPS_QUANTUM = 16


def halving_error(coarse: np.ndarray, fine: np.ndarray) -> np.ndarray:
    """Error estimate [-] of metric rows from a run and its rerun at twice the steps per
    period (same points, engine metric rows).

    The largest relative change of ``power`` and ``v_peak`` and of ``x_max`` and ``x_min``
    (relative to the displacement amplitude): with RK4's 4th order the coarse run's own
    error is about 16/15 of it.
    """
    coarse, fine = np.asarray(coarse), np.asarray(fine)

    def change(index, scale):
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.abs(coarse[..., index] - fine[..., index]) / scale
        return np.where(scale > 0, ratio, 0.0)

    amplitude = 0.5 * (fine[..., METRIC.x_max] - fine[..., METRIC.x_min])
    return np.maximum.reduce([
        change(METRIC.power, np.abs(fine[..., METRIC.power])),
        change(METRIC.v_peak, np.abs(fine[..., METRIC.v_peak])),
        change(METRIC.x_max, amplitude),
        change(METRIC.x_min, amplitude),
    ])


def refined_steps(steps, errors, target, coarser, refine):
    """Steps per period (n,) to solve again at for error estimates ``errors`` (n,) [-] at
    ``steps`` (n,) to meet ``target`` (n,) [-]: the fourth order's ask with a margin of
    1.1, or twice the steps after a re-solve (``refine`` > 0) whose estimate fell slower
    than SLOW_ORDER from the last one's, ``coarser`` (n, 2): its steps and estimate."""
    want = np.ceil(steps * (errors / target) ** 0.25 * 1.1 / STEPS_QUANTUM) * STEPS_QUANTUM
    before, error = coarser.T
    with np.errstate(divide="ignore", invalid="ignore"):
        order = np.log(error / errors) / np.log(steps / before)
    slow = (refine > 0) & ~(order >= SLOW_ORDER)
    return np.where(slow, 2 * steps, want)
