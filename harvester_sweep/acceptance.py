"""When the orbit solver may take a periodic orbit: the motion is on its way to it.

Newton's method on the period map converges to unstable orbits and to orbits that the
motion from its initial state never reaches as readily as to its attractor; it only
accelerates the motion. A converged orbit is taken when the motion is proved to reach it
(docs/numerics.md, "Periodic orbits"):

- an orbit clear of the stops, when the motion provably never reaches a stop either
  (:func:`never_reaches`: an energy bound of the linear motion's transient);
- an orbit with contact, when the motion is in its linear regime (:func:`on_its_way`),
  within its margin from grazing a stop (:func:`reach`).

Distances are relative to each component's scale (:func:`norm`).
"""

from __future__ import annotations

import numpy as np

from . import dense
from ._engine import METRIC, N_RIGID, PARAM
from .models import tip_mass

#: A motion is in an orbit's linear regime when the monodromy predicts its next p periods
#: to this fraction of their distance from the orbit [-].
LINEAR_REGIME = 0.1
#: ... and it is within this distance of the orbit, relative to the orbit's amplitudes: a
#: guard, as one look at the linear regime is a heuristic and near a fold the basin of
#: another attractor lies close to the orbit [-].
NEAR = 0.1
#: ... and within this share of the orbit's margin from grazing a stop (:func:`reach`) [-].
GRAZING = 1.0
#: Maps of p periods the monodromy's prediction is followed to see that it stays NEAR [-].
AHEAD = 16
#: Margin of the no-contact proof, relative to the bound, for the step's own error (RK4
#: and the Hermite interpolant are far below it at any step the engine takes) [-].
PROOF_MARGIN = 1e-3


def norm(d, scale):
    """Largest component of ``d`` (..., D) relative to ``scale`` (..., D) [-]."""
    return np.max(np.abs(d) / scale, axis=-1)


def reaches_a_stop(rows, high, low):
    """Whether motions between x = ``low`` and ``high`` [m] (n,) come to a stop of packed
    rows (n, len(PARAM)): to the gap of an upper stop, or to a lower one (a NaN extent
    counts as reaching)."""
    return (rows[:, PARAM.khm] > 0) & ~(high < rows[:, PARAM.gap]) \
        | (rows[:, PARAM.lower_khm] > 0) & ~(low > -rows[:, PARAM.lower_gap])


def on_its_way(t0, t1, q, y, jac, scale, floor, near=NEAR):
    """Whether motions at ``t0`` (n, D), ``q`` (n,) maps of the period map later at ``t1``,
    are on their way to its fixed points ``y`` (n, D) of monodromy ``jac`` (n, D, D), in
    components relative to ``scale`` (n, D), with Newton's floor ``floor`` (n,) [-].

    Yes where ``t0`` is on the fixed point (within the floor), or where it is within
    ``near`` (n,) of it (NEAR, or nearer: :func:`reach`), the monodromy predicts ``t1 - y``
    from ``t0 - y`` to LINEAR_REGIME of its size, and the prediction from ``t1`` for AHEAD
    more maps stays within NEAR, where the linear regime was seen to hold. (A motion may
    first move away from a stable orbit, as one of a non-normal monodromy does: on its way
    too, if it stays near.)
    """
    d0 = norm(t0 - y, scale)
    d1 = norm(t1 - y, scale)
    predicted = t0 - y
    for k in range(int(q.max(initial=0))):
        predicted = np.where((k < q)[:, None], dense.matvec_each(jac, predicted),
                             predicted)
    linear = norm(t1 - y - predicted, scale) <= LINEAR_REGIME * d1 + floor
    ahead = np.empty((AHEAD,) + y.shape)
    ahead[0] = dense.matvec_each(jac, t1 - y)
    for k in range(1, AHEAD):
        ahead[k] = dense.matvec_each(jac, ahead[k - 1])
    stays = (d1 <= NEAR) & np.all(norm(ahead, scale) <= NEAR, axis=0)
    way = (d0 <= near) & linear & stays & (d0 > floor)
    return (d0 <= floor) | way


def reach(m, scale):
    """How near a motion must come to orbits of metric rows ``m`` (n, len(METRIC)) to be
    in their linear regime, relative to the component scales ``scale`` (n, D) [-]: NEAR,
    or nearer an orbit that comes near grazing a stop (GRAZING times the margin).

    The period map is smooth only as long as the motion makes the orbit's contacts and no
    other: a motion farther from the orbit than the top of one of its swings is from the
    stop (``near_miss``) may touch where it does not, and one farther than the overshoot
    its slowest impact would carry a harmonic swing beyond the gap, 0.5 (v_imp / (w x))^2
    of the amplitude x (``approach_velocity_min``), may miss that impact. A stable orbit
    that grazes is then the attractor of no motion beyond that margin."""
    with np.errstate(invalid="ignore"):
        miss = m[:, METRIC.near_miss] / scale[:, 0]
        overshoot = 0.5 * (m[:, METRIC.approach_velocity_min] / scale[:, 1]) ** 2
    margin = np.fmin(miss, overshoot)
    return np.where(margin >= 0, np.minimum(GRAZING * margin, NEAR), NEAR)


def never_reaches(rows, high, low, e):
    """Whether motions a deviation ``e`` (n, D) [m, m/s, V, (m, m/s)] from orbits clear of
    the stops that reach from x = ``low`` to ``high`` [m] (n,) never reach a stop of packed
    rows (n, len(PARAM)) either.

    The homogeneous part of the linear motion loses energy, which bounds its excursion B
    (the model's ``excursion_bound``), so ``x(t) <= high + B`` at all later times, and
    ``x(t) >= low - B`` (a moving stop's own transient is bounded alike)."""
    bound = tip_mass.excursion_bound(e[:, :N_RIGID], rows[:, PARAM.wn2], rows[:, PARAM.thm],
                                     rows[:, PARAM.thc])
    if e.shape[1] > N_RIGID:  # (a moving stop's own transient)
        stop = tip_mass.stop_excursion_bound(e[:, N_RIGID:], rows[:, PARAM.stop_wn2])
        bound = bound + np.where(rows[:, PARAM.stop_ratio] > 0, stop, 0.0)
    return (high + bound + PROOF_MARGIN * (np.abs(high) + bound) < rows[:, PARAM.gap]) \
        & (low - bound - PROOF_MARGIN * (np.abs(low) + bound) > -rows[:, PARAM.lower_gap])
