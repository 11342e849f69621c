"""A stop that moves: the upper stop on a spring and damper, fixed to the base.

State ``(x, v, V, x_s, v_s)``: the tip's (layouts.STATE) and the stop's displacement
relative to the base [m] and velocity [m/s]. The stop feels the base's acceleration
as the tip does, and the contact force the other way::

    x''   = A sin(w t) - wn^2 x - (c/m) x' + (theta/m) V - F_c / m
    x_s'' = A sin(w t) - (k_s/m_s) x_s - (c_s/m_s) x_s' + F_c / m_s
    F_c   = k_h delta^1.5 max(1 + c_h (x' - x_s'), 0),   delta = max(x - g - x_s, 0)

The contact's switches are those of the rigid stop with the relative motion in place of
the tip's: ``x - x_s = g`` (touch, separation) and ``1 + c_h (x' - x_s') = 0`` (the
no-tension clip). A lane holding a moving stop takes every step here, in scalar code
(lanes.load marks it so), so that the lane loop of the rigid stop carries none of it.
Apart from the stop, the tip's step is the lane loop's trial step and the stop's own two
equations are stepped beside it (:func:`_apart`); in contact the step is taken again from
its start in quarter steps; every switch is located inside the step as in :mod:`.rk4`.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..jit import JIT, njit
from ..models import hertz
from ..models.tip_mass import contact_force, contact_force_rate, in_contact, voltage_rate
from . import booking, hermite
from .layouts import LANE
from .rk4 import GRADED, GRADED_TO_SWITCH, THETA_TOL, WHOLE, forcing

#: The coefficients of a point with a moving stop: the tip's (model.Coefficients) and
#: k_s/m_s [1/s^2], c_s/m_s [1/s], m/m_s [-].
StopCoefficients = namedtuple("StopCoefficients", ("wn2", "cm", "thm", "khm", "g", "ch",
                                                   "irc", "thc", "swn2", "scm", "ratio"))

# Sub-step fractions of a step in contact: four quarters.
QUARTERS = np.array([0.25, 0.25, 0.25, 0.25])


@njit(inline="always", **JIT)
def coupled_derivatives(x, v, V, xs, vs, f, k, on):
    """Accelerations of the tip and the stop [m/s^2] and dV/dt [V/s] at forcing ``f``
    [m/s^2]; ``on`` 1 in contact, 0 out of it."""
    fm = contact_force(x - xs, v - vs, on * k.khm, k.g, k.ch)  # F_c / m
    a = f - k.wn2 * x + k.thm * V - k.cm * v - fm
    a_s = f - k.swn2 * xs - k.scm * vs + fm * k.ratio
    return a, a_s, -k.irc * V - k.thc * v


@njit(**JIT)
def coupled_rk4(x, v, V, xs, vs, dt, f0, fm, f1, k, on):
    """One classical RK4 step of length dt [s] with forcing f0, fm, f1 [m/s^2] at its
    start, middle and end; returns the state at its end and int V^2 dt [V^2 s]."""
    hh, h6 = 0.5 * dt, dt / 6.0
    a1, b1, e1 = coupled_derivatives(x, v, V, xs, vs, f0, k, on)
    x2, v2, V2, s2, u2 = x + hh * v, v + hh * a1, V + hh * e1, xs + hh * vs, vs + hh * b1
    a2, b2, e2 = coupled_derivatives(x2, v2, V2, s2, u2, fm, k, on)
    x3, v3, V3, s3, u3 = x + hh * v2, v + hh * a2, V + hh * e2, xs + hh * u2, vs + hh * b2
    a3, b3, e3 = coupled_derivatives(x3, v3, V3, s3, u3, fm, k, on)
    x4, v4, V4, s4, u4 = x + dt * v3, v + dt * a3, V + dt * e3, xs + dt * u3, vs + dt * b3
    a4, b4, e4 = coupled_derivatives(x4, v4, V4, s4, u4, f1, k, on)
    return (x + h6 * (v + 2.0 * (v2 + v3) + v4), v + h6 * (a1 + 2.0 * (a2 + a3) + a4),
            V + h6 * (e1 + 2.0 * (e2 + e3) + e4), xs + h6 * (vs + 2.0 * (u2 + u3) + u4),
            vs + h6 * (b1 + 2.0 * (b2 + b3) + b4),
            h6 * (V * V + 2.0 * (V2 * V2 + V3 * V3) + V4 * V4))


@njit(**JIT)
def coupled_pieces(y, start, length, fractions, s0, c0, n_steps, h, A, k, on):
    """RK4 over the fraction [start, start + length] of a step of h [s] (forcing phase
    sin, cos = s0, c0 at its start) in sub-steps of ``fractions`` of ``length``, in their
    order. ``y`` is (x, v, V, x_s, v_s); returns the end state and int V^2 dt."""
    w = math.pi / n_steps  # forcing phase per half step
    x, v, V, xs, vs = y
    q, at = 0.0, start
    f0 = forcing(A, s0, c0, 2.0 * w * at)
    n = fractions.shape[0]
    for i in range(n):
        dt = fractions[i] * length
        f1 = forcing(A, s0, c0, 2.0 * w * (at + dt))
        x, v, V, xs, vs, dq = coupled_rk4(x, v, V, xs, vs, dt * h,
                                  f0, forcing(A, s0, c0, w * (2.0 * at + dt)), f1, k, on)
        q += dq
        at += dt
        f0 = f1
    return (x, v, V, xs, vs), q


@njit(inline="always", **JIT)
def _with_damping(k, ch):
    """``k`` with the contact damping c_h = ``ch`` [s/m]."""
    return StopCoefficients(k.wn2, k.cm, k.thm, k.khm, k.g, ch, k.irc, k.thc, k.swn2, k.scm,
                            k.ratio)


@njit(inline="always", **JIT)
def _touching(y, k):
    """Whether the stop pushes at state ``y``: past both contact surfaces."""
    x, v, _, xs, vs = y
    return in_contact(x - xs, v - vs, k.g, k.ch)


@njit(**JIT)
def _switch(y, yn, s0, c0, n_steps, h, A, k, on):
    """The earliest contact switch inside the step from ``y`` to ``yn`` (taken with
    contact state ``on``): hertz.TOUCH on x - x_s = g, hertz.CLIP on 1 + c_h (v - v_s) = 0,
    0 already
    across at the start; its time as a fraction of the step, first on the cubic Hermite
    interpolant of the relative motion, then by Newton on RK4 sub-steps (rk4.switch_step
    for the rigid stop)."""
    x, v, V, xs, vs = y
    xn, vn, Vn, xsn, vsn = yn
    w = math.pi / n_steps
    d0, d1, r0, r1 = x - xs - k.g, xn - xsn - k.g, v - vs, vn - vsn
    theta, kind = 2.0, 0
    if d0 * d1 < 0.0:
        theta, kind = hermite.root(d0, r0, d1, r1, h, 0.0), hertz.TOUCH
    if hertz.clip(r0, k.ch) * hertz.clip(r1, k.ch) < 0.0:
        a0, b0, _ = coupled_derivatives(x, v, V, xs, vs, A * s0, k, on)
        a1, b1, _ = coupled_derivatives(xn, vn, Vn, xsn, vsn, forcing(A, s0, c0, 2.0 * w), k, on)
        s2 = hermite.root(r0, a0 - b0, r1, a1 - b1, h, hertz.clip_rate(k.ch))
        if s2 < theta:
            theta, kind = s2, hertz.CLIP
    if kind == 0:
        return 0, 0.0
    for _ in range(4):  # Newton on the sub-step length
        f1 = forcing(A, s0, c0, 2.0 * w * theta)
        e = coupled_rk4(x, v, V, xs, vs, theta * h, A * s0, forcing(A, s0, c0, w * theta), f1,
                        k, on)
        if kind == hertz.TOUCH:
            residual, rate = e[0] - e[3] - k.g, e[1] - e[4]
        else:
            a, b, _ = coupled_derivatives(e[0], e[1], e[2], e[3], e[4], f1, k, on)
            residual, rate = hertz.clip(e[1] - e[4], k.ch), k.ch * (a - b)
        if rate == 0.0:
            break
        step = residual / (rate * h)
        theta = min(max(theta - step, 0.0), 1.0)
        if abs(step) <= THETA_TOL:
            break
    return kind, theta


@njit(**JIT)
def step(L, j):
    """Take lane ``j``'s step with its moving stop from the step's start, and book its
    extrema, impacts and force peaks (as lanes.finish_step does for a rigid stop)."""
    x, v, V = L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j]
    xs, vs, on = L[LANE.stop_x + j], L[LANE.stop_v + j], L[LANE.stop_on + j]
    s0, c0, ch = L[LANE.sin + j], L[LANE.cos + j], L[LANE.ch + j]
    A, h, n_steps, g = L[LANE.amplitude + j], L[LANE.h + j], L[LANE.steps + j], L[LANE.gap + j]
    latch, kh = L[LANE.latch + j], L[LANE.kh + j]
    irc, thc = L[LANE.irc + j], L[LANE.thc + j]
    k = StopCoefficients(L[LANE.wn2 + j], L[LANE.cm + j], L[LANE.thm + j], L[LANE.khm + j], g,
                         ch, irc, thc, L[LANE.stop_wn2 + j], L[LANE.stop_cm + j],
                         L[LANE.stop_ratio + j])
    y = (x, v, V, xs, vs)
    if L[LANE.locate + j] == 0.0:  # plain fixed steps: the force always on, clipped
        if latch > 0.0 and x - xs <= g and v - vs > 0.0:  # predicted approach velocity
            ch = latch / (v - vs)
            k = _with_damping(k, ch)
        yn, dq = coupled_pieces(y, 0.0, 1.0, WHOLE, s0, c0, n_steps, h, A, k, 1.0)
        d0, d1 = x - xs - g, yn[0] - yn[3] - g
        if d0 <= 0.0 < d1:  # first touch, on the cubic Hermite interpolant
            ch = booking.impact(L, j, hermite.crossing_rate(d0, v - vs, d1, yn[1] - yn[4], h,
                                                            0.0), ch)
        on = 1.0
    else:
        if on == 1.0:
            yn, dq = coupled_pieces(y, 0.0, 1.0, QUARTERS, s0, c0, n_steps, h, A, k, on)
        else:  # apart, the tip's step is the lane loop's trial step; the stop's is its own
            yn, dq = _apart(L, j, y, k)
        if _touching(yn, k) != (on == 1.0):
            kind, theta = _switch(y, yn, s0, c0, n_steps, h, A, k, on)
            # up to the switch with the old contact state (graded towards a separation)...
            graded = on == 1.0 and kind == hertz.TOUCH
            ye, q1 = coupled_pieces(y, 0.0, theta, GRADED_TO_SWITCH if graded else WHOLE, s0, c0,
                            n_steps, h, A, k, on)
            onset = on == 0.0 and kind == hertz.TOUCH
            if onset:
                ch = booking.impact(L, j, ye[1] - ye[4], ch)
                k = _with_damping(k, ch)
            on = 1.0 - on
            # ... and after it with the new one (graded from a touch)
            yn, q2 = coupled_pieces(ye, theta, 1.0 - theta, GRADED if onset else WHOLE,
                                    s0, c0, n_steps, h, A, k, on)
            dq = q1 + q2
    xn, vn, Vn, xsn, vsn = yn
    fc, fcp = L[LANE.fc + j], L[LANE.fc_previous + j]
    fcn = contact_force(xn - xsn, vn - vsn, on * kh, g, ch)  # of the relative motion
    dfc, dfcn = 0.0, 0.0
    if fcn > 0.0 and booking.at_peak(L, j, fcp, fc, fcn):  # (its rates: booking.peak)
        s1 = s0 * L[LANE.cos_step + j] + c0 * L[LANE.sin_step + j]
        a0, b0, _ = coupled_derivatives(x, v, V, xs, vs, A * s0, k, on)
        a1, b1, _ = coupled_derivatives(xn, vn, Vn, xsn, vsn, A * s1, k, on)
        dfc = contact_force_rate(x - xs, v - vs, a0 - b0, on * kh, g, ch)
        dfcn = contact_force_rate(xn - xsn, vn - vsn, a1 - b1, on * kh, g, ch)
    booking.extrema(L, j, x, v, V, voltage_rate(V, v, irc, thc), xn, vn, Vn,
                    voltage_rate(Vn, vn, irc, thc), h, fcp, fc, fcn, dfc, dfcn, True, np.inf)
    smax = max(L[LANE.stop_x_max + j], abs(xsn))
    if vs > 0.0 >= vsn or vs < 0.0 <= vsn:
        smax = max(smax, abs(hermite.extremum(xs, vs, xsn, vsn, h)))
    L[LANE.stop_x_max + j] = smax
    L[LANE.x + j], L[LANE.v + j], L[LANE.voltage + j] = xn, vn, Vn
    L[LANE.stop_x + j], L[LANE.stop_v + j], L[LANE.stop_on + j] = xsn, vsn, on
    L[LANE.fc_previous + j], L[LANE.fc + j], L[LANE.ch + j] = fc, fcn, ch
    L[LANE.q + j] += dq


@njit(inline="always", **JIT)
def _apart(L, j, y, k):
    """The step of lane ``j`` from ``y`` with tip and stop apart: the tip's is the lane
    loop's trial step (the contact-free map of the rigid stop's lanes, its RK4 step to
    rounding), the stop's an RK4 step of its own linear equation, forced as the tip is;
    int V^2 dt from the step's ends, as the lane loop takes it."""
    x, v, V, xs, vs = y
    s0, c0 = L[LANE.sin + j], L[LANE.cos + j]
    A, ca, sa, h = L[LANE.amplitude + j], L[LANE.cos_half + j], L[LANE.sin_half + j], L[LANE.h + j]
    sm = s0 * ca + c0 * sa
    s1 = sm * ca + (c0 * ca - s0 * sa) * sa
    f0, fm, f1 = A * s0, A * sm, A * s1
    hh, h6 = 0.5 * h, h / 6.0
    b1 = f0 - k.swn2 * xs - k.scm * vs
    s2, u2 = xs + hh * vs, vs + hh * b1
    b2 = fm - k.swn2 * s2 - k.scm * u2
    s3, u3 = xs + hh * u2, vs + hh * b2
    b3 = fm - k.swn2 * s3 - k.scm * u3
    s4, u4 = xs + h * u3, vs + h * b3
    b4 = f1 - k.swn2 * s4 - k.scm * u4
    xn, vn, Vn = L[LANE.x_trial + j], L[LANE.v_trial + j], L[LANE.voltage_trial + j]
    dq = hermite.v2_integral(V, voltage_rate(V, v, k.irc, k.thc), Vn,
                             voltage_rate(Vn, vn, k.irc, k.thc), L[LANE.half_h + j],
                             L[LANE.h2_6 + j])
    return ((xn, vn, Vn, xs + h6 * (vs + 2.0 * (u2 + u3) + u4),
             vs + h6 * (b1 + 2.0 * (b2 + b3) + b4)), dq)
