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
from .jit import SOLVER_JIT, njit

#: Re-solves at a finer step for the accuracy target [-].
REFINEMENTS = 3
#: A re-solve whose error estimate fell slower than this order of the step asks for
#: twice the steps next, not for the fourth order's: near grazing the estimate wanders
#: about its trend from one step to the next (docs/numerics.md) [-].
SLOW_ORDER = 2.0
#: The steps per period of a re-solve are a multiple of this [-].
STEPS_QUANTUM = 16
#: A coarse orbit's error over its step-halving estimate, by RK4's fourth order: the
#: change to twice the steps is 15/16 of the coarse run's error [-].
ERROR_PER_ESTIMATE = 16 / 15


@njit(**SOLVER_JIT)
def _change(coarse, fine, scale):
    """|coarse - fine| / scale [-], 0 where the scale is not positive."""
    return abs(coarse - fine) / scale if scale > 0 else 0.0


@njit(**SOLVER_JIT)
def halving_error(coarse, fine):
    """Error estimate [-] of the metric row ``coarse`` of a run from the row ``fine`` of
    its rerun at twice the steps per period (engine metric rows).

    The largest relative change of ``power``, ``v_peak`` and a moving stop's
    ``stop_displacement_max`` (relative to their own size; a rigid stop's is 0 at every
    step, and adds nothing) and of ``x_max`` and ``x_min`` (relative to the displacement
    amplitude): with RK4's 4th order the coarse run's own error is about 16/15 of it.
    """
    amplitude = 0.5 * (fine[METRIC.x_max] - fine[METRIC.x_min])
    out = _change(coarse[METRIC.power], fine[METRIC.power], abs(fine[METRIC.power]))
    out = np.maximum(out, _change(coarse[METRIC.v_peak], fine[METRIC.v_peak],
                               abs(fine[METRIC.v_peak])))
    out = np.maximum(out, _change(coarse[METRIC.stop_displacement_max],
                               fine[METRIC.stop_displacement_max],
                               abs(fine[METRIC.stop_displacement_max])))
    out = np.maximum(out, _change(coarse[METRIC.x_max], fine[METRIC.x_max], amplitude))
    return np.maximum(out, _change(coarse[METRIC.x_min], fine[METRIC.x_min], amplitude))


@njit(**SOLVER_JIT)
def refined_steps(steps, error, target, before, before_error, refine):
    """Steps per period to solve again at for an error estimate ``error`` [-] at ``steps``
    to meet ``target`` [-]: the fourth order's ask with a margin of 1.1, or twice the
    steps after a re-solve (``refine`` > 0) whose estimate fell slower than SLOW_ORDER
    from the last one's, ``before_error`` at ``before`` steps per period."""
    want = np.ceil(steps * (error / target) ** 0.25 * 1.1 / STEPS_QUANTUM) * STEPS_QUANTUM
    order = np.log(before_error / error) / np.log(steps / before)
    if refine > 0 and not order >= SLOW_ORDER:
        return 2.0 * steps
    return want
