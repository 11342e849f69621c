"""What a lane books from a step it finished in scalar code: first touches, and the
period's extrema and contact-force peaks placed inside the step; and how near its swings
came to grazing a rigid stop: the distance a swing's top stays short of it (a near miss),
the approach velocity of a first touch (both 0 at a grazing).

Shared by the rigid stop's finish (lanes.finish_step) and the moving stop's
(stop_motion.step), which differ in how they take the step, not in what they book.
"""

from __future__ import annotations

from ..jit import JIT, njit
from . import hermite
from .layouts import LANE


@njit(inline="always", **JIT)
def impact(L, j, v_on, ch):
    """Book a first touch of lane ``j`` at approach velocity ``v_on`` [m/s]; returns the
    contact damping [s/m] from now on: ``ch``, or with the latched law c_h v_imp / v_on."""
    L[LANE.impacts + j] += 1.0
    L[LANE.sum_vimp + j] += v_on
    L[LANE.vimp_min + j] = min(L[LANE.vimp_min + j], v_on)
    latch = L[LANE.latch + j]
    if latch > 0.0 and v_on > 0.0:
        L[LANE.vimp + j] = v_on
        return latch / v_on
    return ch


@njit(inline="always", **JIT)
def peak(L, j, fcp, fc, fcn, upper):
    """Book the peak of a contact force sampled fcp, fc, fcn [N] at three step ends,
    fc the largest: the vertex of the parabola through them; among the upper stop's peaks
    when ``upper``."""
    a = 0.5 * (fcp + fcn) - fc
    b = 0.5 * (fcn - fcp)
    top = fc - b * b / (4.0 * a)
    L[LANE.fc_max + j] = max(L[LANE.fc_max + j], top)
    if upper:
        L[LANE.fc_peak_min + j] = min(L[LANE.fc_peak_min + j], top)
        L[LANE.fc_peak_max + j] = max(L[LANE.fc_peak_max + j], top)


@njit(inline="always", **JIT)
def extrema(L, j, x, v, V, dV, xn, vn, Vn, dVn, h, fcp, fc, fcn, upper, near):
    """Book the extrema of lane ``j``'s step of h [s] from (x, v, V) to (xn, vn, Vn)
    (dV, dVn: dV/dt at its ends [V/s]): of x and V inside it on the cubic Hermite
    interpolant, a contact-force peak (fcp, fc, fcn [N]: the force a step before its start,
    at its start and at its end), and both ends (the ends of the runs of plain steps, see
    lanes._commit_steps); a top of x short of ``near`` [m] (the gap of the rigid stop the
    lane faces, inf for none) as a near miss. The extrema inside, the force peak and the
    near miss only where the lane books them (LANE.turn_floor 0: see
    layouts.BOOKED_METRICS)."""
    turns = L[LANE.turn_floor + j] == 0.0
    if turns and (v > 0.0 >= vn or v < 0.0 <= vn):
        xe = hermite.extremum(x, v, xn, vn, h)
        L[LANE.x_max + j], L[LANE.x_min + j] = (max(L[LANE.x_max + j], xe),
                                                min(L[LANE.x_min + j], xe))
        if v > 0.0 and xe < near:
            L[LANE.near_miss + j] = min(L[LANE.near_miss + j], near - xe)
    if turns and (dV > 0.0) != (dVn > 0.0):
        L[LANE.v_peak + j] = max(L[LANE.v_peak + j], abs(hermite.extremum(V, dV, Vn, dVn, h)))
    if turns and fcp > 0.0 and fc >= fcp and fc > fcn:  # parabola through the peak
        peak(L, j, fcp, fc, fcn, upper)
    L[LANE.x_max + j], L[LANE.x_min + j] = (max(L[LANE.x_max + j], x, xn),
                                            min(L[LANE.x_min + j], x, xn))
    L[LANE.v_max + j], L[LANE.v_peak + j] = (max(L[LANE.v_max + j], abs(vn)),
                                             max(L[LANE.v_peak + j], abs(V), abs(Vn)))
    L[LANE.fc_max + j] = max(L[LANE.fc_max + j], fc, fcn)
