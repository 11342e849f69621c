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
from ..models.tip_mass import Coefficients, derivatives, rk4
from . import hermite


@njit(inline="always", **JIT)
def forcing(A, s0, c0, d):
    """A sin(phi_0 + d) [m/s^2] from s0, c0 = sin, cos of the step's start phase phi_0 and
    Taylor series in the offset d [rad]; |d| <= 2 pi / 16 (16 steps per period at least),
    where it is within 2e-15 A of A sin (rounding included)."""
    d2 = d * d
    sd = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0 * (
        1.0 - d2 / 110.0)))))
    cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0 * (
        1.0 - d2 / 90.0 * (1.0 - d2 / 132.0)))))
    return A * (s0 * cd + c0 * sd)


@njit(inline="always", **JIT)
def with_contact(k, khm, ch):
    """``k`` with the contact term k_h/m = ``khm`` (0: out of contact) and c_h = ``ch``."""
    return Coefficients(k.wn2, k.cm, k.thm, khm, k.g, ch, k.irc, k.thc)


# Sub-step fractions of a piece of step next to a touch or separation, finest at the
# switch: the Hertz force grows like (t - t_0)^1.5 there, which costs RK4 its order.
GRADED = np.array([1 / 64, 1 / 64, 1 / 32, 1 / 16, 1 / 8, 1 / 4, 1 / 2])
WHOLE = np.array([1.0])


@njit(**JIT)
def pieces(x, v, V, start, length, fractions, reverse, s0, c0, n_steps, h, A, k):
    """RK4 over the fraction [start, start + length] of a step of h [s] whose forcing phase
    starts at sin, cos = s0, c0, in sub-steps of the given ``fractions`` of ``length`` (in
    reverse order when ``reverse``). Returns x, v, V, int V^2 dt."""
    w = math.pi / n_steps  # forcing phase per half step
    q = 0.0
    at = start
    f0 = forcing(A, s0, c0, 2.0 * w * at)
    n = fractions.shape[0]
    for i in range(n):
        piece = fractions[n - 1 - i] if reverse else fractions[i]
        dt = piece * length
        f1 = forcing(A, s0, c0, 2.0 * w * (at + dt))
        x, v, V, dq, _ = rk4(x, v, V, dt * h, f0, forcing(A, s0, c0, w * (2.0 * at + dt)),
                             f1, k)
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
