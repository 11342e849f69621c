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


#: Newton iterations for the top of a force peak's quartic, from the parabola's vertex
#: (which is within a few hundredths of a step of it: three iterations reach rounding) [-].
PEAK_ITERATIONS = 4


@njit(inline="always", **JIT)
def at_peak(L, j, fcp, fc, fcn):
    """Whether lane ``j`` books a contact-force peak at the step whose start samples the
    force fc [N], fcp a step before and fcn at its end: fc the largest of the three, in
    a contact (fcp > 0), where the lane books peaks (LANE.turn_floor 0)."""
    return L[LANE.turn_floor + j] == 0.0 and fcp > 0.0 and fc >= fcp and fc > fcn


@njit(inline="always", **JIT)
def peak(L, j, fcp, fc, fcn, dfc, dfcn, h, upper):
    """Book the peak of a contact force sampled fcp, fc, fcn [N] at three step ends h [s]
    apart, fc the largest (at_peak); among the upper stop's peaks when ``upper``.

    Where the contact goes on past the step (fcn > 0) the force is smooth over the two
    steps, and the peak is the top of the quartic through the three samples and the
    force's rate dF_c/dt at the step's start and end (dfc, dfcn [N/s]): its error is
    RK4's, falling as the step to the fourth power. Else (a contact of two steps, the
    separation inside this one) it is the vertex of the parabola through the samples,
    whose error falls as the step squared."""
    a = 0.5 * (fcp + fcn) - fc  # (< 0: fc is the largest, and above fcn)
    b = 0.5 * (fcn - fcp)
    s = min(max(-b / (2.0 * a), -1.0), 1.0)  # the parabola's vertex [steps from fc]
    top = fc - b * b / (4.0 * a)
    if fcn > 0.0:
        # p(s) = fc + c1 s + c2 s^2 + c3 s^3 + c4 s^4 through p(-1) = fcp, p(0) = fc,
        # p(1) = fcn, p'(0) = h dfc, p'(1) = h dfcn
        c1 = h * dfc
        c3 = b - c1
        c4 = 0.5 * (h * dfcn - c1 - 3.0 * c3) - a
        c2 = a - c4
        for _ in range(PEAK_ITERATIONS):
            slope = c1 + s * (2.0 * c2 + s * (3.0 * c3 + s * 4.0 * c4))
            bend = 2.0 * c2 + s * (6.0 * c3 + s * 12.0 * c4)
            if not bend < 0.0:  # (not a top: keep the parabola's)
                break
            s = min(max(s - slope / bend, -1.0), 1.0)
        top = max(fc + s * (c1 + s * (c2 + s * (c3 + s * c4))), fc)
    L[LANE.fc_max + j] = max(L[LANE.fc_max + j], top)
    if upper:
        L[LANE.fc_peak_min + j] = min(L[LANE.fc_peak_min + j], top)
        L[LANE.fc_peak_max + j] = max(L[LANE.fc_peak_max + j], top)


@njit(inline="always", **JIT)
def extrema(L, j, x, v, V, dV, xn, vn, Vn, dVn, h, fcp, fc, fcn, dfc, dfcn, upper, near):
    """Book the extrema of lane ``j``'s step of h [s] from (x, v, V) to (xn, vn, Vn)
    (dV, dVn: dV/dt at its ends [V/s]): of x and V inside it on the cubic Hermite
    interpolant, a contact-force peak (fcp, fc, fcn [N]: the force a step before its start,
    at its start and at its end; dfc, dfcn [N/s]: its rate at the step's ends, read only
    at a peak: :func:`peak`), and both ends (the ends of the runs of plain steps, see
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
    if at_peak(L, j, fcp, fc, fcn):
        peak(L, j, fcp, fc, fcn, dfc, dfcn, h, upper)
    L[LANE.x_max + j], L[LANE.x_min + j] = (max(L[LANE.x_max + j], x, xn),
                                            min(L[LANE.x_min + j], x, xn))
    L[LANE.v_max + j], L[LANE.v_peak + j] = (max(L[LANE.v_max + j], abs(vn)),
                                             max(L[LANE.v_peak + j], abs(V), abs(Vn)))
    L[LANE.fc_max + j] = max(L[LANE.fc_max + j], fc, fcn)
