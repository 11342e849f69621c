"""The period map's derivative carried along a lane: a run's monodromy without perturbed
copies.

A lane that carries tangents (LANE.tangents) holds T = d y / d y0, the derivative of its
state y = (x, v, V) by the state y0 its run started from, and carries it through each of
its steps as the derivative of that step's own arithmetic, so that at the run's end T is
the derivative of the engine's RK4 period map (the monodromy) up to rounding:

- **Clear of the stops** a step is the linear map ``I + D`` (tip_mass.free_step_map, the
  lane's rows LANE.mxx ...), the same for every step of the lane. The lane loop takes those
  steps in vector code and T waits: the steps since LANE.t_since are carried in at once,
  as ``(I + D)^k`` by repeated squaring (:func:`catch_up`), when the lane next takes a step
  of another kind or ends its run.
- **In contact** T goes through each step's RK4 stages of the variational equations
  (tip_mass.rk4_tangent): for a plain step, which the lane loop commits as it does any
  lane's, from its start state kept before the loop (lanes.keep_starts, carry_tangents);
  for a step finished in scalar code, there, sub-step by sub-step where the step is split
  (quarter steps, the graded pieces of rk4.pieces).
- **A located switch** (touch, separation, clip) splits its step at theta, the root of the
  switch's surface on the RK4 sub-step up to it, and theta moves with y0. The step's end
  is ``G(theta) = after(before(y0, theta), theta)``: its derivative is T through both
  pieces at a fixed theta plus ``G'(theta) d theta``, with ``d theta = -(e . d y_s) / (e .
  H'(theta))`` from the switch's surface normal e and ``H = before(y0, .)``. G' and H'
  are the pieces' RK4 stages differentiated by their times and lengths
  (rk4.switch_tangents, tip_mass.rk4_moved): the force is continuous across the switch,
  so no saltation jump enters, but the pieces are laid out from theta, and their RK4
  error moves with it.
- **Mirroring** (lanes.mirror) negates the state, so it negates T.

Only lanes that locate their switches with a rigid stop and a fixed approach velocity carry
tangents (:func:`carried`); the orbit solver takes copies for the others.
"""

from __future__ import annotations

from ..jit import JIT, njit
from ..models.tip_mass import rk4_slopes, rk4_tangent
from .layouts import LANE, LANES, PARAM


@njit(**JIT)
def carried(p):
    """Whether a point of parameter row ``p`` can carry tangents: switches located, rigid
    stops, no latched approach velocity (whose law moves with the state)."""
    return (p[PARAM.locate] != 0.0 and p[PARAM.stop_ratio] == 0.0
            and p[PARAM.latch] == 0.0 and p[PARAM.lower_latch] == 0.0)


@njit(inline="always", **JIT)
def row(r, c):
    """The lane table's row of T's entry (r, c)."""
    return LANE.txx + (3 * r + c) * LANES


@njit(**JIT)
def start(L, j, it):
    """Lane ``j`` starts carrying tangents (T = I) at its step of iteration ``it``."""
    for r in range(3):
        for c in range(3):
            L[row(r, c) + j] = 1.0 if r == c else 0.0
    L[LANE.t_since + j] = it


@njit(inline="always", **JIT)
def _product(a, b):
    """a @ b of 3 x 3 matrices held as 9-tuples, row by row."""
    return (a[0] * b[0] + a[1] * b[3] + a[2] * b[6], a[0] * b[1] + a[1] * b[4] + a[2] * b[7],
            a[0] * b[2] + a[1] * b[5] + a[2] * b[8], a[3] * b[0] + a[4] * b[3] + a[5] * b[6],
            a[3] * b[1] + a[4] * b[4] + a[5] * b[7], a[3] * b[2] + a[4] * b[5] + a[5] * b[8],
            a[6] * b[0] + a[7] * b[3] + a[8] * b[6], a[6] * b[1] + a[7] * b[4] + a[8] * b[7],
            a[6] * b[2] + a[7] * b[5] + a[8] * b[8])


@njit(**JIT)
def catch_up(L, j, it):
    """Carry into lane ``j``'s T its contact-free steps from LANE.t_since up to the step of
    iteration ``it`` (not included): the step's matrix I + D to their number's power."""
    k = int(it - L[LANE.t_since + j])
    L[LANE.t_since + j] = it
    if k <= 0:
        return
    # I + D from the lane's rows of D: (x, v, V) rows, the state's columns
    m = (1.0 + L[LANE.mxx + j], L[LANE.mxv + j], L[LANE.mxe + j],
         L[LANE.mvx + j], 1.0 + L[LANE.mvv + j], L[LANE.mve + j],
         L[LANE.mex + j], L[LANE.mev + j], 1.0 + L[LANE.mee + j])
    power = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    while k > 0:
        if k & 1:
            power = _product(power, m)
        k >>= 1
        if k > 0:
            m = _product(m, m)
    t = (L[row(0, 0) + j], L[row(0, 1) + j], L[row(0, 2) + j],
         L[row(1, 0) + j], L[row(1, 1) + j], L[row(1, 2) + j],
         L[row(2, 0) + j], L[row(2, 1) + j], L[row(2, 2) + j])
    t = _product(power, t)
    for i in range(9):
        L[LANE.txx + i * LANES + j] = t[i]


@njit(**JIT)
def through_step(L, j, x, v, V, dt, f0, fm, f1, k):
    """Carry lane ``j``'s T through one RK4 step of dt [s] from (x, v, V) (tip_mass.rk4's
    arguments)."""
    through_step_inline(L, j, x, v, V, dt, f0, fm, f1, k)


@njit(inline="always", **JIT)
def through_step_inline(L, j, x, v, V, dt, f0, fm, f1, k):
    """:func:`through_step` written into its caller, whose own RK4 stages of the same step
    (the state's, their rates) it then shares."""
    slopes = rk4_slopes(x, v, V, dt, f0, fm, f1, k)
    for c in range(3):
        dx, dv, dV = rk4_tangent(slopes, dt, k, L[row(0, c) + j], L[row(1, c) + j],
                                 L[row(2, c) + j])
        L[row(0, c) + j], L[row(1, c) + j], L[row(2, c) + j] = dx, dv, dV


@njit(**JIT)
def write(L, j, it, out):
    """Write lane ``j``'s T, its steps up to iteration ``it`` (not included) carried in,
    into ``out`` (3, 3), for the state as it is (not mirrored: LANE.sign)."""
    catch_up(L, j, it)
    s = L[LANE.sign + j]
    for r in range(3):
        for c in range(3):
            out[r, c] = s * L[row(r, c) + j]
