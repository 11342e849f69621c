"""Many points stepped together: the lane-blocked driver of the RK4 kernel.

Each thread takes points from one shared queue and steps LANES of them at once. The
plain RK4 step of every lane runs in branch-free loops over groups of GROUP lanes, which
LLVM compiles to vector code: out of contact the step is linear, and is applied as the matrix it is
(kernel.free_step_map); a group with a lane in contact also runs the RK4 stages with the
contact force. The rare steps that need more (a contact switch to locate, graded sub-steps next
to a touch or a separation, an extremum or a force peak to place, the end of a forcing
period) are finished lane by lane with the scalar functions of
:mod:`harvester_sweep.kernel`; the steps just after a touch and before a separation,
in quarter steps, run first, in vector code on the lanes that take them, packed
(_quarter_steps). A lane whose point is done takes the next point of its line (the next
frequency of a continuation, from the state the point left) or else the first point of
the next line of the queue, so that slow points do not hold a group back, no lane waits
for other lines and the threads end together; once the queue is empty the points left
are moved to the first lanes and an empty group is skipped.

A point's result does not depend on its lane, its thread or the thread count: every lane
runs the same vector instructions (tests/test_reproducibility.py checks a point in
different lanes and groups), which steps run scalar code is decided by the point's own
state, and nothing is reassociated (see kernel.FASTMATH)."""

from __future__ import annotations

import math
import threading
from pathlib import Path

import numba
import numpy as np
from numba import njit, prange, types
from numba.core import cgutils
from numba.extending import intrinsic

from .kernel import (
    _A_FCMAX,
    _A_NIMP,
    _A_Q,
    _A_SVIMP,
    _A_VMAX,
    _A_VPK,
    _A_XMAX,
    _A_XMIN,
    _GAP_HISTORY,
    _GRADED,
    _NA,
    _WHOLE,
    DIVERGED,
    FASTMATH,
    M_ORBIT,
    M_PERIODS,
    M_STATUS,
    MAX_ORBIT_PERIOD,
    NM,
    NOT_SETTLED,
    NP,
    P_A,
    P_CH,
    P_CM,
    P_EPERX,
    P_G,
    P_IRC,
    P_KHM,
    P_LATCH,
    P_LOCATE,
    P_M,
    P_MAXP,
    P_N,
    P_T,
    P_THC,
    P_THM,
    P_TOL,
    P_VPERX,
    P_WN2,
    P_XLIM,
    SETTLED,
    _derivatives,
    _hermite_crossing_rate,
    _hermite_extremum,
    _orbit_period,
    _reduce,
    _rk4,
    _rk4_pieces,
    _switch_step,
    _v2_integral,
    free_step_map,
)

# The kernel's flags (see kernel.FASTMATH): nsz and arcp let LLVM vectorize the lane loop,
# which has no division, so that arcp cannot make a vector lane differ from scalar code.
_JIT = dict(cache=True, fastmath=FASTMATH, error_model="numpy")

LANES = 16  # points stepped together by one thread
GROUP = 8  # lanes that take the contact-free code together; _lane_steps writes out 2 groups
assert LANES == 2 * GROUP

# The lane table is one flat array of rows of LANES values; a row's constant offset lets
# LLVM see that the lane loop's loads and stores never overlap, so that it vectorizes.
# Rows: the state of each lane's point...
(_X, _V, _E, _VIMP, _CH, _ON, _FINE, _Q, _XMAX, _XMIN, _VMAX, _VPK, _FCP, _FC, _FCMAX, _NIMP,
 _SVIMP, _K0, _KEND, _N, _S, _C,
 # ... the trial step of the lane loop and whether a lane needs scalar work ...
 _XN, _VN, _EN, _NEED, _XC, _VC, _EC,
 # ... the parameters the lane loop reads ...
 _PA, _PWN2, _PCM, _PTHM, _PKHM, _PKH, _PG, _PCHL, _PIRC, _PTHC, _PH, _PHH, _PH26, _PCA, _PSA,
 _PCB, _PSB, _PCE, _PSE, _PNS, _PLOC,
 # ... and the contact-free step as the linear map it is (kernel.free_step_map): the
 # increments of x, v, V from (x, v, V, sin, cos) at its start.
 _MXX, _MXV, _MXE, _MXS, _MXC, _MVX, _MVV, _MVE, _MVS, _MVC, _MEX, _MEV, _MEE, _MES, _MEC,
 # ... and the lanes that take quarter steps, packed (_quarter_steps): their lane, state,
 # forcing phase and parameters.
 _QJ, _QX, _QV, _QE, _QS, _QC, _QA, _QCE, _QSE, _QDT, _QWN2, _QCM, _QTHM, _QKHM, _QG, _QCH,
 _QIRC, _QTHC,
 ) = range(0, 83 * LANES, LANES)
_ROWS = 83
_BLOCK = 4  # lanes of one vector: quarter steps run on whole blocks of packed lanes
# Steps between exact resets of the forcing rotation, whose rounding drifts: at every
# multiple of _SYNC steps, and at each period's start. Over 2048 steps (sin, cos) drift by
# at most 9e-14 (at 368-65536 steps a period), far below RK4's error where a period has few
# steps and about the rounding floor where it has many; each reset is a step finished in
# scalar code (2048 rather than 512: 64 x 64 sweep +1.5 %, ensemble at 1e-7 +2 %).
_SYNC = 2048.0


@njit(**_JIT)
def _table():
    """A lane table of zeros, aligned to 64 bytes: no vector load of a row straddles two
    cache lines (a misaligned table ran the lane loop about 20 % slower)."""
    block = np.zeros(_ROWS * LANES + 8)
    skip = (8 - block.ctypes.data % 64 // 8) % 8
    return block[skip:skip + _ROWS * LANES]


@njit(**_JIT)
def _load(L, j, p, y, it):
    """Put the point of parameter row ``p`` and state ``y`` into lane ``j``, at t = 0, to
    take its first step in iteration ``it`` of the lane loop."""
    n_steps = p[P_N]
    h = p[P_T] / n_steps
    L[_PA + j], L[_PWN2 + j], L[_PCM + j], L[_PTHM + j] = p[P_A], p[P_WN2], p[P_CM], p[P_THM]
    L[_PKHM + j], L[_PKH + j], L[_PG + j] = p[P_KHM], p[P_KHM] * p[P_M], p[P_G]
    L[_PCHL + j] = p[P_LATCH]
    L[_PIRC + j], L[_PTHC + j] = p[P_IRC], p[P_THC]
    L[_PH + j], L[_PHH + j], L[_PH26 + j] = h, 0.5 * h, h * h / 6.0
    ca, sa = math.cos(math.pi / n_steps), math.sin(math.pi / n_steps)
    L[_PCA + j], L[_PSA + j] = ca, sa
    L[_PCB + j], L[_PSB + j] = math.cos(2 * math.pi / n_steps), math.sin(2 * math.pi / n_steps)
    L[_PCE + j], L[_PSE + j] = math.cos(math.pi / (4 * n_steps)), math.sin(math.pi / (4 * n_steps))
    m = free_step_map(h, ca, sa, p[P_A], p[P_WN2], p[P_CM], p[P_THM], p[P_IRC], p[P_THC])
    for r, row in enumerate((_MXX, _MVX, _MEX)):
        for c in range(5):
            L[row + c * LANES + j] = m[r, c]
    L[_PNS + j], L[_PLOC + j] = n_steps, p[P_LOCATE]
    x, v, e, vimp = y[0], y[1], y[2], y[3]
    latch = p[P_LATCH]
    ch = latch / vimp if latch > 0.0 else p[P_CH]
    g = p[P_G]
    L[_X + j], L[_V + j], L[_E + j], L[_VIMP + j], L[_CH + j] = x, v, e, vimp, ch
    L[_ON + j] = 1.0 if p[P_LOCATE] == 0.0 or (x > g and 1.0 + ch * v > 0.0) else 0.0
    L[_FINE + j] = 0.0
    L[_N + j] = 0.0
    _start_period(L, j, it)


@njit(**_JIT)
def _start_period(L, j, it):
    """Reset the per-period accumulators of lane ``j`` and the forcing phase to 0, for a
    period whose first step is taken in iteration ``it`` of the lane loop.

    Every lane takes one step an iteration, so a lane's steps into its period are the
    iterations since _K0; _KEND is the iteration at whose end the lane stops (a resync
    of the forcing phase or the period's end): a row to compare with, not a count to
    update, in the lane loop."""
    x, v, e = L[_X + j], L[_V + j], L[_E + j]
    d = max(x - L[_PG + j], 0.0)
    fc = L[_ON + j] * L[_PKH + j] * d * math.sqrt(d) * max(1.0 + L[_CH + j] * v, 0.0)
    L[_Q + j] = 0.0
    L[_XMAX + j], L[_XMIN + j], L[_VMAX + j], L[_VPK + j] = x, x, abs(v), abs(e)
    L[_FCP + j], L[_FC + j], L[_FCMAX + j] = fc, fc, fc
    L[_NIMP + j], L[_SVIMP + j] = 0.0, 0.0
    L[_S + j], L[_C + j] = 0.0, 1.0
    L[_K0 + j] = it
    L[_KEND + j] = it + min(_SYNC, L[_PNS + j]) - 1.0


@njit(**_JIT)
def _lane_steps(L, groups, it):
    """One plain RK4 step of the lanes of the first ``groups`` groups, branch-free so that
    LLVM vectorizes it.

    The trial steps run group by group into trial rows: a group is GROUP lanes (two AVX2
    vectors), written out with constant bounds so that it compiles to vector code only.
    A lane out of contact steps by the RK4 step's linear map (kernel.free_step_map, 15
    multiply-adds and 3 adds); a group with a lane in contact also runs the RK4 stages with the
    contact force, and each lane takes the one that applies to it, so that a point gets
    the same bits whatever its neighbours. Two groups rather than one block of LANES,
    because a block is more often in contact; not four groups of one vector, whose
    contact-free loop LLVM compiled to scalar code once the trial step got short. A
    second loop commits: lanes whose
    step needs more (a contact switch, graded sub-steps near a touch or a separation, an
    extremum to place, a force peak, the end of a period) are marked in _NEED and left
    for :func:`_finish_step`. Returns the number of lanes with a point marked, and how
    many of them take quarter steps (see _quarter_steps).
    """
    touching = _trial_group(L, 0)
    if groups > 1:  # (else the second group is idle: no lane in contact)
        touching += _trial_group(L, GROUP)
    if touching == 0.0:
        return _commit_steps(L, False, it)
    return _commit_steps(L, True, it)


@njit(inline="always", **_JIT)
def _trial_group(L, j0):
    """The RK4 stages of group j0 (see _lane_steps); returns how many of its lanes touch."""
    touching = 0.0
    for j in range(j0, j0 + GROUP):
        touching += L[_ON + j]
    if touching == 0.0:
        _trial_steps(L, j0, False)
    else:
        _trial_steps(L, j0, True)
    return touching


@njit(inline="always", **_JIT)
def _trial_steps(L, j0, contact):
    """The trial step of group j0's lanes: the contact-free map (see the rows _MXX...),
    and with ``contact`` the RK4 stages with the contact force for the lanes in contact,
    chosen lane by lane (a lane out of contact gets the same bits either way)."""
    for j in range(j0, j0 + GROUP):
        x, v, e, s0, c0 = L[_X + j], L[_V + j], L[_E + j], L[_S + j], L[_C + j]
        xn = x + (L[_MXX + j] * x + L[_MXV + j] * v + L[_MXE + j] * e + L[_MXS + j] * s0
                  + L[_MXC + j] * c0)
        vn = v + (L[_MVX + j] * x + L[_MVV + j] * v + L[_MVE + j] * e + L[_MVS + j] * s0
                  + L[_MVC + j] * c0)
        en = e + (L[_MEX + j] * x + L[_MEV + j] * v + L[_MEE + j] * e + L[_MES + j] * s0
                  + L[_MEC + j] * c0)
        L[_XN + j], L[_VN + j], L[_EN + j] = xn, vn, en
    if contact:
        for j in range(j0, j0 + GROUP):
            x, v, e, s0, c0 = L[_X + j], L[_V + j], L[_E + j], L[_S + j], L[_C + j]
            A, ca, sa = L[_PA + j], L[_PCA + j], L[_PSA + j]
            sm = s0 * ca + c0 * sa
            s1 = sm * ca + (c0 * ca - s0 * sa) * sa
            on = L[_ON + j]
            xc, vc, ec, _, _ = _rk4(x, v, e, L[_PH + j], A * s0, A * sm, A * s1, L[_PWN2 + j],
                                    L[_PCM + j], L[_PTHM + j], on * L[_PKHM + j], L[_PG + j],
                                    L[_CH + j], L[_PIRC + j], L[_PTHC + j])
            L[_XC + j], L[_VC + j], L[_EC + j] = xc, vc, ec
        # (chosen in a loop of its own: with the choice in the loop above, LLVM left that
        # loop scalar)
        for j in range(j0, j0 + GROUP):
            free = L[_ON + j] == 0.0
            L[_XN + j] = L[_XN + j] if free else L[_XC + j]
            L[_VN + j] = L[_VN + j] if free else L[_VC + j]
            L[_EN + j] = L[_EN + j] if free else L[_EC + j]


@njit(inline="always", **_JIT)
def _commit_steps(L, contact, it):
    """Commit the trial step of every lane that needs nothing more (see _lane_steps), in
    iteration ``it``.

    With ``contact=False`` no lane is in contact: every lane locates its switches (plain
    fixed steps keep the contact on), the force is 0 and stays so, and neither the force
    peak nor the approach to a separation needs looking at. The step's int V^2 dt comes
    from its ends (kernel._v2_integral). Returns the number of lanes with a point (not
    idle) marked _NEED, and how many of them take quarter steps (_quarter).
    """
    marked, quarters = 0, 0
    for j in range(LANES):
        x, v, e, ch = L[_X + j], L[_V + j], L[_E + j], L[_CH + j]
        xn, vn, en = L[_XN + j], L[_VN + j], L[_EN + j]
        g, cb, sb = L[_PG + j], L[_PCB + j], L[_PSB + j]
        s0, c0 = L[_S + j], L[_C + j]
        irc, thc = L[_PIRC + j], L[_PTHC + j]
        dv, dvn = -irc * e - thc * v, -irc * en - thc * vn
        dq = _v2_integral(e, dv, en, dvn, L[_PHH + j], L[_PH26 + j])
        need = (v * vn <= 0.0) | (dv * dvn <= 0.0) | (it >= L[_KEND + j])
        if contact:
            on, h = L[_ON + j], L[_PH + j]
            d = max(xn - g, 0.0)
            fcn = on * L[_PKH + j] * d * math.sqrt(d) * max(1.0 + ch * vn, 0.0)
            fc, fcp = L[_FC + j], L[_FCP + j]
            located = L[_PLOC + j] != 0.0
            # plain fixed steps with a latched law predict the approach velocity: in scalar
            predict = (not located) & (L[_PCHL + j] > 0.0) & (x <= g) & (v > 0.0)
            switch = located & (((xn > g) & (1.0 + ch * vn > 0.0)) != (on == 1.0))
            touch = (not located) & (x <= g) & (xn > g)
            quarter = located & (on == 1.0) & (  # as _quarter
                (L[_FINE + j] > 0.0) | ((v < 0.0) & (x - g < -3.0 * h * v)))
            need = need | switch | touch | predict | quarter | (
                (fcp > 0.0) & (fc >= fcp) & (fc > fcn))
            quarters += 1 if quarter else 0
            L[_FCP + j], L[_FC + j] = fcp if need else fc, fc if need else fcn
        else:  # (the force rows stay as they are: 0, or the last force of a contact,
            # which the touch step, never a plain one, shifts out)
            need = need | ((xn > g) & (1.0 + ch * vn > 0.0))
        # A lane marked _NEED keeps its state, for _finish_step to redo the step from it
        # (the trial stays in the trial rows); its trial values are kept out of the running
        # sum without branches. The running maximum of |v| takes the step's start, a
        # sample either way (the last of a period is taken by _finish_step). The extrema
        # of x, V and F_c need no running value here: with the sign of v, of dV/dt and of
        # dF_c/dt kept, the samples are monotonic, so the largest lies at either end of a
        # run of plain steps, where _finish_step takes it.
        off = 1.0 if need else 0.0
        L[_NEED + j] = off
        L[_X + j], L[_V + j], L[_E + j] = x if need else xn, v if need else vn, e if need else en
        L[_S + j] = s0 if need else s0 * cb + c0 * sb
        L[_C + j] = c0 if need else c0 * cb - s0 * sb
        L[_Q + j] += (1.0 - off) * dq
        L[_VMAX + j] = max(L[_VMAX + j], abs(v))
        marked += 1 if need else 0
    return marked, quarters


@njit(inline="always", **_JIT)
def _quarter(L, j):
    """Whether lane ``j``'s step is to be taken in quarter steps: its contact switches
    located, in contact, and just after a touch (_FINE) or about to separate (within 3
    steps at its velocity). These steps still see the (t - t_0)^1.5 growth of the force."""
    x, v, h = L[_X + j], L[_V + j], L[_PH + j]
    return L[_PLOC + j] != 0.0 and L[_ON + j] == 1.0 and (
        L[_FINE + j] > 0.0 or (v < 0.0 and x - L[_PG + j] < -3.0 * h * v))


@njit(**_JIT)
def _quarter_steps(L, lanes):
    """Redo the trial step of the marked lanes (_NEED) that take quarter steps (_quarter)
    in four quarter steps with the contact force, for _finish_step to finish.

    They are packed into whole blocks of _BLOCK lanes (the last padded with copies of the
    first), which run in vector code: a point's quarter steps are the same instructions in
    any lane of a block, and cost a block, not a lane each, when several lanes take them
    together (the copies of a point in an ensemble, neighbouring gaps in a sweep).
    """
    n = 0
    for j in range(lanes):
        if L[_NEED + j] == 0.0 or not _quarter(L, j):
            continue
        L[_QJ + n] = j
        L[_QX + n], L[_QV + n], L[_QE + n] = L[_X + j], L[_V + j], L[_E + j]
        L[_QS + n], L[_QC + n], L[_QA + n] = L[_S + j], L[_C + j], L[_PA + j]
        L[_QCE + n], L[_QSE + n], L[_QDT + n] = L[_PCE + j], L[_PSE + j], 0.25 * L[_PH + j]
        L[_QWN2 + n], L[_QCM + n], L[_QTHM + n] = L[_PWN2 + j], L[_PCM + j], L[_PTHM + j]
        L[_QKHM + n], L[_QG + n], L[_QCH + n] = L[_PKHM + j], L[_PG + j], L[_CH + j]
        L[_QIRC + n], L[_QTHC + n] = L[_PIRC + j], L[_PTHC + j]
        n += 1
    if n == 0:
        return
    blocks = (n + _BLOCK - 1) // _BLOCK
    for k in range(n, blocks * _BLOCK):
        for r in range(_QJ, _QTHC + LANES, LANES):
            L[r + k] = L[r]
    # (each block's offset written out: LLVM vectorizes the loop of a block whose offset
    # it knows)
    _quarter_block(L, 0)
    if blocks > 1:
        _quarter_block(L, _BLOCK)
    if blocks > 2:
        _quarter_block(L, 2 * _BLOCK)
    if blocks > 3:
        _quarter_block(L, 3 * _BLOCK)
    for k in range(n):
        j = int(L[_QJ + k])
        L[_XN + j], L[_VN + j], L[_EN + j] = L[_QX + k], L[_QV + k], L[_QE + k]


@njit(inline="always", **_JIT)
def _quarter_block(L, b):
    """Four quarter steps of the packed lanes b, ..., b + _BLOCK - 1 (see _quarter_steps),
    with the forcing every eighth of a step by rotating the phase; written out, as LLVM
    vectorizes only a loop without an inner loop."""
    for k in range(b, b + _BLOCK):
        x, v, e, s0, c0 = L[_QX + k], L[_QV + k], L[_QE + k], L[_QS + k], L[_QC + k]
        A, ce, se, dt = L[_QA + k], L[_QCE + k], L[_QSE + k], L[_QDT + k]
        wn2, cm, thm, khm = L[_QWN2 + k], L[_QCM + k], L[_QTHM + k], L[_QKHM + k]
        g, ch, irc, thc = L[_QG + k], L[_QCH + k], L[_QIRC + k], L[_QTHC + k]
        s1, c1 = s0 * ce + c0 * se, c0 * ce - s0 * se
        s2, c2 = s1 * ce + c1 * se, c1 * ce - s1 * se
        s3, c3 = s2 * ce + c2 * se, c2 * ce - s2 * se
        s4, c4 = s3 * ce + c3 * se, c3 * ce - s3 * se
        s5, c5 = s4 * ce + c4 * se, c4 * ce - s4 * se
        s6, c6 = s5 * ce + c5 * se, c5 * ce - s5 * se
        s7, c7 = s6 * ce + c6 * se, c6 * ce - s6 * se
        s8 = s7 * ce + c7 * se
        x, v, e, _, _ = _rk4(x, v, e, dt, A * s0, A * s1, A * s2, wn2, cm, thm, khm, g, ch, irc,
                             thc)
        x, v, e, _, _ = _rk4(x, v, e, dt, A * s2, A * s3, A * s4, wn2, cm, thm, khm, g, ch, irc,
                             thc)
        x, v, e, _, _ = _rk4(x, v, e, dt, A * s4, A * s5, A * s6, wn2, cm, thm, khm, g, ch, irc,
                             thc)
        x, v, e, _, _ = _rk4(x, v, e, dt, A * s6, A * s7, A * s8, wn2, cm, thm, khm, g, ch, irc,
                             thc)
        L[_QX + k], L[_QV + k], L[_QE + k] = x, v, e


@njit(**_JIT)
def _finish_step(L, j, it):
    """Redo and finish the step of lane ``j`` that the lane loop marked (see _lane_steps)
    in iteration ``it``; whether it ends the lane's forcing period."""
    x, v, e, on, ch = L[_X + j], L[_V + j], L[_E + j], L[_ON + j], L[_CH + j]
    xn, vn, en = L[_XN + j], L[_VN + j], L[_EN + j]
    A, wn2, cm, thm, khm = L[_PA + j], L[_PWN2 + j], L[_PCM + j], L[_PTHM + j], L[_PKHM + j]
    g, irc, thc, h, latch = L[_PG + j], L[_PIRC + j], L[_PTHC + j], L[_PH + j], L[_PCHL + j]
    n_steps = L[_PNS + j]
    s0, c0 = L[_S + j], L[_C + j]  # the forcing phase at the start of the step
    fine = L[_FINE + j]
    dv = -irc * e - thc * v  # dV/dt at the start of the step [V/s]
    # int V^2 dt over the trial step as the lane loop takes it (see _commit_steps), unless
    # the step is redone below
    dq = _v2_integral(e, dv, en, -irc * en - thc * vn, L[_PHH + j], L[_PH26 + j])
    if L[_PLOC + j] == 0.0:
        if latch > 0.0 and x <= g and v > 0.0:  # predicted approach velocity: redo the step
            ch = latch / v
            ca, sa = L[_PCA + j], L[_PSA + j]
            sm = s0 * ca + c0 * sa
            s1 = sm * ca + (c0 * ca - s0 * sa) * sa
            xn, vn, en, dq, _ = _rk4(x, v, e, h, A * s0, A * sm, A * s1, wn2, cm, thm, khm,
                                     g, ch, irc, thc)
        if x <= g < xn:  # first touch, on the cubic Hermite interpolant
            v_on = _hermite_crossing_rate(x, v, xn, vn, h, g)
            L[_NIMP + j] += 1.0
            L[_SVIMP + j] += v_on
            if latch > 0.0 and v_on > 0.0:
                L[_VIMP + j] = v_on
                ch = latch / v_on
    elif (xn > g and 1.0 + ch * vn > 0.0) != (on == 1.0):
        a0, _ = _derivatives(x, v, e, A * s0, wn2, cm, thm, on * khm, g, ch, irc, thc)
        kind, theta, done, xe, ve, ee, q1 = _switch_step(
            x, v, e, a0, xn, vn, en, on, s0, c0, n_steps, h, A, wn2, cm, thm, khm, g, ch, irc,
            thc)
        # Up to the switch with the old contact state (graded towards a separation; else
        # one sub-step, Newton's last when it converged)...
        graded = on == 1.0 and kind == 1
        if graded or not done:
            xe, ve, ee, q1 = _rk4_pieces(x, v, e, 0.0, theta, _GRADED if graded else _WHOLE,
                                         True, s0, c0, n_steps, h, A, wn2, cm, thm, on * khm,
                                         g, ch, irc, thc)
        onset = on == 0.0 and kind == 1
        if onset:
            L[_NIMP + j] += 1.0
            L[_SVIMP + j] += ve
            if latch > 0.0 and ve > 0.0:
                L[_VIMP + j] = ve
                ch = latch / ve
        on = 1.0 - on
        # ... and after it with the new one (graded from a touch).
        xn, vn, en, q2 = _rk4_pieces(xe, ve, ee, theta, 1.0 - theta, _GRADED if onset else _WHOLE,
                                     False, s0, c0, n_steps, h, A, wn2, cm, thm, on * khm, g,
                                     ch, irc, thc)
        dq = q1 + q2
        fine = 3.0 if onset else 0.0
    elif _quarter(L, j):  # the trial step was taken in quarter steps (_quarter_steps)
        fine = max(fine - 1.0, 0.0)
    dvn = -irc * en - thc * vn
    if v > 0.0 >= vn or v < 0.0 <= vn:
        xe = _hermite_extremum(x, v, xn, vn, h)
        L[_XMAX + j], L[_XMIN + j] = max(L[_XMAX + j], xe), min(L[_XMIN + j], xe)
    if (dv > 0.0) != (dvn > 0.0):
        L[_VPK + j] = max(L[_VPK + j], abs(_hermite_extremum(e, dv, en, dvn, h)))
    d = max(xn - g, 0.0)
    fc, fcp = L[_FC + j], L[_FCP + j]
    fcn = on * L[_PKH + j] * d * math.sqrt(d) * max(1.0 + ch * vn, 0.0)
    if fcp > 0.0 and fc >= fcp and fc > fcn:  # parabola through the peak
        a = 0.5 * (fcp + fcn) - fc
        b = 0.5 * (fcn - fcp)
        L[_FCMAX + j] = max(L[_FCMAX + j], fc - b * b / (4.0 * a))
    L[_X + j], L[_V + j], L[_E + j] = xn, vn, en
    L[_FCP + j], L[_FC + j] = fc, fcn
    L[_ON + j], L[_CH + j], L[_FINE + j] = on, ch, fine
    L[_Q + j] += dq
    # both ends of the step: the ends of the runs of plain steps (see _commit_steps)
    L[_XMAX + j], L[_XMIN + j] = max(L[_XMAX + j], x, xn), min(L[_XMIN + j], x, xn)
    L[_VMAX + j], L[_VPK + j] = max(L[_VMAX + j], abs(vn)), max(L[_VPK + j], abs(e), abs(en))
    L[_FCMAX + j] = max(L[_FCMAX + j], fc, fcn)
    k0 = L[_K0 + j]
    k = it + 1.0 - k0  # steps into the period after this one
    # The forcing phase of the next step: rotated as in the lane loop, and reset exactly
    # every _SYNC steps (the rotation's rounding drifts); at k = n_steps the period ends
    # and _start_period sets it to 0.
    sync = _SYNC * math.floor(k / _SYNC)
    if k == sync and k < n_steps:
        phase = 2.0 * math.pi * k / n_steps
        L[_S + j], L[_C + j] = math.sin(phase), math.cos(phase)
    else:
        cb, sb = L[_PCB + j], L[_PSB + j]
        L[_S + j], L[_C + j] = s0 * cb + c0 * sb, c0 * cb - s0 * sb
    # the next step to stop at: a resync or the end (a lane in quarter steps is marked as
    # such by _commit_steps)
    L[_KEND + j] = k0 + min(sync + _SYNC, n_steps) - 1.0
    return k >= n_steps


@njit(**_JIT)
def _end_period(L, j, p, ring, acc, gaps, ring_len, n_strobe, settle, it):
    """Book the period that lane ``j`` just finished in iteration ``it``; the status once
    it is done, else -1."""
    x, v, e, q = L[_X + j], L[_V + j], L[_E + j], L[_Q + j]
    n = int(L[_N + j]) + 1
    L[_N + j] = n
    if not (math.isfinite(x + v + e + q) and abs(x) <= p[P_XLIM]):
        return DIVERGED, 0
    slot = (n - 1) % MAX_ORBIT_PERIOD
    acc[slot, _A_Q], acc[slot, _A_XMAX], acc[slot, _A_XMIN] = q, L[_XMAX + j], L[_XMIN + j]
    acc[slot, _A_VMAX], acc[slot, _A_VPK] = L[_VMAX + j], L[_VPK + j]
    acc[slot, _A_FCMAX], acc[slot, _A_NIMP], acc[slot, _A_SVIMP] = (
        L[_FCMAX + j], L[_NIMP + j], L[_SVIMP + j])
    r = n % ring_len
    ring[r, 0], ring[r, 1], ring[r, 2] = x, v, e
    _start_period(L, j, it + 1.0)
    if settle:
        orbit = _orbit_period(ring, acc, gaps, n, ring_len, p[P_TOL], p[P_VPERX], p[P_EPERX])
        if orbit > 0 and n >= n_strobe:
            return SETTLED, orbit
    if n >= int(p[P_MAXP]):
        return NOT_SETTLED, 0
    return -1, 0


@njit(**_JIT)
def _output(L, j, p, y, metrics, strobe, ring, acc, ring_len, status, orbit):
    """Write the state, stroboscopic samples and metrics of lane ``j``'s finished point."""
    n = int(L[_N + j])
    y[0], y[1], y[2], y[3] = L[_X + j], L[_V + j], L[_E + j], L[_VIMP + j]
    n_strobe = strobe.shape[0]
    for i in range(n_strobe):
        age = n_strobe - 1 - i
        valid = age <= n and status != DIVERGED
        for c in range(3):
            strobe[i, c] = ring[(n - age) % ring_len, c] if valid else np.nan
    _reduce(acc, n, orbit if status == SETTLED else min(n, MAX_ORBIT_PERIOD), p, metrics)
    metrics[M_ORBIT] = orbit
    metrics[M_STATUS] = status
    metrics[M_PERIODS] = n
    if status == DIVERGED:
        for i in range(M_ORBIT):
            metrics[i] = np.nan


@njit(**_JIT)
def _run_queue(params, states, metrics, strobes, series, settle, queue, successors, control, b):
    """Run lines that start at the points ``queue`` (indices) to their ends, LANES at a
    time, as thread ``b``: a lane whose point is done takes the point ``successors`` names
    next on its line (-1: none), from the state it left, or else the next line not yet
    taken from the queue (by any thread), so that no lane waits for the slowest point.
    ``control[b]`` counts the points done; ``control[-1]`` set to nonzero stops taking
    points (see _next_point)."""
    lanes = min(LANES, len(queue))
    n_strobe = strobes.shape[1]
    ring_len = max(MAX_ORBIT_PERIOD + 1, n_strobe)
    L = _table()
    ring = np.empty((lanes, ring_len, 3))
    acc = np.zeros((lanes, MAX_ORBIT_PERIOD, _NA))
    gaps = np.empty((lanes, _GAP_HISTORY, MAX_ORBIT_PERIOD + 1))
    point = np.full(lanes, -1)
    n_series = series.shape[0]
    for j in range(LANES):
        _idle(L, j)
    active = 0
    for j in range(lanes):  # the lanes that get no point are the last ones
        pt = _next_point(params, states, successors, queue, -1, False, control, b)
        if pt < 0:
            break
        _take(L, j, params, states, pt, ring, acc, gaps, 0.0)
        point[j] = pt
        active += 1
    groups = (active + GROUP - 1) // GROUP
    it = -1.0  # the iteration of the lane loop
    while active > 0:
        it += 1.0
        if n_series > 0:  # one point recorded at every step boundary
            i = int(L[_N + 0] * L[_PNS + 0] + it - L[_K0 + 0])
            if i < n_series:
                series[i, 0], series[i, 1], series[i, 2] = L[_X + 0], L[_V + 0], L[_E + 0]
                series[i, 3] = L[_FC + 0]
        marked, quarters = _lane_steps(L, groups, it)
        if marked == 0:
            continue
        if quarters > 0:
            _quarter_steps(L, lanes)
        finished = False
        for j in range(lanes):
            if L[_NEED + j] == 0.0 or point[j] < 0:
                continue
            if not _finish_step(L, j, it):
                continue
            pt = point[j]
            status, orbit = _end_period(L, j, params[pt], ring[j], acc[j], gaps[j], ring_len,
                                        n_strobe, settle, it)
            if status < 0:
                continue
            if n_series > 0:
                i = int(L[_N + 0] * L[_PNS + 0])
                if i < n_series:
                    series[i, 0], series[i, 1], series[i, 2] = L[_X + 0], L[_V + 0], L[_E + 0]
                    series[i, 3] = L[_FC + 0]
            _output(L, j, params[pt], states[pt], metrics[pt], strobes[pt], ring[j], acc[j],
                    ring_len, status, orbit)
            control[b] += 1
            pt = _next_point(params, states, successors, queue, pt, status == DIVERGED,
                             control, b)
            if pt >= 0:
                _take(L, j, params, states, pt, ring, acc, gaps, it + 1.0)
                point[j] = pt
            else:
                point[j] = -1
                _idle(L, j)
                active -= 1
                finished = True
        if finished:  # the queue is empty: move the points left to the first lanes
            active = 0
            for j in range(lanes):
                if point[j] >= 0:
                    if j != active:
                        _move(L, j, active, ring, acc, gaps)
                        point[active], point[j] = point[j], -1
                    active += 1
            groups = (active + GROUP - 1) // GROUP


@njit(**_JIT)
def _next_point(params, states, successors, queue, done, diverged, control, b):
    """The next point to run after point ``done`` (-1: none yet): ``done``'s successor,
    which starts from ``done``'s final state (from its own initial state, the state at
    rest, when ``done`` ``diverged``), or else the next line of ``queue``, which every
    thread takes from (``control[-2]``, the next to take, is shared); -1 when none is left
    or ``control[-1]`` asks to stop.

    A point whose budget of periods (P_MAXP) is 0 is not run (refused before integration,
    its outputs left for the caller to write): its state passes on to its successor.
    """
    pt = -1
    if done >= 0:
        pt = successors[done]
        if pt >= 0 and not diverged:
            states[pt, :] = states[done, :]
    while control[len(control) - 1] == 0:
        if pt < 0:
            taken = _fetch_add(control, len(control) - 2)
            if taken >= len(queue):
                return -1
            pt = queue[taken]
        if params[pt, P_MAXP] > 0.0:
            return pt
        control[b] += 1
        following = successors[pt]
        if following >= 0:
            states[following, :] = states[pt, :]
        pt = following
    return -1


@intrinsic
def _fetch_add(typingctx, counts, i):
    """``counts[i] += 1`` as one atomic operation (int64 array); returns the value before."""
    if not (isinstance(counts, types.Array) and counts.dtype == types.int64
            and isinstance(i, types.Integer)):
        return None

    def codegen(context, builder, signature, args):
        array, index = args
        ary = context.make_array(signature.args[0])(context, builder, array)
        index = context.cast(builder, index, signature.args[1], types.intp)
        pointer = cgutils.get_item_pointer(context, builder, signature.args[0], ary, [index])
        return builder.atomic_rmw("add", pointer, context.get_constant(types.int64, 1),
                                  "monotonic")

    return types.int64(counts, i), codegen


@njit(**_JIT)
def _move(L, j, i, ring, acc, gaps):
    """Move the point of lane ``j`` to lane ``i`` and leave lane ``j`` idle."""
    for r in range(0, _ROWS * LANES, LANES):
        L[r + i] = L[r + j]
    ring[i], acc[i], gaps[i] = ring[j], acc[j], gaps[j]
    _idle(L, j)


@njit(**_JIT)
def _idle(L, j):
    """Lane ``j`` without a point, which the lane loop never marks: it stays at x = 0,
    v = 1, V = 1 (its increments are 0), with dV/dt = 1 (1/(R C_p) = -1, theta/C_p =
    0), no forcing, the stop at infinity, no contact and no period end."""
    L[_PA + j], L[_PKHM + j], L[_PNS + j], L[_PLOC + j], L[_ON + j] = 0.0, 0.0, np.inf, 1.0, 0.0
    L[_PG + j], L[_PIRC + j], L[_PTHC + j], L[_KEND + j] = np.inf, -1.0, 0.0, np.inf
    L[_FC + j], L[_FCP + j] = 0.0, 0.0
    L[_X + j], L[_V + j], L[_E + j] = 0.0, 1.0, 1.0
    for r in range(_MXX, _MEC + LANES, LANES):
        L[r + j] = 0.0


@njit(**_JIT)
def _take(L, j, params, states, pt, ring, acc, gaps, it):
    _load(L, j, params[pt], states[pt], it)
    ring[j, 0, 0], ring[j, 0, 1], ring[j, 0, 2] = L[_X + j], L[_V + j], L[_E + j]
    acc[j, :, :] = 0.0
    gaps[j, :, :] = np.inf


def run_points(params, states, metrics, strobes, successors=None, on_points=None) -> None:
    """Run every point to steady state, on all numba threads.

    ``params[i]`` is a parameter row (``kernel.pack_parameters``), ``states[i]`` the state
    (updated in place), ``metrics[i]`` and ``strobes[i]`` the outputs (``kernel.METRIC_NAMES``;
    the last S stroboscopic samples). Points are independent and each is computed by the
    same instructions whichever lane or thread takes it, so a point's result does not
    depend on the thread count or on the other points.

    ``successors[i]``, when given, is the point that starts from point i's final state
    (-1: none), one frequency on of a continuation line (it starts from its own
    ``states`` when point i diverges); a point is named at most once and lines do not
    close on themselves (else ValueError). A lane walks a line to its end, with no wait for
    other lines. A point whose row has P_MAXP = 0 is not run: its state passes on and its
    outputs are left unwritten. ``on_points(n)``, when given, is called in this thread as
    points finish (n: how many since the last call); the kernel then runs in another
    thread, and stops taking points when ``on_points`` raises (or on KeyboardInterrupt).
    """
    n = params.shape[0]
    successors = (np.full(n, -1, dtype=np.int64) if successors is None
                  else np.ascontiguousarray(successors, dtype=np.int64))
    heads = _line_heads(successors, n)
    # Lines taken by forcing period (stable: in the callers' order within one): the lanes
    # of a group then hold points whose contacts come at about the same step of the
    # period, so that fewer steps of a group run the contact stages (the kernel of a
    # 64 x 64 gap x frequency sweep built gap-major 3-4 % faster, best and median of 8
    # alternated runs, measured when each thread had a queue of its own).
    heads = heads[np.argsort(-params[heads, P_T], kind="stable")]
    threads = max(1, min(numba.get_num_threads(), len(heads)))
    control = np.zeros(threads + 2, dtype=np.int64)  # points done per thread; next line; stop
    args = (params, states, metrics, strobes, successors, heads, control)
    if on_points is None:
        _run_threads(*args)
        return
    failure = []

    def run():
        try:
            numba.set_num_threads(threads)  # (numba's thread count is per calling thread)
            _run_threads(*args)
        except BaseException as error:  # raised again in the calling thread
            failure.append(error)

    worker = threading.Thread(target=run, name="harvester_sweep kernel", daemon=True)
    worker.start()
    reported = 0
    try:
        running = True
        while running:  # (at least once: a kernel may end before it is first looked at)
            worker.join(_POLL)
            running = worker.is_alive()
            done = int(control[:threads].sum())
            if done > reported:
                on_points(done - reported)
                reported = done
    finally:
        control[-1] = 1  # a no-op once the kernel is done; else it stops taking points
        worker.join()
    if failure:
        raise failure[0]


_POLL = 0.2  # seconds between looks at the progress of a kernel run in another thread


def _line_heads(successors: np.ndarray, n: int) -> np.ndarray:
    """The first point of every line of ``successors`` (see run_points); ValueError where
    they do not make lines."""
    linked = successors[successors >= 0]
    if successors.shape != (n,) or (successors < -1).any() or (linked >= n).any() \
            or len(np.unique(linked)) != len(linked):
        raise ValueError("successors: must hold, for each point, the index of another point "
                         "or -1, no point named twice")
    continued = np.zeros(n, dtype=bool)
    continued[linked] = True
    heads = np.flatnonzero(~continued)
    walked, ahead = len(heads), heads
    while ahead.size:  # one point further along every line per pass
        ahead = successors[ahead]
        ahead = ahead[ahead >= 0]
        walked += ahead.size
    if walked != n:  # the points left over close on themselves
        raise ValueError("successors: a cycle of points (a line must have a first point)")
    return heads


@njit(parallel=True, nogil=True, **_JIT)
def _run_threads(params, states, metrics, strobes, successors, heads, control):
    """Every thread takes lines from ``heads`` as its lanes need them (see _next_point),
    so that the threads end together whatever the lines cost."""
    no_series = np.empty((0, 4))
    for b in prange(len(control) - 2):
        _run_queue(params, states, metrics, strobes, no_series, True, heads, successors,
                   control, b)


def warm_up() -> None:
    """Compile :func:`run_points` (or load it from numba's on-disk cache) without running."""
    run_points(np.zeros((0, NP)), np.zeros((0, 4)), np.zeros((0, NM)), np.zeros((0, 0, 3)))


def cache_warm() -> bool:
    """Whether :func:`run_points` is in numba's on-disk cache; if not, its first call
    compiles the kernel (about 30 s)."""
    if _FLUSHED:
        return False
    try:
        return Path(_run_threads._cache._cache_file._index_path).exists()
    except AttributeError:  # another numba's internals: say nothing
        return True


def record_series(row: np.ndarray, state: np.ndarray, periods: int) -> np.ndarray:
    """(x, v, V, F_c) at every step over ``periods`` forcing periods from ``state``.

    Returns a float64 array of shape ``(periods * steps_per_period + 1, 4)``; ``state``
    is not modified.
    """
    row = row.copy()
    row[P_MAXP] = periods
    n_steps = int(row[P_N])
    series = np.empty((periods * n_steps + 1, 4))
    _run_queue(row[None, :], state.copy()[None, :], np.empty((1, NM)), np.empty((1, 0, 3)),
               series, False, np.zeros(1, dtype=np.int64), np.full(1, -1, dtype=np.int64),
               np.zeros(3, dtype=np.int64), 0)
    return series


_FLUSHED: list = []  # not empty once the cache was flushed by this process


def _flush_if_kernel_changed() -> None:
    """Drop this module's cached machine code when kernel.py has changed since it was cached.

    numba's on-disk cache checks only the stamp of the file that defines a function, but
    the functions here inline kernel.py's: after an edit of kernel.py alone (an editable
    install), they would run the old kernel. A hash of kernel.py is kept next to the cache.
    """
    from hashlib import sha256

    from . import kernel

    cache = getattr(_run_threads, "_cache", None)
    if cache is None or not hasattr(cache, "cache_path"):
        return
    stamp = sha256(Path(kernel.__file__).read_bytes()).hexdigest()
    marker = Path(cache.cache_path) / "lanes.kernel-sha256"
    try:
        if marker.exists() and marker.read_text() == stamp:
            return
        for value in globals().values():
            if isinstance(value, numba.core.registry.CPUDispatcher):
                value._cache.flush()
        marker.write_text(stamp)
        _FLUSHED.append(True)
    except OSError:  # an unwritable cache: numba recompiles or falls back by itself
        pass


_flush_if_kernel_changed()
