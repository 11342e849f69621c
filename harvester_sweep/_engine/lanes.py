"""The lane table: many points stepped together, LANES at a time per thread.

The plain RK4 step of every lane runs in branch-free loops over groups of GROUP lanes,
which LLVM compiles to vector code: out of contact the step is linear, and is applied as
the matrix it is (tip_mass.free_step_map), or as the matrix of several such steps at once
(a multi-step: :func:`resume`); a group with a lane in contact also runs the RK4 stages
with the contact force. The rare steps that need more (a contact switch to locate, graded
sub-steps next to a touch or a separation, an extremum or a force peak to place, the end
of a forcing period) are marked and finished lane by lane in scalar code
(:func:`finish_step`); the steps just after a touch and before a separation, in quarter
steps, run first, in vector code on the lanes that take them, packed (quarter_steps).

A point's result does not depend on its lane: every lane runs the same vector
instructions, and which steps run scalar code is decided by the point's own state (see
flags). Which point a lane holds is the scheduler's business (:mod:`.scheduler`).
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import JIT, njit
from ..models import hertz
from ..models.tip_mass import (
    Coefficients,
    contact_force,
    contact_force_rate,
    derivatives,
    free_step_map,
    in_contact,
    rk4,
    voltage_rate,
)
from . import booking, hermite, steady, stop_motion, tangents
from .layouts import (
    ACC,
    BLOCK,
    BOOKED_METRICS,
    GROUP,
    LANE,
    LANES,
    METRIC,
    MULTI_ROWS,
    N_STROBE,
    N_VALUES,
    PARAM,
    STATE,
    STATUS,
)
from .rk4 import GRADED, GRADED_TO_SWITCH, WHOLE, pieces, switch_step, switch_tangents
from .steady import MAX_ORBIT_PERIOD

# Steps between exact resets of the forcing rotation, whose rounding drifts: at every
# multiple of SYNC steps, and at each period's start. Over 2048 steps (sin, cos) drift by
# at most 9e-14 (at 368-65536 steps a period), far below RK4's error where a period has few
# steps and about the rounding floor where it has many; each reset is a step finished in
# scalar code, hence not more often.
SYNC = 2048.0


# The rows of layouts.MULTI_ROWS and their alt_ rows, swapped when a lane changes mode (a
# multi-step always marks the turns of v and V: see resume).
_MULTI_ROWS = tuple((getattr(LANE, name), getattr(LANE, "alt_" + name))
                    for name in MULTI_ROWS)


# Multi-steps a period at least [-]: int V^2 dt is booked on the cubic Hermite
# interpolant over a multi-step, whose error grows as the fourth power of its length; at
# this many a period it stays about that of the RK4 steps themselves (whose error is
# what the step-halving estimate measures, and which a multi-step does not change).
MULTI_SPAN = 256.0


@njit(**JIT)
def multi_steps(p):
    """Steps a multi-step of a point of parameter row ``p`` takes (resume): PARAM.multi,
    halved until the period holds MULTI_SPAN of them, where the lane's steps clear of the
    stops are the linear map (switches located, a rigid stop, no latched law); else 1."""
    if not (p[PARAM.locate] != 0.0 and p[PARAM.stop_ratio] == 0.0
            and p[PARAM.latch] == 0.0 and p[PARAM.lower_latch] == 0.0):
        return 1.0
    r = float(int(p[PARAM.multi]))
    while r > 1.0 and p[PARAM.steps] < MULTI_SPAN * r:
        r = math.floor(r / 2.0)
    return max(r, 1.0)


@njit(**JIT)
def _load_multi(L, j, m, r, n_steps, h):
    """The alt_ rows of lane ``j``: a multi-step of ``r`` contact-free steps, whose
    increment (3 x 5, as m's: tip_mass.free_step_map) is found by taking the r steps from
    each basis vector of (x, v, V, sin, cos), the forcing rotated a step at a time as the
    lane loop rotates it; its increments are summed, not I + D formed (see free_step_map).
    (In scalars: ``m @ z`` on arrays this small costs a BLAS call each, and this runs at
    every load of a point, which for the orbit solver's one-period runs is as often as a
    period.)"""
    cb, sb = L[LANE.cos_step + j], L[LANE.sin_step + j]
    for i in range(5):
        z0, z1, z2 = 1.0 if i == 0 else 0.0, 1.0 if i == 1 else 0.0, 1.0 if i == 2 else 0.0
        z3, z4 = 1.0 if i == 3 else 0.0, 1.0 if i == 4 else 0.0
        t0, t1, t2 = 0.0, 0.0, 0.0
        for _ in range(int(r)):
            d0 = m[0, 0] * z0 + m[0, 1] * z1 + m[0, 2] * z2 + m[0, 3] * z3 + m[0, 4] * z4
            d1 = m[1, 0] * z0 + m[1, 1] * z1 + m[1, 2] * z2 + m[1, 3] * z3 + m[1, 4] * z4
            d2 = m[2, 0] * z0 + m[2, 1] * z1 + m[2, 2] * z2 + m[2, 3] * z3 + m[2, 4] * z4
            z0, z1, z2 = z0 + d0, z1 + d1, z2 + d2
            t0, t1, t2 = t0 + d0, t1 + d1, t2 + d2
            z3, z4 = z3 * cb + z4 * sb, z4 * cb - z3 * sb
        L[LANE.alt_mxx + i * LANES + j] = t0
        L[LANE.alt_mvx + i * LANES + j] = t1
        L[LANE.alt_mex + i * LANES + j] = t2
    L[LANE.alt_cos_step + j] = math.cos(2.0 * math.pi * r / n_steps)
    L[LANE.alt_sin_step + j] = math.sin(2.0 * math.pi * r / n_steps)
    L[LANE.alt_half_h + j], L[LANE.alt_h2_6 + j] = 0.5 * r * h, (r * h) ** 2 / 6.0
    L[LANE.alt_turn_floor + j] = 0.0


@njit(inline="always", **JIT)
def _swap_multi(L, j):
    """Swap lane ``j``'s rows of one step and of a multi-step (_MULTI_ROWS)."""
    for a, b in _MULTI_ROWS:
        L[a + j], L[b + j] = L[b + j], L[a + j]
    L[LANE.mode + j] = 1.0 - L[LANE.mode + j]


@njit(**JIT)
def resume(L, j, it):
    """Lane ``j``, whose next step is in iteration ``it``, takes multi-steps from there
    where it can: LANE.multi > 1, out of contact, no quarter steps due, and room for one
    before its next stop (LANE.k_end: a resync or the period's end, which it takes in
    single steps).

    A multi-step is the composition of LANE.multi contact-free steps: the same map as
    the steps one at a time, up to rounding, at the cost of one. The lane loop marks it as
    it marks a step: where it ends in contact, past the mirror's threshold, with a turn of
    v or V inside (always, booked or not: a swing's top inside it may graze the stop) or
    at LANE.k_end, here the iteration of the last multi-step up to the next stop (which it
    reaches where the steps left are a multiple of LANE.multi). finish_step finishes it
    whole where it holds nothing but turns clear of the stop, or the stop at its end
    (_turns_only); else it takes it apart (_take_apart): it is redone as single steps, so
    that every switch, near miss and period end is found and finished as a step finds it."""
    r = L[LANE.multi + j]
    if r <= 1.0 or L[LANE.mode + j] != 0.0 or L[LANE.on + j] != 0.0 or L[LANE.fine + j] != 0.0:
        return
    whole = math.floor((L[LANE.k_end + j] - it + 1.0) / r)  # (up to the stop's step)
    if whole < 1.0:
        return
    _swap_multi(L, j)
    L[LANE.multi_since + j] = it
    L[LANE.k_end + j] = it + whole - 1.0


@njit(inline="always", **JIT)
def _leave_multi(L, j, it):
    """Lane ``j``, whose multi-steps ran up to iteration ``it`` (not included), goes back to
    single steps: its counts of steps (LANE.k0, LANE.t_since, in iterations) move back by
    the steps its multi-steps took beyond one each."""
    extra = (L[LANE.multi + j] - 1.0) * (it - L[LANE.multi_since + j])
    L[LANE.k0 + j] -= extra
    L[LANE.t_since + j] -= extra
    _swap_multi(L, j)


@njit(**JIT)
def _take_apart(L, j, it):
    """Lane ``j``'s multi-step of iteration ``it`` is marked: the lane goes back to single
    steps, its counts of steps (LANE.k0, LANE.t_since, in iterations) moved back by the
    steps its multi-steps took beyond one each, and its trial step is this iteration's
    single step. It takes single steps until past LANE.hold, the last step the multi-step
    spanned, unless what it was taken apart for comes sooner (finish_step)."""
    _leave_multi(L, j, it)
    L[LANE.hold + j] = it + L[LANE.multi + j] - 1.0
    x, v, V, s0, c0 = _state(L, j)
    L[LANE.x_trial + j] = x + _increment(L, LANE.mxx + j, x, v, V, s0, c0)
    L[LANE.v_trial + j] = v + _increment(L, LANE.mvx + j, x, v, V, s0, c0)
    L[LANE.voltage_trial + j] = V + _increment(L, LANE.mex + j, x, v, V, s0, c0)


@njit(**JIT)
def new_table():
    """A lane table of zeros, aligned to 64 bytes: no vector load of a row straddles two
    cache lines (a misaligned table ran the lane loop about 20 % slower)."""
    block = np.zeros(len(LANE) * LANES + 8)
    skip = (8 - block.ctypes.data % 64 // 8) % 8
    return block[skip : skip + len(LANE) * LANES]


@njit(**JIT)
def load(L, j, p, y, it):
    """Put the point of parameter row ``p`` and state ``y`` into lane ``j``, at t = 0, to
    take its first step in iteration ``it`` of the lane loop."""
    n_steps = p[PARAM.steps]
    h = p[PARAM.period] / n_steps
    L[LANE.amplitude + j], L[LANE.wn2 + j], L[LANE.cm + j], L[LANE.thm + j] = (
        p[PARAM.amplitude],
        p[PARAM.wn2],
        p[PARAM.cm],
        p[PARAM.thm],
    )
    L[LANE.khm + j], L[LANE.kh + j], L[LANE.gap + j] = (
        p[PARAM.khm],
        p[PARAM.khm] * p[PARAM.mass],
        p[PARAM.gap],
    )
    L[LANE.latch + j] = p[PARAM.latch]
    L[LANE.irc + j], L[LANE.thc + j] = p[PARAM.irc], p[PARAM.thc]
    L[LANE.h + j], L[LANE.half_h + j], L[LANE.h2_6 + j] = h, 0.5 * h, h * h / 6.0
    ca, sa = math.cos(math.pi / n_steps), math.sin(math.pi / n_steps)
    L[LANE.cos_half + j], L[LANE.sin_half + j] = ca, sa
    L[LANE.cos_step + j], L[LANE.sin_step + j] = (
        math.cos(2 * math.pi / n_steps),
        math.sin(2 * math.pi / n_steps),
    )
    L[LANE.cos_eighth + j], L[LANE.sin_eighth + j] = (
        math.cos(math.pi / (4 * n_steps)),
        math.sin(math.pi / (4 * n_steps)),
    )
    m = free_step_map(
        h,
        ca,
        sa,
        p[PARAM.amplitude],
        p[PARAM.wn2],
        p[PARAM.cm],
        p[PARAM.thm],
        p[PARAM.irc],
        p[PARAM.thc],
    )
    for r, row in enumerate((LANE.mxx, LANE.mvx, LANE.mex)):
        for c in range(5):
            L[row + c * LANES + j] = m[r, c]
    L[LANE.steps + j], L[LANE.locate + j] = n_steps, p[PARAM.locate]
    L[LANE.turn_floor + j] = 0.0 if p[PARAM.book] != 0.0 else -np.inf
    r = multi_steps(p)
    L[LANE.multi + j], L[LANE.mode + j], L[LANE.hold + j] = r, 0.0, -np.inf
    if r > 1.0:
        _load_multi(L, j, m, r, n_steps, h)
    L[LANE.phase + j] = p[PARAM.phase]
    x, v, V = y[STATE.x], y[STATE.v], y[STATE.voltage]
    vimp = y[STATE.approach_velocity]
    latch = p[PARAM.latch]
    ch = latch / vimp if latch > 0.0 else p[PARAM.ch]
    g = p[PARAM.gap]
    L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j], L[LANE.vimp + j], L[LANE.ch + j] = (
        x,
        v,
        V,
        vimp,
        ch,
    )
    # the lower stop waits in the *_other rows (NO_STOP: never reached)
    g_low, latch_low = p[PARAM.lower_gap], p[PARAM.lower_latch]
    L[LANE.gap_other + j], L[LANE.latch_other + j] = g_low, latch_low
    L[LANE.khm_other + j] = p[PARAM.lower_khm]
    L[LANE.kh_other + j] = p[PARAM.lower_khm] * p[PARAM.mass]
    L[LANE.ch_other + j] = latch_low / vimp if latch_low > 0.0 else p[PARAM.lower_ch]
    L[LANE.vimp_other + j] = vimp
    L[LANE.sign + j], L[LANE.flip_below + j] = 1.0, 0.5 * (g - g_low)
    # a moving stop (stop_motion): its state, and every step finished in scalar code (a
    # threshold of mirroring no x is below); the lane loop sees no contact (LANE.on 0)
    xs, vs = y[STATE.stop_x], y[STATE.stop_v]
    moving = p[PARAM.stop_ratio] > 0.0
    L[LANE.stop_x + j], L[LANE.stop_v + j] = xs, vs
    L[LANE.stop_wn2 + j], L[LANE.stop_cm + j] = p[PARAM.stop_wn2], p[PARAM.stop_cm]
    L[LANE.stop_ratio + j] = p[PARAM.stop_ratio]
    L[LANE.tangents + j] = 1.0 if p[PARAM.tangents] != 0.0 and tangents.carried(p) else 0.0
    tangents.start(L, j, it)  # (mirrored below with the state)
    if moving:
        L[LANE.flip_below + j] = np.inf
    elif x < L[LANE.flip_below + j]:
        mirror(L, j)
    x, v, g, ch = L[LANE.x + j], L[LANE.v + j], L[LANE.gap + j], L[LANE.ch + j]
    on = 1.0 if p[PARAM.locate] == 0.0 or in_contact(x - xs, v - vs, g, ch) else 0.0
    L[LANE.on + j], L[LANE.stop_on + j] = (0.0, on) if moving else (on, 0.0)
    L[LANE.fine + j] = 0.0
    L[LANE.periods + j] = 0.0
    _start_period(L, j, it)


@njit(**JIT)
def _start_period(L, j, it):
    """Reset the per-period accumulators of lane ``j`` and the forcing phase to its start, for a
    period whose first step is taken in iteration ``it`` of the lane loop.

    Every lane takes one step an iteration, so a lane's steps into its period are the
    iterations since LANE.k0; LANE.k_end is the iteration at whose end the lane stops (a resync
    of the forcing phase or the period's end): a row to compare with, not a count to
    update, in the lane loop."""
    x, v, V = L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j]
    xs, vs = L[LANE.stop_x + j], L[LANE.stop_v + j]  # (0 for a rigid stop: the same bits)
    fc = contact_force(x - xs, v - vs, max(L[LANE.on + j], L[LANE.stop_on + j])
                       * L[LANE.kh + j], L[LANE.gap + j], L[LANE.ch + j])
    L[LANE.stop_x_max + j] = abs(xs)
    L[LANE.fc_peak_min + j], L[LANE.fc_peak_max + j] = np.inf, -np.inf
    L[LANE.near_miss + j], L[LANE.vimp_min + j] = np.inf, np.inf
    L[LANE.q + j] = 0.0
    L[LANE.x_max + j], L[LANE.x_min + j], L[LANE.v_max + j], L[LANE.v_peak + j] = (
        x,
        x,
        abs(v),
        abs(V),
    )
    L[LANE.fc_previous + j], L[LANE.fc + j], L[LANE.fc_max + j] = fc, fc, fc
    L[LANE.impacts + j], L[LANE.sum_vimp + j] = 0.0, 0.0
    L[LANE.impacts_other + j], L[LANE.sum_vimp_other + j], L[LANE.fc_max_other + j] = (
        0.0, 0.0, 0.0)
    phase = L[LANE.phase + j]  # (0 but for a start within a period: sin 0, cos 1 exactly)
    L[LANE.sin + j], L[LANE.cos + j] = math.sin(phase), math.cos(phase)
    L[LANE.k0 + j] = it
    L[LANE.k_end + j] = it + min(SYNC, L[LANE.steps + j]) - 1.0


# Rows that change sign when a lane mirrors: the state, the forcing, the contact-free map's
# forcing columns, the mirror's own threshold and the state's derivative (tangents).
_NEGATED = (LANE.x, LANE.v, LANE.voltage, LANE.amplitude, LANE.mxs, LANE.mxc, LANE.mvs,
            LANE.mvc, LANE.mes, LANE.mec, LANE.alt_mxs, LANE.alt_mxc, LANE.alt_mvs,
            LANE.alt_mvc, LANE.alt_mes, LANE.alt_mec, LANE.flip_below) + tuple(
                range(LANE.txx, LANE.tee + LANES, LANES))
# Rows of the stop in use and of the other one, swapped when a lane mirrors.
_SWAPPED = ((LANE.gap, LANE.gap_other), (LANE.kh, LANE.kh_other), (LANE.khm, LANE.khm_other),
            (LANE.ch, LANE.ch_other), (LANE.latch, LANE.latch_other),
            (LANE.vimp, LANE.vimp_other), (LANE.impacts, LANE.impacts_other),
            (LANE.sum_vimp, LANE.sum_vimp_other), (LANE.fc_max, LANE.fc_max_other))


@njit(**JIT)
def mirror(L, j):
    """Hand lane ``j`` over to its other stop, out of contact.

    The model without its stops is odd: (x, v, V) -> (-x, -v, -V) with the forcing
    negated maps its solutions onto each other, and maps the lower stop at x = -g_l onto
    an upper stop at g_l. So a lane holds one stop at a time, the nearer one, and every
    contact path of the kernel serves both: at half way between the stops (LANE.flip_below)
    the lane negates its state and forcing and swaps the two stops' rows. Negation is exact,
    so a point that never comes half way to a lower stop gets the bits it gets without one.
    """
    L[LANE.sign + j] = -L[LANE.sign + j]
    for r in _NEGATED:
        L[r + j] = -L[r + j]
    for a, b in _SWAPPED:
        L[a + j], L[b + j] = L[b + j], L[a + j]
    L[LANE.x_max + j], L[LANE.x_min + j] = -L[LANE.x_min + j], -L[LANE.x_max + j]
    L[LANE.fc + j], L[LANE.fc_previous + j] = 0.0, 0.0


@njit(**JIT)
def lane_steps(L, it):
    """One plain RK4 step of the lanes of both groups, branch-free so that LLVM vectorizes
    it.

    The trial steps run group by group into trial rows: a group is GROUP lanes (two AVX2
    vectors), written out with constant bounds so that it compiles to vector code only.
    A lane out of contact steps by the RK4 step's linear map (tip_mass.free_step_map, 15
    multiply-adds and 3 adds; a multi-step's in multi-step mode: resume); a group with a
    lane in contact also runs the RK4 stages with the contact force, and each lane takes
    the one that applies to it, so that a point gets the same bits whatever its
    neighbours. Two groups rather than one block of LANES, because a block is more often
    in contact; not four groups of one vector, whose contact-free loop LLVM compiled to
    scalar code once the trial step got short. A second loop commits: lanes whose step
    needs more (a contact switch, graded sub-steps near a touch or a separation, an
    extremum to place, a force peak, the end of a period) are marked in LANE.need and left
    for :func:`finish_step`. Both groups are committed in one loop, in the contact form if
    either has a lane in contact (a lane out of contact commits the same bits either
    way), because one loop for each group, each in its own form, compiled to slower code
    (benchmarks/results/commit_groups_47.md). Returns the number of lanes with a point
    marked, and how many of them take quarter steps (see quarter_steps).
    """
    touching = _trial_group(L, 0) + _trial_group(L, GROUP)
    if touching == 0.0:
        return _commit_steps(L, False, it, LANES)
    return _commit_steps(L, True, it, LANES)


@njit(**JIT)
def first_group_steps(L, it):
    """:func:`lane_steps` of a table whose second group is idle (at most GROUP points: the
    last points of a call, a round of few lines): the first group's trial step and its
    commit alone. A function of its own, as lane_steps with a branch for it compiled to
    slower code for full tables (benchmarks/results/commit_groups_47.md)."""
    if _trial_group(L, 0) == 0.0:
        return _commit_steps(L, False, it, GROUP)
    return _commit_steps(L, True, it, GROUP)


@njit(inline="always", **JIT)
def _trial_group(L, j0):
    """The RK4 stages of group j0 (see lane_steps); returns how many of its lanes touch."""
    touching = 0.0
    for j in range(j0, j0 + GROUP):
        touching += L[LANE.on + j]
    if touching == 0.0:
        _trial_steps(L, j0, False)
    else:
        _trial_steps(L, j0, True)
    return touching


@njit(inline="always", **JIT)
def _state(L, j):
    """Lane ``j``'s x [m], v [m/s], V [V] and the sin, cos of its forcing phase."""
    return L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j], L[LANE.sin + j], L[LANE.cos + j]


@njit(inline="always", **JIT)
def _increment(L, row, x, v, V, s0, c0):
    """One row of the contact-free step's increment: the map's five entries in the lane
    table from ``row`` on (rows LANES apart: LANE.mxx ... LANE.mxc for x) times
    (x, v, V, sin, cos)."""
    return (L[row] * x + L[row + LANES] * v + L[row + 2 * LANES] * V + L[row + 3 * LANES] * s0
            + L[row + 4 * LANES] * c0)


@njit(inline="always", **JIT)
def _half_phases(s0, c0, ca, sa):
    """sin of the forcing phase half a step and a step on from sin, cos = s0, c0, by
    rotating it by the half step's cos, sin = ca, sa, for scalar code: the lane loop's
    trial step writes the same rotation out, its code left as it was."""
    sm = s0 * ca + c0 * sa
    return sm, sm * ca + (c0 * ca - s0 * sa) * sa


@njit(inline="always", **JIT)
def _trial_steps(L, j0, contact):
    """The trial step of group j0's lanes: the contact-free map (see the rows LANE.mxx...),
    and with ``contact`` the RK4 stages with the contact force for the lanes in contact,
    chosen lane by lane (a lane out of contact gets the same bits either way)."""
    for j in range(j0, j0 + GROUP):
        x, v, V, s0, c0 = _state(L, j)
        xn = x + _increment(L, LANE.mxx + j, x, v, V, s0, c0)
        vn = v + _increment(L, LANE.mvx + j, x, v, V, s0, c0)
        Vn = V + _increment(L, LANE.mex + j, x, v, V, s0, c0)
        L[LANE.x_trial + j], L[LANE.v_trial + j], L[LANE.voltage_trial + j] = xn, vn, Vn
    if contact:
        for j in range(j0, j0 + GROUP):
            x, v, V, s0, c0 = _state(L, j)
            A, ca, sa = L[LANE.amplitude + j], L[LANE.cos_half + j], L[LANE.sin_half + j]
            sm = s0 * ca + c0 * sa
            s1 = sm * ca + (c0 * ca - s0 * sa) * sa
            on = L[LANE.on + j]
            coef = Coefficients(
                L[LANE.wn2 + j],
                L[LANE.cm + j],
                L[LANE.thm + j],
                on * L[LANE.khm + j],
                L[LANE.gap + j],
                L[LANE.ch + j],
                L[LANE.irc + j],
                L[LANE.thc + j],
            )
            xc, vc, Vc, _, _ = rk4(x, v, V, L[LANE.h + j], A * s0, A * sm, A * s1, coef)
            L[LANE.x_contact + j], L[LANE.v_contact + j], L[LANE.voltage_contact + j] = xc, vc, Vc
        # (chosen in a loop of its own: with the choice in the loop above, LLVM left that
        # loop scalar)
        for j in range(j0, j0 + GROUP):
            free = L[LANE.on + j] == 0.0
            L[LANE.x_trial + j] = L[LANE.x_trial + j] if free else L[LANE.x_contact + j]
            L[LANE.v_trial + j] = L[LANE.v_trial + j] if free else L[LANE.v_contact + j]
            L[LANE.voltage_trial + j] = (
                L[LANE.voltage_trial + j] if free else L[LANE.voltage_contact + j]
            )


@njit(inline="always", **JIT)
def _commit_steps(L, contact, it, lanes):
    """Commit the trial step of every lane of the first ``lanes`` (GROUP or LANES) that
    needs nothing more (see lane_steps), in iteration ``it``.

    With ``contact=False`` no lane is in contact: every lane locates its switches (plain
    fixed steps keep the contact on), the force is 0 and stays so, and neither the force
    peak nor the approach to a separation needs looking at. The step's int V^2 dt comes
    from its ends (hermite.v2_integral). Returns the number of lanes with a point (not
    idle) marked LANE.need, and how many of them take quarter steps (_quarter).
    """
    marked, quarters = 0, 0
    for j in range(lanes):
        x, v, V, ch = L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j], L[LANE.ch + j]
        xn, vn, Vn = L[LANE.x_trial + j], L[LANE.v_trial + j], L[LANE.voltage_trial + j]
        g, cb, sb = L[LANE.gap + j], L[LANE.cos_step + j], L[LANE.sin_step + j]
        s0, c0 = L[LANE.sin + j], L[LANE.cos + j]
        irc, thc = L[LANE.irc + j], L[LANE.thc + j]
        dV, dVn = voltage_rate(V, v, irc, thc), voltage_rate(Vn, vn, irc, thc)
        dq = hermite.v2_integral(V, dV, Vn, dVn, L[LANE.half_h + j], L[LANE.h2_6 + j])
        turn = L[LANE.turn_floor + j]
        need = ((v * vn <= turn) | (dV * dVn <= turn) | (it >= L[LANE.k_end + j])
                | (xn < L[LANE.flip_below + j]))
        if contact:
            on, h = L[LANE.on + j], L[LANE.h + j]
            fcn = contact_force(xn, vn, on * L[LANE.kh + j], g, ch)
            fc, fcp = L[LANE.fc + j], L[LANE.fc_previous + j]
            located = L[LANE.locate + j] != 0.0
            # plain fixed steps with a latched law predict the approach velocity: in scalar
            predict = (not located) & (L[LANE.latch + j] > 0.0) & (x <= g) & (v > 0.0)
            switch = located & (in_contact(xn, vn, g, ch) != (on == 1.0))
            touch = (not located) & (x <= g) & (xn > g)
            quarter = (
                located
                & (on == 1.0)
                & (  # as _quarter
                    (L[LANE.fine + j] > 0.0) | ((v < 0.0) & (x - g < -3.0 * h * v))
                )
            )
            need = (
                need | switch | touch | predict | quarter
                | ((fcp > -L[LANE.turn_floor + j]) & (fc >= fcp) & (fc > fcn))
            )
            quarters += 1 if quarter else 0
            L[LANE.fc_previous + j], L[LANE.fc + j] = fcp if need else fc, fc if need else fcn
        else:  # (the force rows stay as they are: 0, or the last force of a contact,
            # which the touch step, never a plain one, shifts out)
            need = need | in_contact(xn, vn, g, ch)
        # A lane marked LANE.need keeps its state, for finish_step to redo the step from it
        # (the trial stays in the trial rows); its trial values are kept out of the running
        # sum without branches. The running maximum of |v| takes the step's start, a
        # sample either way (the last of a period is taken by finish_step). The extrema
        # of x, V and F_c need no running value here: with the sign of v, of dV/dt and of
        # dF_c/dt kept, the samples are monotonic, so the largest lies at either end of a
        # run of plain steps, where finish_step takes it.
        off = 1.0 if need else 0.0
        L[LANE.need + j] = off
        L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j] = (
            x if need else xn,
            v if need else vn,
            V if need else Vn,
        )
        L[LANE.sin + j] = s0 if need else s0 * cb + c0 * sb
        L[LANE.cos + j] = c0 if need else c0 * cb - s0 * sb
        L[LANE.q + j] += (1.0 - off) * dq
        L[LANE.v_max + j] = max(L[LANE.v_max + j], abs(v))
        marked += 1 if need else 0
    return marked, quarters


@njit(inline="always", **JIT)
def _quarter(L, j):
    """Whether lane ``j``'s step is to be taken in quarter steps: its contact switches
    located, in contact, and just after a touch (LANE.fine) or about to separate (within 3
    steps at its velocity). These steps still see the (t - t_0)^1.5 growth of the force."""
    x, v, h = L[LANE.x + j], L[LANE.v + j], L[LANE.h + j]
    return (
        L[LANE.locate + j] != 0.0
        and L[LANE.on + j] == 1.0
        and (L[LANE.fine + j] > 0.0 or (v < 0.0 and x - L[LANE.gap + j] < -3.0 * h * v))
    )


# The rows a lane taking quarter steps copies into its packed slot: (packed, lane) rows.
_QUARTER_ROWS = (
    (LANE.q_x, LANE.x), (LANE.q_v, LANE.v), (LANE.q_voltage, LANE.voltage),
    (LANE.q_sin, LANE.sin), (LANE.q_cos, LANE.cos), (LANE.q_amplitude, LANE.amplitude),
    (LANE.q_cos_eighth, LANE.cos_eighth), (LANE.q_sin_eighth, LANE.sin_eighth),
    (LANE.q_wn2, LANE.wn2), (LANE.q_cm, LANE.cm), (LANE.q_thm, LANE.thm),
    (LANE.q_khm, LANE.khm), (LANE.q_gap, LANE.gap), (LANE.q_ch, LANE.ch),
    (LANE.q_irc, LANE.irc), (LANE.q_thc, LANE.thc),
)


@njit(**JIT)
def quarter_steps(L, lanes):
    """Redo the trial step of the marked lanes (LANE.need) that take quarter steps (_quarter)
    in four quarter steps with the contact force, for finish_step to finish.

    They are packed, BLOCK lanes at a time, into one block (the last padded with copies
    of its first), which runs in vector code: a point's quarter steps are the same
    instructions in any lane of a block, and cost a block, not a lane each, when several
    lanes take them together (the copies of a point in an ensemble, neighbouring gaps in a
    sweep). One block, at a constant offset, run as often as needed: LLVM vectorizes the
    loop of a block whose offset it knows, and one copy of the block's code is a quarter
    of the compile of four written out, which was a large share of the engine's
    (benchmarks/results/compile_time.md).
    """
    j = 0
    while j < lanes:
        n = 0
        while j < lanes and n < BLOCK:
            if L[LANE.need + j] != 0.0 and _quarter(L, j):
                L[LANE.q_lane + n] = j
                for packed, row in _QUARTER_ROWS:
                    L[packed + n] = L[row + j]
                L[LANE.q_dt + n] = 0.25 * L[LANE.h + j]
                n += 1
            j += 1
        if n == 0:
            return
        for k in range(n, BLOCK):
            for r in range(LANE.q_lane, LANE.q_thc + LANES, LANES):
                L[r + k] = L[r]
        _quarter_block(L)
        for k in range(n):
            i = int(L[LANE.q_lane + k])
            L[LANE.x_trial + i], L[LANE.v_trial + i], L[LANE.voltage_trial + i] = (
                L[LANE.q_x + k],
                L[LANE.q_v + k],
                L[LANE.q_voltage + k],
            )


@njit(inline="always", **JIT)
def _eighth_phases(s0, c0, ce, se):
    """sin of the forcing phase 1, 2, ..., 8 eighths of a step on from sin, cos = s0, c0,
    by rotating it by an eighth's cos, sin = ce, se: the quarter steps' forcing, in their
    vector block and where a lane's tangents are carried through them."""
    s1, c1 = s0 * ce + c0 * se, c0 * ce - s0 * se
    s2, c2 = s1 * ce + c1 * se, c1 * ce - s1 * se
    s3, c3 = s2 * ce + c2 * se, c2 * ce - s2 * se
    s4, c4 = s3 * ce + c3 * se, c3 * ce - s3 * se
    s5, c5 = s4 * ce + c4 * se, c4 * ce - s4 * se
    s6, c6 = s5 * ce + c5 * se, c5 * ce - s5 * se
    s7, c7 = s6 * ce + c6 * se, c6 * ce - s6 * se
    return s1, s2, s3, s4, s5, s6, s7, s7 * ce + c7 * se


@njit(**JIT)
def _quarter_tangents(L, j, x, v, V, s0, c0):
    """Carry lane ``j``'s tangents through the four quarter steps from (x, v, V) that
    quarter_steps took (the same arguments, in scalar code)."""
    A, dt = L[LANE.amplitude + j], 0.25 * L[LANE.h + j]
    s1, s2, s3, s4, s5, s6, s7, s8 = _eighth_phases(s0, c0, L[LANE.cos_eighth + j],
                                                    L[LANE.sin_eighth + j])
    coef = Coefficients(L[LANE.wn2 + j], L[LANE.cm + j], L[LANE.thm + j], L[LANE.khm + j],
                        L[LANE.gap + j], L[LANE.ch + j], L[LANE.irc + j], L[LANE.thc + j])
    tangents.through_step(L, j, x, v, V, dt, A * s0, A * s1, A * s2, coef)
    x, v, V, _, _ = rk4(x, v, V, dt, A * s0, A * s1, A * s2, coef)
    tangents.through_step(L, j, x, v, V, dt, A * s2, A * s3, A * s4, coef)
    x, v, V, _, _ = rk4(x, v, V, dt, A * s2, A * s3, A * s4, coef)
    tangents.through_step(L, j, x, v, V, dt, A * s4, A * s5, A * s6, coef)
    x, v, V, _, _ = rk4(x, v, V, dt, A * s4, A * s5, A * s6, coef)
    tangents.through_step(L, j, x, v, V, dt, A * s6, A * s7, A * s8, coef)


@njit(inline="always", **JIT)
def _quarter_block(L):
    """Four quarter steps of the packed lanes 0, ..., BLOCK - 1 (see quarter_steps),
    with the forcing every eighth of a step by rotating the phase; written out, as LLVM
    vectorizes only a loop without an inner loop."""
    for k in range(BLOCK):
        x, v, V, s0, c0 = (
            L[LANE.q_x + k],
            L[LANE.q_v + k],
            L[LANE.q_voltage + k],
            L[LANE.q_sin + k],
            L[LANE.q_cos + k],
        )
        A, ce, se, dt = (
            L[LANE.q_amplitude + k],
            L[LANE.q_cos_eighth + k],
            L[LANE.q_sin_eighth + k],
            L[LANE.q_dt + k],
        )
        wn2, cm, thm, khm = (
            L[LANE.q_wn2 + k],
            L[LANE.q_cm + k],
            L[LANE.q_thm + k],
            L[LANE.q_khm + k],
        )
        g, ch, irc, thc = L[LANE.q_gap + k], L[LANE.q_ch + k], L[LANE.q_irc + k], L[LANE.q_thc + k]
        s1, s2, s3, s4, s5, s6, s7, s8 = _eighth_phases(s0, c0, ce, se)
        coef = Coefficients(wn2, cm, thm, khm, g, ch, irc, thc)
        x, v, V, _, _ = rk4(x, v, V, dt, A * s0, A * s1, A * s2, coef)
        x, v, V, _, _ = rk4(x, v, V, dt, A * s2, A * s3, A * s4, coef)
        x, v, V, _, _ = rk4(x, v, V, dt, A * s4, A * s5, A * s6, coef)
        x, v, V, _, _ = rk4(x, v, V, dt, A * s6, A * s7, A * s8, coef)
        L[LANE.q_x + k], L[LANE.q_v + k], L[LANE.q_voltage + k] = x, v, V


@njit(**JIT)
def finish_step(L, j, it):
    """Redo and finish the step of lane ``j`` that the lane loop marked (see lane_steps)
    in iteration ``it``; whether it ends the lane's forcing period."""
    s0, c0 = L[LANE.sin + j], L[LANE.cos + j]  # the forcing phase at the start of the step
    if L[LANE.stop_ratio + j] > 0.0:
        stop_motion.step(L, j)
        return _next_phase(L, j, it, s0, c0)
    if L[LANE.mode + j] != 0.0:
        if _turns_only(L, j, it):
            cb, sb = L[LANE.cos_step + j], L[LANE.sin_step + j]  # (a multi-step's)
            L[LANE.sin + j], L[LANE.cos + j] = s0 * cb + c0 * sb, c0 * cb - s0 * sb
            if it < L[LANE.k_end + j]:
                return False
            # its last multi-step before the lane's stop: single steps from here
            _leave_multi(L, j, it + 1.0)
            k = it + 1.0 - L[LANE.k0 + j]
            if k == _next_stop(L, j, k) or k >= L[LANE.steps + j]:  # (at a resync or the end)
                return _next_phase(L, j, it, s0, c0)
            return False
        _take_apart(L, j, it)
    if L[LANE.multi + j] <= 1.0:
        _finish_rigid(L, j, it)
        return _next_phase(L, j, it, s0, c0)
    # (an extremum inside the step, or the lane mirrored: what a multi-step was taken
    # apart for, likely)
    v, dV, sign = L[LANE.v + j], _voltage_rate_of(L, j), L[LANE.sign + j]
    _finish_rigid(L, j, it)
    turned = (v * L[LANE.v + j] * sign * L[LANE.sign + j] <= 0.0
              or dV * _voltage_rate_of(L, j) * sign * L[LANE.sign + j] <= 0.0
              or sign != L[LANE.sign + j])
    ended = _next_phase(L, j, it, s0, c0)
    if not ended:
        if it >= L[LANE.hold + j] or turned:
            resume(L, j, it + 1.0)
        elif L[LANE.on + j] == 0.0:  # (come back once past what it was taken apart for)
            L[LANE.k_end + j] = min(L[LANE.k_end + j], L[LANE.hold + j])
    return ended


# A top of a swing inside a multi-step within this of the stop (relative to the larger of
# the two) takes the multi-step apart, so that single steps decide whether it touches: the
# cubic Hermite interpolant over a multi-step places the top to about 1e-9 of the amplitude
# at MULTI_SPAN multi-steps a period [-].
NEAR_TOP = 1e-6


@njit(**JIT)
def _turns_only(L, j, it):
    """Finish lane ``j``'s marked multi-step of iteration ``it`` whole, its forcing phase
    left to the caller, where it holds nothing but turns of x or V clear of the stop or
    the lane's stop (LANE.k_end) at its end: the turns' extrema are placed on the cubic
    Hermite interpolant over the multi-step (as a step's over the step) and the step is
    committed as the lane loop commits one; returns whether it was. A multi-step that ends
    in contact or past the mirror's threshold, or whose top of a swing comes within
    NEAR_TOP of the stop, is left to be taken apart."""
    x, v, V, _, _ = _state(L, j)
    xn, vn, Vn = L[LANE.x_trial + j], L[LANE.v_trial + j], L[LANE.voltage_trial + j]
    g, ch, khm = L[LANE.gap + j], L[LANE.ch + j], L[LANE.khm + j]
    if in_contact(xn, vn, g, ch) or xn < L[LANE.flip_below + j]:
        return False
    span = L[LANE.multi + j] * L[LANE.h + j]
    near = g if khm > 0.0 else np.inf
    if v > 0.0 >= vn and hermite.extremum(x, v, xn, vn, span) >= near - NEAR_TOP * max(
            abs(near), abs(x)):
        return False
    irc, thc = L[LANE.irc + j], L[LANE.thc + j]
    dV, dVn = voltage_rate(V, v, irc, thc), voltage_rate(Vn, vn, irc, thc)
    fc = L[LANE.fc + j]
    booking.extrema(L, j, x, v, V, dV, xn, vn, Vn, dVn, span, L[LANE.fc_previous + j], fc,
                    0.0, 0.0, 0.0, L[LANE.sign + j] > 0.0, near)
    L[LANE.q + j] += hermite.v2_integral(V, dV, Vn, dVn, L[LANE.half_h + j], L[LANE.h2_6 + j])
    L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j] = xn, vn, Vn
    L[LANE.fc_previous + j], L[LANE.fc + j] = fc, 0.0
    return True


@njit(inline="always", **JIT)
def _voltage_rate_of(L, j):
    """dV/dt [V/s] of lane ``j``'s state."""
    return voltage_rate(L[LANE.voltage + j], L[LANE.v + j], L[LANE.irc + j], L[LANE.thc + j])


# (a call, not inlined: finish_step calls it twice, and numba compiled the inlined body
# once for each, a large share of the lane engine's compile time; a step finished in
# scalar code does not notice the call)
@njit(**JIT)
def _finish_rigid(L, j, it):
    """finish_step with a rigid stop, in iteration ``it``: the step redone where it
    switches contact or needs quarter steps, its extrema and force peak placed, the lane
    mirrored past half way; a lane that carries tangents carries them through a step that
    is not contact-free (see tangents)."""
    x, v, V, s0, c0 = _state(L, j)
    on, ch = L[LANE.on + j], L[LANE.ch + j]
    xn, vn, Vn = L[LANE.x_trial + j], L[LANE.v_trial + j], L[LANE.voltage_trial + j]
    A, wn2, cm, thm, khm = (
        L[LANE.amplitude + j],
        L[LANE.wn2 + j],
        L[LANE.cm + j],
        L[LANE.thm + j],
        L[LANE.khm + j],
    )
    g, irc, thc, h, latch = (
        L[LANE.gap + j],
        L[LANE.irc + j],
        L[LANE.thc + j],
        L[LANE.h + j],
        L[LANE.latch + j],
    )
    n_steps = L[LANE.steps + j]
    fine = L[LANE.fine + j]
    carry = L[LANE.tangents + j] != 0.0
    dV = voltage_rate(V, v, irc, thc)  # at the start of the step [V/s]
    # int V^2 dt over the trial step as the lane loop takes it (see _commit_steps), unless
    # the step is redone below
    dq = hermite.v2_integral(
        V, dV, Vn, voltage_rate(Vn, vn, irc, thc), L[LANE.half_h + j], L[LANE.h2_6 + j]
    )
    if L[LANE.locate + j] == 0.0:
        if latch > 0.0 and x <= g and v > 0.0:  # predicted approach velocity: redo the step
            ch = latch / v
            ca, sa = L[LANE.cos_half + j], L[LANE.sin_half + j]
            sm = s0 * ca + c0 * sa
            s1 = sm * ca + (c0 * ca - s0 * sa) * sa
            xn, vn, Vn, dq, _ = rk4(
                x, v, V, h, A * s0, A * sm, A * s1, Coefficients(wn2, cm, thm, khm, g, ch, irc, thc)
            )
        if x <= g < xn:  # first touch, on the cubic Hermite interpolant
            ch = booking.impact(L, j, hermite.crossing_rate(x, v, xn, vn, h, g), ch)
    elif in_contact(xn, vn, g, ch) != (on == 1.0):
        before = Coefficients(wn2, cm, thm, on * khm, g, ch, irc, thc)  # the old contact state
        a0, _ = derivatives(x, v, V, A * s0, before)
        kind, theta, done, xe, ve, Ve, q1 = switch_step(
            x, v, V, a0, xn, vn, Vn, s0, c0, n_steps, h, A, before
        )
        # Up to the switch with the old contact state (graded towards a separation; else
        # one sub-step, Newton's last when it converged)...
        graded = on == 1.0 and kind == hertz.TOUCH
        if graded or not done:
            xe, ve, Ve, q1 = pieces(
                x,
                v,
                V,
                0.0,
                theta,
                GRADED_TO_SWITCH if graded else WHOLE,
                s0,
                c0,
                n_steps,
                h,
                A,
                before,
            )
        onset = on == 0.0 and kind == hertz.TOUCH
        if onset:
            ch = booking.impact(L, j, ve, ch)
        on = 1.0 - on
        # ... and after it with the new one (graded from a touch).
        after = Coefficients(wn2, cm, thm, on * khm, g, ch, irc, thc)
        xn, vn, Vn, q2 = pieces(
            xe,
            ve,
            Ve,
            theta,
            1.0 - theta,
            GRADED if onset else WHOLE,
            s0,
            c0,
            n_steps,
            h,
            A,
            after,
        )
        dq = q1 + q2
        fine = 3.0 if onset else 0.0
        if carry:
            tangents.catch_up(L, j, it)
            switch_tangents(L, j, x, v, V, xe, ve, Ve, kind, theta,
                            GRADED_TO_SWITCH if graded else WHOLE, GRADED if onset else WHOLE,
                            s0, c0, n_steps, h, A, before, after)
            L[LANE.t_since + j] = it + 1.0
    elif _quarter(L, j):  # the trial step was taken in quarter steps (quarter_steps)
        fine = max(fine - 1.0, 0.0)
        if carry:
            tangents.catch_up(L, j, it)
            _quarter_tangents(L, j, x, v, V, s0, c0)
            L[LANE.t_since + j] = it + 1.0
    elif carry and on == 1.0:  # a plain step in contact
        _contact_step_tangents(L, j, it, x, v, V, s0, c0)
    fc, fcp = L[LANE.fc + j], L[LANE.fc_previous + j]
    fcn = contact_force(xn, vn, on * L[LANE.kh + j], g, ch)
    dfc, dfcn = 0.0, 0.0
    if fcn > 0.0 and booking.at_peak(L, j, fcp, fc, fcn):
        dfc, dfcn = _peak_rates(L, j, x, v, V, xn, vn, Vn, s0, c0, on, ch)
    booking.extrema(L, j, x, v, V, dV, xn, vn, Vn, voltage_rate(Vn, vn, irc, thc), h, fcp, fc,
                    fcn, dfc, dfcn, L[LANE.sign + j] > 0.0, g if khm > 0.0 else np.inf)
    L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j] = xn, vn, Vn
    L[LANE.fc_previous + j], L[LANE.fc + j] = fc, fcn
    L[LANE.on + j], L[LANE.ch + j], L[LANE.fine + j] = on, ch, fine
    L[LANE.q + j] += dq
    if xn < L[LANE.flip_below + j]:  # nearer the other stop (out of this one's reach)
        mirror(L, j)


@njit(**JIT)
def _peak_rates(L, j, x, v, V, xn, vn, Vn, s0, c0, on, ch):
    """dF_c/dt [N/s] at the start and the end of lane ``j``'s step from (x, v, V) at forcing
    phase sin, cos = s0, c0 to (xn, vn, Vn), in contact state ``on`` with damping ``ch``
    [s/m]: what the quartic of a force peak takes (booking.peak)."""
    g, kh = L[LANE.gap + j], on * L[LANE.kh + j]
    k = Coefficients(L[LANE.wn2 + j], L[LANE.cm + j], L[LANE.thm + j], on * L[LANE.khm + j],
                     g, ch, L[LANE.irc + j], L[LANE.thc + j])
    A = L[LANE.amplitude + j]
    s1 = s0 * L[LANE.cos_step + j] + c0 * L[LANE.sin_step + j]
    a0, _ = derivatives(x, v, V, A * s0, k)
    a1, _ = derivatives(xn, vn, Vn, A * s1, k)
    return contact_force_rate(x, v, a0, kh, g, ch), contact_force_rate(xn, vn, a1, kh, g, ch)


@njit(**JIT)
def _contact_step_tangents(L, j, it, x, v, V, s0, c0):
    """Carry lane ``j``'s tangents through its plain step in contact of iteration ``it``
    from (x, v, V) at forcing phase sin, cos = s0, c0 (the lane loop's trial step)."""
    tangents.catch_up(L, j, it)
    sm, s1 = _half_phases(s0, c0, L[LANE.cos_half + j], L[LANE.sin_half + j])
    A = L[LANE.amplitude + j]
    tangents.through_step(L, j, x, v, V, L[LANE.h + j], A * s0, A * sm, A * s1, Coefficients(
        L[LANE.wn2 + j], L[LANE.cm + j], L[LANE.thm + j], L[LANE.khm + j], L[LANE.gap + j],
        L[LANE.ch + j], L[LANE.irc + j], L[LANE.thc + j]))
    L[LANE.t_since + j] = it + 1.0


@njit(**JIT)
def carriers(L, lanes, out):
    """Write into ``out`` the first ``lanes`` lanes that carry tangents and are in contact;
    returns how many: the lanes keep_starts and carry_tangents look at."""
    n = 0
    for j in range(lanes):
        if L[LANE.tangents + j] != 0.0 and L[LANE.on + j] == 1.0:
            out[n] = j
            n += 1
    return n


@njit(**JIT)
def keep_starts(L, lanes, n):
    """Keep the state at the start of this iteration's step of the lanes ``lanes[:n]``
    (carriers): the lane loop commits a plain step in contact as it does for any lane
    (the same bits), and carry_tangents carries the tangents through it from there. (Not
    in the lane loop itself: a row more written there changed how LLVM compiled it, and a
    lane's bits came to depend on its neighbours.)"""
    for k in range(n):
        j = lanes[k]
        L[LANE.t_x + j], L[LANE.t_v + j] = L[LANE.x + j], L[LANE.v + j]
        L[LANE.t_voltage + j] = L[LANE.voltage + j]
        L[LANE.t_sin + j], L[LANE.t_cos + j] = L[LANE.sin + j], L[LANE.cos + j]


@njit(**JIT)
def carry_tangents(L, lanes, n, it):
    """Carry the tangents of the lanes ``lanes[:n]`` whose starts keep_starts kept through
    their step of iteration ``it``, where the lane loop committed it (not marked for
    finish_step, which carries them through the steps it takes)."""
    for k in range(n):
        j = lanes[k]
        if L[LANE.need + j] == 0.0:
            _contact_step_tangents(L, j, it, L[LANE.t_x + j], L[LANE.t_v + j],
                                   L[LANE.t_voltage + j], L[LANE.t_sin + j], L[LANE.t_cos + j])


@njit(inline="always", **JIT)
def _next_phase(L, j, it, s0, c0):
    """Lane ``j``'s forcing phase after its step from phase sin, cos = s0, c0 in
    iteration ``it``, and the next iteration to stop at; whether the period ended."""
    k0, n_steps = L[LANE.k0 + j], L[LANE.steps + j]
    k = it + 1.0 - k0  # steps into the period after this one
    # The forcing phase of the next step: rotated as in the lane loop, and reset exactly
    # every SYNC steps (the rotation's rounding drifts); at k = n_steps the period ends
    # and _start_period sets it to the start's.
    sync = _next_stop(L, j, k)
    if k == sync and k < n_steps:
        phase = 2.0 * math.pi * k / n_steps + L[LANE.phase + j]
        L[LANE.sin + j], L[LANE.cos + j] = math.sin(phase), math.cos(phase)
    else:
        cb, sb = L[LANE.cos_step + j], L[LANE.sin_step + j]
        L[LANE.sin + j], L[LANE.cos + j] = s0 * cb + c0 * sb, c0 * cb - s0 * sb
    return k >= n_steps


@njit(inline="always", **JIT)
def _next_stop(L, j, k):
    """Set lane ``j``'s LANE.k_end, ``k`` steps into its period, to the iteration of its
    next step to stop at: a resync or the end (a lane in quarter steps is marked as such by
    _commit_steps); returns the last resync at or before k [steps]."""
    sync = SYNC * math.floor(k / SYNC)
    L[LANE.k_end + j] = L[LANE.k0 + j] + min(sync + SYNC, L[LANE.steps + j]) - 1.0
    return sync


@njit(**JIT)
def end_period(L, j, p, ring, acc, gaps, ring_len, n_strobe, settle, it):
    """Book the period that lane ``j`` just finished in iteration ``it``; the status once
    it is done, else -1."""
    s = L[LANE.sign + j]
    x, v, V, q = s * L[LANE.x + j], s * L[LANE.v + j], s * L[LANE.voltage + j], L[LANE.q + j]
    n = int(L[LANE.periods + j]) + 1
    L[LANE.periods + j] = n
    if not (math.isfinite(x + v + V + q) and abs(x) <= p[PARAM.x_limit]):
        return STATUS.diverged, 0
    slot = (n - 1) % MAX_ORBIT_PERIOD
    up = s > 0.0  # the upper stop's rows are those in use, else the other ones
    acc[slot, ACC.q] = q
    acc[slot, ACC.x_max] = L[LANE.x_max + j] if up else -L[LANE.x_min + j]
    acc[slot, ACC.x_min] = L[LANE.x_min + j] if up else -L[LANE.x_max + j]
    acc[slot, ACC.v_max], acc[slot, ACC.v_peak] = L[LANE.v_max + j], L[LANE.v_peak + j]
    impacts, sum_vimp, fc_max = L[LANE.impacts + j], L[LANE.sum_vimp + j], L[LANE.fc_max + j]
    impacts_o, sum_vimp_o, fc_max_o = (L[LANE.impacts_other + j], L[LANE.sum_vimp_other + j],
                                       L[LANE.fc_max_other + j])
    acc[slot, ACC.impacts] = impacts if up else impacts_o
    acc[slot, ACC.sum_vimp] = sum_vimp if up else sum_vimp_o
    acc[slot, ACC.fc_max] = fc_max if up else fc_max_o
    acc[slot, ACC.impacts_lower] = impacts_o if up else impacts
    acc[slot, ACC.fc_max_lower] = fc_max_o if up else fc_max
    acc[slot, ACC.stop_x_max] = L[LANE.stop_x_max + j]
    acc[slot, ACC.fc_peak_min] = L[LANE.fc_peak_min + j]
    acc[slot, ACC.fc_peak_max] = L[LANE.fc_peak_max + j]
    acc[slot, ACC.near_miss] = L[LANE.near_miss + j]
    acc[slot, ACC.vimp_min] = L[LANE.vimp_min + j]
    r = n % ring_len
    ring[r, STATE.x], ring[r, STATE.v], ring[r, STATE.voltage] = x, v, V
    ring[r, STATE.stop_x], ring[r, STATE.stop_v] = L[LANE.stop_x + j], L[LANE.stop_v + j]
    _start_period(L, j, it + 1.0)
    if settle:
        orbit = steady.orbit_period(
            ring,
            acc,
            gaps,
            n,
            ring_len,
            p[PARAM.tolerance],
            p[PARAM.v_per_x],
            p[PARAM.voltage_per_x],
        )
        if orbit > 0 and n >= n_strobe:
            return STATUS.settled, orbit
    if n >= int(p[PARAM.max_periods]):
        return STATUS.not_settled, 0
    resume(L, j, it + 1.0)
    return -1, 0


@njit(**JIT)
def output(L, j, p, y, metrics, strobe, ring, acc, ring_len, status, orbit):
    """Write the state, stroboscopic samples and metrics of lane ``j``'s finished point."""
    n = int(L[LANE.periods + j])
    s = L[LANE.sign + j]
    y[STATE.x], y[STATE.v] = s * L[LANE.x + j], s * L[LANE.v + j]
    y[STATE.voltage] = s * L[LANE.voltage + j]
    y[STATE.stop_x], y[STATE.stop_v] = L[LANE.stop_x + j], L[LANE.stop_v + j]
    y[STATE.approach_velocity] = L[LANE.vimp + j] if s > 0.0 else L[LANE.vimp_other + j]
    n_strobe = strobe.shape[0]
    for i in range(n_strobe):
        age = n_strobe - 1 - i
        valid = age <= n and status != STATUS.diverged
        for c in range(min(N_STROBE, strobe.shape[1])):
            strobe[i, c] = ring[(n - age) % ring_len, c] if valid else np.nan
    steady.reduce(
        acc, n, orbit if status == STATUS.settled else min(n, MAX_ORBIT_PERIOD), p, metrics
    )
    metrics[METRIC.orbit_period] = orbit
    metrics[METRIC.status] = status
    metrics[METRIC.periods_run] = n
    for c in BOOKED_METRICS:
        metrics[c] = metrics[c] if p[PARAM.book] != 0.0 else np.nan
    if status == STATUS.diverged:
        metrics[:N_VALUES] = np.nan


@njit(**JIT)
def refuse(metrics, strobe):
    """Write the outputs of a point refused before integration (too stiff): no values."""
    metrics[:N_VALUES] = np.nan
    metrics[METRIC.status] = STATUS.too_stiff
    metrics[METRIC.orbit_period] = 0.0
    metrics[METRIC.periods_run] = 0.0
    strobe[:, :] = np.nan


@njit(**JIT)
def move(L, j, i, ring, acc, gaps):
    """Move the point of lane ``j`` to lane ``i`` and leave lane ``j`` idle."""
    for r in range(0, len(LANE) * LANES, LANES):
        L[r + i] = L[r + j]
    ring[i], acc[i], gaps[i] = ring[j], acc[j], gaps[j]
    idle(L, j)


@njit(**JIT)
def idle(L, j):
    """Lane ``j`` without a point, which the lane loop never marks: it stays at x = 0,
    v = 1, V = 1 (its increments are 0), with dV/dt = 1 (1/(R C_p) = -1, theta/C_p =
    0), no forcing, the stop at infinity, no contact and no period end."""
    (
        L[LANE.amplitude + j],
        L[LANE.khm + j],
        L[LANE.steps + j],
        L[LANE.locate + j],
        L[LANE.on + j],
    ) = 0.0, 0.0, np.inf, 1.0, 0.0
    L[LANE.gap + j], L[LANE.irc + j], L[LANE.thc + j], L[LANE.k_end + j] = np.inf, -1.0, 0.0, np.inf
    L[LANE.fc + j], L[LANE.fc_previous + j] = 0.0, 0.0
    L[LANE.sign + j], L[LANE.flip_below + j] = 1.0, -np.inf
    L[LANE.stop_ratio + j], L[LANE.stop_on + j] = 0.0, 0.0
    L[LANE.stop_x + j], L[LANE.stop_v + j] = 0.0, 0.0
    L[LANE.tangents + j], L[LANE.need + j] = 0.0, 0.0  # (an idle second group is not committed)
    L[LANE.multi + j], L[LANE.mode + j] = 1.0, 0.0
    L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j] = 0.0, 1.0, 1.0
    for r in range(LANE.mxx, LANE.mec + LANES, LANES):
        L[r + j] = 0.0


@njit(**JIT)
def take(L, j, params, states, pt, ring, acc, gaps, it):
    load(L, j, params[pt], states[pt], it)
    resume(L, j, it)
    s = L[LANE.sign + j]
    ring[j, 0, STATE.x], ring[j, 0, STATE.v] = s * L[LANE.x + j], s * L[LANE.v + j]
    ring[j, 0, STATE.voltage] = s * L[LANE.voltage + j]
    ring[j, 0, STATE.stop_x], ring[j, 0, STATE.stop_v] = L[LANE.stop_x + j], L[LANE.stop_v + j]
    acc[j, :, :] = 0.0
    gaps[j, :, :] = np.inf
