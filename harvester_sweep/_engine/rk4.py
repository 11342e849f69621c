"""RK4 over parts of a step: the forcing inside a step, sub-steps, and contact switches
located inside the step so that no RK4 step straddles the kink of the contact force.

The forcing phase is carried as (sin, cos) of its value at the step's start (s0, c0);
inside the step it comes from a Taylor series in the offset (:func:`forcing`).
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import JIT, njit
from ..models import hertz
from ..models.tip_mass import Coefficients, derivatives, rk4, rk4_moved, rk4_slopes, rk4_tangent
from . import hermite, tangents


@njit(inline="always", **JIT)
def _offset(d):
    """sin d, cos d by Taylor series in the offset d [rad]; |d| <= 2 pi / 16 (16 steps per
    period at least), where each is within 2e-15 of sin, cos (rounding included)."""
    d2 = d * d
    sd = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0 * (
        1.0 - d2 / 110.0)))))
    cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0 * (
        1.0 - d2 / 90.0 * (1.0 - d2 / 132.0)))))
    return sd, cd


@njit(inline="always", **JIT)
def forcing(A, s0, c0, d):
    """A sin(phi_0 + d) [m/s^2] from s0, c0 = sin, cos of the step's start phase phi_0 and
    the offset d [rad] (:func:`_offset`)."""
    sd, cd = _offset(d)
    return A * (s0 * cd + c0 * sd)


@njit(inline="always", **JIT)
def _forcing_rate(A, s0, c0, d, w):
    """d/dt (A sin(phi_0 + d)) [m/s^3] at forcing angular frequency w [rad/s] (as
    :func:`forcing`)."""
    sd, cd = _offset(d)
    return A * w * (c0 * cd - s0 * sd)


@njit(inline="always", **JIT)
def with_contact(k, khm, ch):
    """``k`` with the contact term k_h/m = ``khm`` (0: out of contact) and c_h = ``ch``."""
    return Coefficients(k.wn2, k.cm, k.thm, khm, k.g, ch, k.irc, k.thc)


# Sub-step fractions of a piece of step next to a touch or separation, finest at the
# switch: the Hertz force grows like (t - t_0)^1.5 there, which costs RK4 its order. In
# the order they are taken: GRADED from a switch at the piece's start, GRADED_TO_SWITCH
# up to one at its end. (Two arrays rather than a flag: a literal flag is a signature of
# its own, and every function taking it would be compiled twice.)
GRADED = np.array([1 / 64, 1 / 64, 1 / 32, 1 / 16, 1 / 8, 1 / 4, 1 / 2])
GRADED_TO_SWITCH = np.ascontiguousarray(GRADED[::-1])
WHOLE = np.array([1.0])


@njit(**JIT)
def pieces(x, v, V, start, length, fractions, s0, c0, n_steps, h, A, k, L=None, j=0):
    """RK4 over the fraction [start, start + length] of a step of h [s] whose forcing phase
    starts at sin, cos = s0, c0, in sub-steps of the given ``fractions`` of ``length``, in
    their order. Returns x, v, V, int V^2 dt. With a lane table ``L``,
    lane ``j``'s tangents are carried through the sub-steps too (tangents)."""
    w = math.pi / n_steps  # forcing phase per half step
    q = 0.0
    at = start
    f0 = forcing(A, s0, c0, 2.0 * w * at)
    n = fractions.shape[0]
    for i in range(n):
        piece = fractions[i]
        dt = piece * length
        f1 = forcing(A, s0, c0, 2.0 * w * (at + dt))
        fm = forcing(A, s0, c0, w * (2.0 * at + dt))
        if L is not None:
            tangents.through_step(L, j, x, v, V, dt * h, f0, fm, f1, k)
        x, v, V, dq, _ = rk4(x, v, V, dt * h, f0, fm, f1, k)
        q += dq
        at += dt
        f0 = f1
    return x, v, V, q


# Newton on a switch stops once its correction to the switch time is below this fraction
# of a step, and leaves that correction out so that its last sub-step, which ends at the
# switch, can be kept: the switch is then off by at most 1e-10 of a step, which moves the
# state by far less than rounding (the force is continuous across a switch).
THETA_TOL = 1e-10


@njit(**JIT)
def switch_step(x, v, V, a0, xn, vn, Vn, s0, c0, n_steps, h, A, k):
    """Locate the contact switch inside a step of h [s] from (x, v, V) to (xn, vn, Vn).

    ``k`` holds the contact state before the switch (k.khm = 0 out of contact); a0 is the
    acceleration at the start. The switch is the earliest sign change of x - g (touch,
    separation) or of 1 + c_h v (the no-tension clip), first placed on the cubic Hermite
    interpolant of the trial step, then refined by Newton on RK4 sub-steps. The caller
    integrates up to the switch with the old contact state and after it with the new one.
    Returns the kind of switch (hertz.TOUCH: x = g, hertz.CLIP: 1 + c_h v = 0, 0: already
    across at the start of the step), the switch time as a fraction theta of the step,
    whether Newton converged, and then x, v, V and int V^2 dt at the end of its last
    sub-step, which ends at theta (the caller keeps them rather than step there again).
    """
    g, ch = k.g, k.ch
    w = math.pi / n_steps  # forcing phase per half step
    f_end = forcing(A, s0, c0, 2.0 * w)
    theta, kind = 2.0, 0
    if (x - g) * (xn - g) < 0.0:
        theta, kind = hermite.root(x, v, xn, vn, h, g), hertz.TOUCH
    if hertz.clip(v, ch) * hertz.clip(vn, ch) < 0.0:
        a_end, _ = derivatives(xn, vn, Vn, f_end, k)
        s2 = hermite.root(v, a0, vn, a_end, h, hertz.clip_rate(ch))
        if s2 < theta:
            theta, kind = s2, hertz.CLIP
    if kind == 0:  # no sign change in the step: the state was already across at its start
        theta = 0.0
    f0 = A * s0
    xe, ve, Ve, qe = x, v, V, 0.0
    for _ in range(3):  # Newton on the sub-step length
        dt = theta * h
        xe, ve, Ve, qe, _ = rk4(x, v, V, dt, f0, forcing(A, s0, c0, w * theta),
                                forcing(A, s0, c0, 2.0 * w * theta), k)
        if kind == hertz.TOUCH:
            residual, rate = xe - g, ve
        elif kind == hertz.CLIP:
            ae, _ = derivatives(xe, ve, Ve, forcing(A, s0, c0, 2.0 * w * theta), k)
            residual, rate = hertz.clip(ve, ch), ch * ae
        else:
            break
        if rate == 0.0:
            break
        step = residual / (rate * h)
        if abs(step) <= THETA_TOL:  # converged: theta stays, and so does its sub-step
            return kind, theta, True, xe, ve, Ve, qe
        theta = min(max(theta - step, 0.0), 1.0)
    return kind, theta, False, xe, ve, Ve, qe


@njit(**JIT)
def _pieces_rate(x, v, V, start, length, fractions, s0, c0, n_steps, h, A, k,
                 dstart, dlength, L=None, j=0):
    """The rate of the end state of :func:`pieces` (the same arguments) [m, m/s, V per unit]
    where its start moves by ``dstart`` and its length by ``dlength`` (fractions of the
    step) per unit: the sub-steps' RK4 stages differentiated by their times and lengths.
    With a lane table ``L``, lane ``j``'s tangents are carried through the sub-steps too,
    as :func:`pieces` carries them: each sub-step's stages then serve the state, its
    tangents and its rate at once."""
    w = math.pi / n_steps
    omega = 2.0 * w / h  # [rad/s]
    dx = dv = dV = 0.0
    at, moved = start, dstart  # a sub-step's start and its rate [fractions of the step]
    n = fractions.shape[0]
    for i in range(n):
        piece = fractions[i]
        dt = piece * length
        f0, fm, f1 = (forcing(A, s0, c0, 2.0 * w * at), forcing(A, s0, c0, w * (2.0 * at + dt)),
                      forcing(A, s0, c0, 2.0 * w * (at + dt)))
        r0, rm, r1 = (_forcing_rate(A, s0, c0, 2.0 * w * at, omega),
                      _forcing_rate(A, s0, c0, w * (2.0 * at + dt), omega),
                      _forcing_rate(A, s0, c0, 2.0 * w * (at + dt), omega))
        if L is not None:
            tangents.through_step_inline(L, j, x, v, V, dt * h, f0, fm, f1, k)
        dx, dv, dV = rk4_moved(x, v, V, dt * h, f0, fm, f1, r0, rm, r1, k, dx, dv, dV,
                               moved * h, piece * dlength * h)
        x, v, V, _, _ = rk4(x, v, V, dt * h, f0, fm, f1, k)
        at += dt
        moved += piece * dlength
    return dx, dv, dV


@njit(inline="always", **JIT)
def _normal_change(L, j, c, slopes, dt, k, ex, ev):
    """The change along the normal (ex, ev) of a switch's surface of lane ``j``'s tangent
    ``c`` carried through an RK4 step of dt [s] with the stages' force slopes ``slopes``
    (tip_mass.rk4_slopes)."""
    dx, dv, _ = rk4_tangent(slopes, dt, k, L[tangents.row(0, c) + j], L[tangents.row(1, c) + j],
                            L[tangents.row(2, c) + j])
    return ex * dx + ev * dv


@njit(inline="always", **JIT)
def _add_moved(L, j, gx, gv, gV, m0, m1, m2):
    """Add to lane ``j``'s tangents the rate (gx, gv, gV) [per unit theta] times each one's
    move of theta (m0, m1, m2)."""
    for r, g in ((0, gx), (1, gv), (2, gV)):
        L[tangents.row(r, 0) + j] += g * m0
        L[tangents.row(r, 1) + j] += g * m1
        L[tangents.row(r, 2) + j] += g * m2


@njit(**JIT)
def switch_tangents(L, j, x, v, V, xe, ve, Ve, kind, theta, before_fractions,
                    after_fractions, s0, c0, n_steps, h, A, before, after):
    """Carry lane ``j``'s tangents through a step split at a located switch (the derivative
    of lanes._finish_rigid's step; see tangents for the rule): from (x, v, V) up to theta
    with the contact state ``before`` in ``before_fractions`` (in their order, as
    :func:`pieces`), reaching (xe, ve, Ve), and on with ``after`` in ``after_fractions``.
    Where ``kind`` is a switch (hertz.TOUCH: x = g, hertz.CLIP: 1 + c_h v = 0), theta
    moves with the start state, as the root :func:`switch_step` finds on one sub-step from
    the start, whatever pieces then take the step up to it; the pieces' rates in theta
    are their RK4 stages differentiated by their times and lengths (_pieces_rate)."""
    moves = kind == hertz.TOUCH or kind == hertz.CLIP
    m0 = m1 = m2 = rx = rv = rV = 0.0
    if moves:
        ex, ev = (1.0, 0.0) if kind == hertz.TOUCH else (0.0, before.ch)  # the surface's normal
        rx, rv, rV = _pieces_rate(x, v, V, 0.0, theta, WHOLE, s0, c0, n_steps, h, A,
                                  before, 0.0, 1.0)
        rate = ex * rx + ev * rv  # the root's, on the one sub-step
        moves = rate != 0.0
    if moves:
        # each tangent's move of theta, from its change along the normal on the one sub-step
        w = math.pi / n_steps
        f0, fm, f1 = A * s0, forcing(A, s0, c0, w * theta), forcing(A, s0, c0, 2.0 * w * theta)
        slopes = rk4_slopes(x, v, V, theta * h, f0, fm, f1, before)
        m0 = -_normal_change(L, j, 0, slopes, theta * h, before, ex, ev) / rate
        m1 = -_normal_change(L, j, 1, slopes, theta * h, before, ex, ev) / rate
        m2 = -_normal_change(L, j, 2, slopes, theta * h, before, ex, ev) / rate
    # the tangents through the pieces up to theta, with their rate where theta moves (the
    # one sub-step's, where they are that), ...
    if moves and before_fractions.shape[0] > 1:
        rx, rv, rV = _pieces_rate(x, v, V, 0.0, theta, before_fractions, s0, c0,
                                  n_steps, h, A, before, 0.0, 1.0, L, j)
    else:
        pieces(x, v, V, 0.0, theta, before_fractions, s0, c0, n_steps, h, A, before, L, j)
    if moves:
        _add_moved(L, j, rx, rv, rV, m0, m1, m2)
        # ... and after it, from the same state
        ax, av, aV = _pieces_rate(xe, ve, Ve, theta, 1.0 - theta, after_fractions, s0,
                                  c0, n_steps, h, A, after, 1.0, -1.0, L, j)
        _add_moved(L, j, ax, av, aV, m0, m1, m2)
    else:
        pieces(xe, ve, Ve, theta, 1.0 - theta, after_fractions, s0, c0, n_steps, h, A,
               after, L, j)
