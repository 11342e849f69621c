"""When the orbit solver may take a periodic orbit: the motion is on its way to it.

Newton's method on the period map converges to unstable orbits and to orbits that the
motion from its initial state never reaches as readily as to its attractor; it only
accelerates the motion. A converged orbit is taken when the motion is proved to reach it
(docs/numerics.md, "Periodic orbits"):

- an orbit clear of the stops, when the motion provably never reaches a stop either
  (:func:`never_reaches`: an energy bound of the linear motion's transient);
- an orbit with contact, when the motion is in its linear regime (:func:`on_its_way`),
  within its margin from grazing a stop (:func:`reach`).

Distances are relative to each component's scale (:func:`norm`). Each function judges one
point, compiled: the orbit solver calls them inside its rounds.
"""

from __future__ import annotations

import numpy as np

from . import dense
from ._engine import METRIC, N_RIGID, PARAM
from .jit import SOLVER_JIT, njit
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


@njit(**SOLVER_JIT)
def norm(d, scale):
    """Largest component of ``d`` (D,) relative to ``scale`` (D,) [-]; NaN if any is."""
    best = -np.inf
    for c in range(d.shape[0]):
        r = abs(d[c]) / scale[c]
        if r != r:
            return np.nan
        best = max(best, r)
    return best


@njit(**SOLVER_JIT)
def reaches_a_stop(row, high, low):
    """Whether a motion between x = ``low`` and ``high`` [m] comes to a stop of packed row
    ``row`` (len(PARAM)): to the gap of an upper stop, or to a lower one (a NaN extent
    counts as reaching)."""
    return (row[PARAM.khm] > 0 and not high < row[PARAM.gap]) \
        or (row[PARAM.lower_khm] > 0 and not low > -row[PARAM.lower_gap])


@njit(**SOLVER_JIT)
def on_its_way(t0, t1, q, y, jac, scale, floor, near=NEAR):
    """Whether a motion at ``t0`` (D,), ``q`` maps of the period map later at ``t1``, is
    on its way to its fixed point ``y`` (D,) of monodromy ``jac`` (D, D), in components
    relative to ``scale`` (D,), with Newton's floor ``floor`` [-].

    Yes where ``t0`` is on the fixed point (within the floor), or where it is within
    ``near`` of it (NEAR, or nearer: :func:`reach`), the monodromy predicts ``t1 - y``
    from ``t0 - y`` to LINEAR_REGIME of its size, and the prediction from ``t1`` for AHEAD
    more maps stays within NEAR, where the linear regime was seen to hold. (A motion may
    first move away from a stable orbit, as one of a non-normal monodromy does: on its way
    too, if it stays near.)
    """
    d0 = norm(t0 - y, scale)
    d1 = norm(t1 - y, scale)
    predicted = t0 - y
    for _ in range(q):
        predicted = dense.matvec(jac, predicted)
    linear = norm(t1 - y - predicted, scale) <= LINEAR_REGIME * d1 + floor
    stays = d1 <= NEAR
    ahead = t1 - y
    for _ in range(AHEAD):
        ahead = dense.matvec(jac, ahead)
        stays = stays and norm(ahead, scale) <= NEAR
    way = d0 <= near and linear and stays and d0 > floor
    return d0 <= floor or way


@njit(**SOLVER_JIT)
def reach(m, scale):
    """How near a motion must come to an orbit of metric row ``m`` (len(METRIC)) to be in
    its linear regime, relative to the component scales ``scale`` (D,) [-]: NEAR, or
    nearer an orbit that comes near grazing a stop (GRAZING times the margin).

    The period map is smooth only as long as the motion makes the orbit's contacts and no
    other: a motion farther from the orbit than the top of one of its swings is from the
    stop (``near_miss``) may touch where it does not, and one farther than the overshoot
    its slowest impact would carry a harmonic swing beyond the gap, 0.5 (v_imp / (w x))^2
    of the amplitude x (``approach_velocity_min``), may miss that impact. A stable orbit
    that grazes is then the attractor of no motion beyond that margin."""
    miss = m[METRIC.near_miss] / scale[0]
    ratio = m[METRIC.approach_velocity_min] / scale[1]
    overshoot = 0.5 * (ratio * ratio)
    margin = np.fmin(miss, overshoot)
    return min(GRAZING * margin, NEAR) if margin >= 0 else NEAR


@njit(**SOLVER_JIT)
def never_reaches(row, high, low, e):
    """Whether a motion a deviation ``e`` (D,) [m, m/s, V, (m, m/s)] from an orbit clear of
    the stops that reaches from x = ``low`` to ``high`` [m] never reaches a stop of packed
    row ``row`` (len(PARAM)) either.

    The homogeneous part of the linear motion loses energy, which bounds its excursion B
    (the model's ``excursion_bound``), so ``x(t) <= high + B`` at all later times, and
    ``x(t) >= low - B`` (a moving stop's own transient is bounded alike)."""
    bound = tip_mass.excursion_bound(e[0], e[1], e[2], row[PARAM.wn2], row[PARAM.thm],
                                     row[PARAM.thc])
    if e.shape[0] > N_RIGID:  # (a moving stop's own transient)
        stop = tip_mass.stop_excursion_bound(e[N_RIGID], e[N_RIGID + 1], row[PARAM.stop_wn2])
        bound = bound + (stop if row[PARAM.stop_ratio] > 0 else 0.0)
    return high + bound + PROOF_MARGIN * (abs(high) + bound) < row[PARAM.gap] \
        and low - bound - PROOF_MARGIN * (abs(low) + bound) > -row[PARAM.lower_gap]


@njit(**SOLVER_JIT)
def closing_period(strobes, y, p, scale, tol):
    """The orbit period [forcing periods] of a fixed point ``y`` (D,) of the p-period map:
    the smallest divisor d of p whose strobe d periods on is within ``tol`` of ``y``,
    relative to ``scale`` (D,), else p. ``strobes`` (n, D): the last strobes of a run of
    p periods from ``y``, oldest first (n > p)."""
    n = strobes.shape[0]
    for d in range(1, p):
        if p % d == 0 and norm(strobes[n - 1 - (p - d)] - y, scale) <= tol:
            return d
    return p


@njit(**SOLVER_JIT)
def periods_to_near(p, near, distance, radius):
    """Periods a motion ``distance`` from a stable orbit of period ``p`` and spectral
    radius ``radius`` needs to come to half ``near`` of it (relative to the scales) [-]:
    how long to integrate on before the next attempt at that orbit."""
    return np.ceil(p * np.log(near / (2 * distance))
                   / np.log(min(max(radius, 1e-3), 1 - 1e-9)))


@njit(**SOLVER_JIT)
def suggested_period(strobes, scale):
    """The orbit period [forcing periods] suggested by a run's last stroboscopic samples
    ``strobes`` (n, D), oldest first, in components relative to ``scale`` (D,): the
    smallest p < n whose repeat |y(nT) - y((n-p)T)| is within 10 times the best of any."""
    n = strobes.shape[0]
    gaps = np.empty(n - 1)
    best = np.inf
    for k in range(n - 1):
        gap = norm(strobes[n - 1] - strobes[n - 2 - k], scale)
        gaps[k] = gap if np.isfinite(gap) else np.inf
        best = min(best, gaps[k])
    if not np.isfinite(best):
        return 1
    for k in range(n - 1):
        if gaps[k] <= 10 * best:
            return k + 1
    return 1
