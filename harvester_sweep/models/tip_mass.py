"""The tip-mass model, declared once: its state, right-hand side, contact surfaces,
contact-free step, linear system and energy.

State ``(x, v, V)`` (:data:`STATE`): tip displacement relative to the base [m],
velocity [m/s], voltage across the load [V]::

    x'' = A sin(w t) - wn^2 x - (c/m) x' + (theta/m) V - F_c / m
    V'  = -V / (R C_p) - (theta / C_p) x'
    F_c = the Hertz law (:mod:`.hertz`) at delta = x - g and rate x'

Options of the same model, each adding to the declaration: a second stop below, at
``x = -g_l`` (the engine mirrors the state towards it, so its law is the same function);
a stop on a spring (:data:`STOP_STATE`, its equations in the engine's stop_motion). The
latched approach velocity of the contact law rides along with the state (:data:`LATCHED`).

Out of contact the system is linear (:func:`linear_system`), and so is its RK4 step
(:func:`free_step_map`). The RK4 step's own derivative by its start state, time and length
(:func:`rk4_slopes`, :func:`rk4_tangent`, :func:`rk4_moved`: the variational equations in
its stages) is what the engine carries a monodromy along a run with. A point's
coefficients travel as one :data:`Coefficients` tuple (``k``); ``khm`` is 0 for a point out
of contact.

What is derived from this declaration: the engine's state rows and their sizes
(``_engine.layouts``), the orbits' component scales (``period_map.point_scales``), the
basins' box, the no-contact proof's bound (``acceptance``), the response without the stop
(``linear``), the solver's first scales (``orbits``) and the step's coupled rate
(``timescales``). The tests hold it against references written apart from it: the
textbook phasor, the Hertz law's closed forms, SciPy on the same equations
(tests/physics/test_model_declaration.py, tests/helpers.py).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..jit import JIT, SOLVER_JIT, njit
from . import hertz
from .state import Component

#: The state the period map acts on, in order.
STATE = (
    Component("x", "m", "displacement", "tip displacement relative to the base"),
    Component("v", "m/s", "velocity", "tip velocity"),
    Component("voltage", "V", "voltage", "voltage across the load"),
)
#: What a stop on a spring adds to the state (zero for a rigid stop).
STOP_STATE = (
    Component("stop_x", "m", "displacement",
              "displacement of a moving stop relative to the base (0: rigid stop)"),
    Component("stop_v", "m/s", "velocity", "velocity of a moving stop"),
)
#: Carried with the state, outside the period map: the contact law's latched velocity.
LATCHED = Component("approach_velocity", "m/s", "velocity",
                    "approach velocity latched at the last first touch")

#: A point's model coefficients: wn^2 [1/s^2], c/m [1/s], theta/m [N/(V kg)],
#: k_h/m [N/(m^1.5 kg)] (0: no contact force), g [m], c_h [s/m], 1/(R C_p) [1/s],
#: theta/C_p [V s/m].
Coefficients = namedtuple("Coefficients", ("wn2", "cm", "thm", "khm", "g", "ch", "irc", "thc"))


@njit(inline="always", **JIT)
def derivatives(x, v, V, f, k, contact=True):
    """Acceleration [m/s^2] and dV/dt [V/s] at forcing acceleration ``f`` [m/s^2].

    ``contact=False`` (a constant at the call) leaves the contact term out of the code: the
    same bits as khm = 0, without its square root.
    """
    a = f - k.wn2 * x + k.thm * V - k.cm * v
    if contact:
        a = a - hertz.force(k.khm, x - k.g, v, k.ch)
    return a, -k.irc * V - k.thc * v


@njit(inline="always", **JIT)
def voltage_rate(V, v, irc, thc):
    """dV/dt [V/s] from the voltage [V] and velocity [m/s]: the load circuit's equation."""
    return -irc * V - thc * v


@njit(inline="always", **JIT)
def in_contact(x, v, g, ch):
    """Whether the stop at gap g [m] pushes at (x [m], v [m/s]): past both contact
    surfaces."""
    return hertz.pushes(x - g, v, ch)


@njit(inline="always", **JIT)
def contact_force(x, v, kh_on, g, ch):
    """Contact force F_c [N] at (x [m], v [m/s]); ``kh_on`` is k_h [N/m^1.5] in contact,
    0 out of it."""
    return hertz.force(kh_on, x - g, v, ch)


@njit(inline="always", **JIT)
def contact_force_rate(x, v, a, kh_on, g, ch):
    """dF_c/dt [N/s] at (x [m], v [m/s], a [m/s^2]: the motion relative to the stop where
    the stop moves); ``kh_on`` as for :func:`contact_force`."""
    _, by_delta, by_rate = hertz.force_and_slopes(kh_on, x - g, v, ch)
    return by_delta * v + by_rate * a


@njit(inline="always", **JIT)
def rk4_increment(x, v, V, dt, f0, fm, f1, k, contact=True):
    """The increments of x, v, V over one classical RK4 step of length dt [s], the
    integral of V^2 over the step by the stages' quadrature [V^2 s] and the acceleration
    at the start [m/s^2]. f0, fm, f1: the forcing accelerations A sin(w t) at the start,
    middle and end of the step [m/s^2]."""
    hh, h6 = 0.5 * dt, dt / 6.0
    a1, e1 = derivatives(x, v, V, f0, k, contact)
    x2, v2, V2 = x + hh * v, v + hh * a1, V + hh * e1
    a2, e2 = derivatives(x2, v2, V2, fm, k, contact)
    x3, v3, V3 = x + hh * v2, v + hh * a2, V + hh * e2
    a3, e3 = derivatives(x3, v3, V3, fm, k, contact)
    x4, v4, V4 = x + dt * v3, v + dt * a3, V + dt * e3
    a4, e4 = derivatives(x4, v4, V4, f1, k, contact)
    return (
        h6 * (v + 2.0 * (v2 + v3) + v4),
        h6 * (a1 + 2.0 * (a2 + a3) + a4),
        h6 * (e1 + 2.0 * (e2 + e3) + e4),
        h6 * (V * V + 2.0 * (V2 * V2 + V3 * V3) + V4 * V4),
        a1,
    )


@njit(inline="always", **JIT)
def rk4(x, v, V, dt, f0, fm, f1, k, contact=True):
    """One classical RK4 step of length dt [s] (see :func:`rk4_increment`); k.khm = 0
    switches the contact off, and so does ``contact=False``. Returns x, v, V at the end,
    the integral of V^2 over the step [V^2 s] and the acceleration at the start [m/s^2]."""
    dx, dv, dV, dq, a1 = rk4_increment(x, v, V, dt, f0, fm, f1, k, contact)
    return x + dx, v + dv, V + dV, dq, a1


@njit(inline="always", **JIT)
def _stage(x, v, V, f, k):
    """The rates of x [m/s], v [m/s^2] and V [V/s] at a state, and the contact force's
    slopes by x and by v there (hertz.force_and_slopes, per unit mass)."""
    fc, sx, sv = hertz.force_and_slopes(k.khm, x - k.g, v, k.ch)
    return f - k.wn2 * x + k.thm * V - k.cm * v - fc, -k.irc * V - k.thc * v, sx, sv


@njit(inline="always", **JIT)
def rk4_slopes(x, v, V, dt, f0, fm, f1, k):
    """The contact force's slopes by x and by v (hertz.slopes, per unit mass: [1/s^2],
    [1/s]) at the four stages of :func:`rk4`'s step from (x, v, V), in stage order: what
    :func:`rk4_tangent` carries a change of the state through that step with."""
    hh = 0.5 * dt
    a1, e1, sx1, sv1 = _stage(x, v, V, f0, k)
    x2, v2, V2 = x + hh * v, v + hh * a1, V + hh * e1
    a2, e2, sx2, sv2 = _stage(x2, v2, V2, fm, k)
    x3, v3, V3 = x + hh * v2, v + hh * a2, V + hh * e2
    a3, _, sx3, sv3 = _stage(x3, v3, V3, fm, k)
    sx4, sv4 = hertz.slopes(k.khm, x + dt * v3 - k.g, v + dt * a3, k.ch)
    return sx1, sv1, sx2, sv2, sx3, sv3, sx4, sv4


@njit(inline="always", **JIT)
def _variation(sx, sv, k, dx, dv, dV):
    """The rates of a change (dx, dv, dV) of the state [m, m/s, V] (the variational
    equations), where the contact force's slopes are sx, sv (:func:`rk4_slopes`)."""
    return (dv, -(k.wn2 + sx) * dx - (k.cm + sv) * dv + k.thm * dV,
            -k.irc * dV - k.thc * dv)


@njit(inline="always", **JIT)
def rk4_tangent(slopes, dt, k, dx, dv, dV):
    """A change (dx, dv, dV) of the state at the start of :func:`rk4`'s step of length dt
    [s], carried to its end: the step's own derivative (the RK4 stages of the variational
    equations, with the stages' force slopes ``slopes`` of :func:`rk4_slopes`)."""
    hh, h6 = 0.5 * dt, dt / 6.0
    sx1, sv1, sx2, sv2, sx3, sv3, sx4, sv4 = slopes
    x1, v1, e1 = _variation(sx1, sv1, k, dx, dv, dV)
    x2, v2, e2 = _variation(sx2, sv2, k, dx + hh * x1, dv + hh * v1, dV + hh * e1)
    x3, v3, e3 = _variation(sx3, sv3, k, dx + hh * x2, dv + hh * v2, dV + hh * e2)
    x4, v4, e4 = _variation(sx4, sv4, k, dx + dt * x3, dv + dt * v3, dV + dt * e3)
    return (dx + h6 * (x1 + 2.0 * (x2 + x3) + x4), dv + h6 * (v1 + 2.0 * (v2 + v3) + v4),
            dV + h6 * (e1 + 2.0 * (e2 + e3) + e4))


@njit(inline="always", **JIT)
def rk4_moved(x, v, V, dt, f0, fm, f1, r0, rm, r1, k, dx, dv, dV, dstart, dlength):
    """The change of the end of :func:`rk4`'s step of length dt [s] from (x, v, V) by a
    change (dx, dv, dV) of its start state, ``dstart`` [s] of its start time and
    ``dlength`` [s] of its length: the RK4 stages differentiated by all three. r0, rm, r1:
    the forcing's rates d/dt (A sin(w t)) at the start, middle and end [m/s^3]."""
    hh = 0.5 * dt
    a1, e1, sx, sv = _stage(x, v, V, f0, k)
    x1, v1, e1d = _variation(sx, sv, k, dx, dv, dV)
    v1 += r0 * dstart
    x2, v2, V2 = x + hh * v, v + hh * a1, V + hh * e1
    a2, e2, sx, sv = _stage(x2, v2, V2, fm, k)
    x2d, v2d, e2d = _variation(sx, sv, k, dx + 0.5 * dlength * v + hh * x1,
                               dv + 0.5 * dlength * a1 + hh * v1,
                               dV + 0.5 * dlength * e1 + hh * e1d)
    v2d += rm * (dstart + 0.5 * dlength)
    x3, v3, V3 = x + hh * v2, v + hh * a2, V + hh * e2
    a3, e3, sx, sv = _stage(x3, v3, V3, fm, k)
    x3d, v3d, e3d = _variation(sx, sv, k, dx + 0.5 * dlength * v2 + hh * x2d,
                               dv + 0.5 * dlength * a2 + hh * v2d,
                               dV + 0.5 * dlength * e2 + hh * e2d)
    v3d += rm * (dstart + 0.5 * dlength)
    x4, v4, V4 = x + dt * v3, v + dt * a3, V + dt * e3
    a4, e4, sx, sv = _stage(x4, v4, V4, f1, k)
    x4d, v4d, e4d = _variation(sx, sv, k, dx + dlength * v3 + dt * x3d,
                               dv + dlength * a3 + dt * v3d, dV + dlength * e3 + dt * e3d)
    v4d += r1 * (dstart + dlength)
    h6, l6 = dt / 6.0, dlength / 6.0
    return (dx + l6 * (v + 2.0 * (v2 + v3) + v4) + h6 * (x1 + 2.0 * (x2d + x3d) + x4d),
            dv + l6 * (a1 + 2.0 * (a2 + a3) + a4) + h6 * (v1 + 2.0 * (v2d + v3d) + v4d),
            dV + l6 * (e1 + 2.0 * (e2 + e3) + e4) + h6 * (e1d + 2.0 * (e2d + e3d) + e4d))


@njit(**JIT)
def free_step_map(h, ca, sa, A, wn2, cm, thm, irc, thc):
    """The RK4 step of length h [s] without contact, as the linear map it is.

    Without the contact force the system is linear, so the increment of one RK4 step is
    linear in z = (x, v, V, sin phi_0, cos phi_0), phi_0 the forcing phase at the step's
    start (the forcing at the middle and the end of the step comes from phi_0 by rotating
    it by half a step: ca, sa = cos, sin of pi / steps per period, as in the lane loop).
    Returns the 3 x 5 matrix D that gives the increments of x, v, V from z, found by
    stepping the basis vectors of z: (x, v, V) + D z is the same step as :func:`rk4`, up
    to rounding, for about a third of its floating-point operations. (The increment, not the
    whole step I + D, is stored: I + D rounded once would repeat the same relative error
    of ~1e-16 at every step, a drift that grows with the number of steps.)
    """
    out = np.empty((3, 5))
    basis = np.eye(5)
    k = Coefficients(wn2, cm, thm, 0.0, 0.0, 0.0, irc, thc)
    for i in range(5):
        x, v, V, s0, c0 = basis[i, 0], basis[i, 1], basis[i, 2], basis[i, 3], basis[i, 4]
        sm, cmid = s0 * ca + c0 * sa, c0 * ca - s0 * sa
        out[0, i], out[1, i], out[2, i], _, _ = rk4_increment(
            x, v, V, h, A * s0, A * sm, A * (sm * ca + cmid * sa), k, False)
    return out


def linear_system(mass, natural_frequency, damping_ratio, coupling, capacitance, resistance,
                  **_):
    """The model clear of its stops as ``y' = M y + b a(t)``, y = (x, v, V) and a(t) the
    base acceleration [m/s^2]: returns M (3 x 3; [1/s], [1/s^2], [N/(V kg)], [V s/m])
    and b (3,) [-]. Parameters in SI units (mass [kg], natural_frequency [Hz],
    damping_ratio [-], coupling [N/V], capacitance [F], resistance [Ohm]); any may be an
    array (then M is (..., 3, 3)). ``**_``: other parameters, ignored."""
    wn = 2.0 * np.pi * np.asarray(natural_frequency, dtype=float)
    return linear_matrix(wn * wn, 2.0 * np.asarray(damping_ratio) * wn,
                         np.divide(coupling, mass),
                         1.0 / (np.asarray(resistance) * capacitance),
                         np.divide(coupling, capacitance))


def linear_matrix(wn2, cm, thm, irc, thc):
    """:func:`linear_system` from the coefficients as the engine holds them (those of
    :data:`Coefficients`: wn^2 [1/s^2], c/m [1/s], theta/m [N/(V kg)], 1/(R C_p) [1/s],
    theta/C_p [V s/m]; arrays broadcast): M (..., 3, 3) and b (3,)."""
    shape = np.broadcast(wn2, cm, thm, irc, thc).shape
    m = np.zeros(shape + (3, 3))
    m[..., 0, 1] = 1.0
    m[..., 1, 0] = -np.asarray(wn2)
    m[..., 1, 1] = -np.asarray(cm)
    m[..., 1, 2] = thm
    m[..., 2, 1] = -np.asarray(thc)
    m[..., 2, 2] = -np.asarray(irc)
    return m, np.array([0.0, 1.0, 0.0])


def free_amplitude(A, w, wn2, cm, thm, irc, thc):
    """|X| [m], the stop-free displacement amplitude under the base acceleration A sin(w t)
    [m/s^2, rad/s], in closed form from the coefficients as the engine holds them (those of
    :data:`Coefficients`); arrays broadcast, inf or NaN at an undamped resonance. The
    phasor of :func:`linear_matrix`, written out: cheap enough for every point's first
    scales."""
    with np.errstate(divide="ignore", invalid="ignore"):
        load = thm * thc / (irc + 1j * w)
        return np.abs(A / (wn2 - w * w + 1j * w * cm + 1j * w * load))


@njit(**SOLVER_JIT)
def excursion_bound(x, v, voltage, wn2, thm, thc):
    """The largest displacement [m] a free, decaying motion from deviation (``x``, ``v``,
    ``voltage``) [m, m/s, V] ever reaches, by energy: the homogeneous motion loses
    ``E = (k x^2 + m v^2 + C_p V^2) / 2`` (``dE/dt = -c v^2 - V^2 / R``), so
    ``|x| <= sqrt(2 E / k)``; wn2 = k/m [1/s^2], thm = theta/m, thc = theta/C_p (their
    ratio is C_p/m; 0 for thc 0)."""
    cv = thm / thc if thc != 0 else 0.0
    return np.sqrt(x * x + (v * v + cv * (voltage * voltage)) / wn2)


@njit(**SOLVER_JIT)
def stop_excursion_bound(x, v, stop_wn2):
    """The same bound [m] for a moving stop's own transient from its deviation (``x``,
    ``v``) [m, m/s]: ``k_s x_s^2 + m_s v_s^2`` decays; stop_wn2 = k_s/m_s [1/s^2]."""
    return np.sqrt(x * x + v * v / stop_wn2)
