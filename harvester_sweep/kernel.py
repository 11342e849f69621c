"""The fixed-step RK4 kernel of one point: the switched Hertz system, its RK4 steps with
contact switches located inside the step, and steady-state detection.

Kernels are plain Numba functions on float arrays (no Python objects); everything
user-facing lives in :mod:`harvester_sweep.scene`. One point's parameters are a row of
``NP`` floats laid out by the ``P_*`` indices below, built by :func:`pack_parameters`.
:mod:`harvester_sweep.lanes` steps many points at once with these functions.

State per point: ``(x, v, V, v_imp)``: displacement [m], velocity [m/s], voltage [V] and
the approach velocity [m/s] latched at the last first touch (used by the latched laws).

The forcing phase is measured from the start of a forcing period, so the state at a
period boundary is a stroboscopic sample y(nT) and can be continued at another frequency.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .contact import damping_factor
from .stepping import contact_damping_value

# Bit-for-bit reproducible whichever lane, group or thread runs a point: no reassociation
# (it would let a vector loop sum in another order than scalar code) and no approximate
# functions. FMA contraction is allowed (about 15 % faster): LLVM fuses a multiply into an
# add of the same basic block, so differently shaped code may round differently, but every
# lane runs the same vector code and which steps run scalar code is decided by the point's
# own state (tests/test_reproducibility.py checks a point in several lanes, groups and
# thread counts). No nnan/ninf either: the divergence check relies on isfinite.
FASTMATH = {"nsz", "arcp", "contract"}
_JIT = dict(cache=True, fastmath=FASTMATH, error_model="numpy")

# Layout of a parameter row.
(
    P_A,  # base acceleration amplitude A [m/s^2]
    P_WN2,  # k/m = wn^2 [1/s^2]
    P_CM,  # c/m = 2 zeta wn [1/s]
    P_THM,  # theta/m [N/(V kg)]
    P_KHM,  # k_h/m [N/(m^1.5 kg)]
    P_M,  # mass m [kg]
    P_G,  # gap g [m]
    P_CH,  # contact damping c_h in fixed mode [s/m]
    P_LATCH,  # factor c_h v_imp of the latched law, 0 in fixed mode [-]
    P_IRC,  # 1/(R C_p) [1/s]
    P_THC,  # theta/C_p [V s/m]
    P_R,  # load resistance R [Ohm]
    P_T,  # forcing period T [s]
    P_N,  # steps per period [-]
    P_MAXP,  # budget of periods [-]
    P_TOL,  # settle tolerance [-]
    P_XLIM,  # |x| beyond this is divergence [m]
    P_LOCATE,  # 1: locate contact switches inside the step, 0: plain fixed steps [-]
    P_VPERX,  # velocity scale per displacement, w [1/s] (settle test)
    P_EPERX,  # voltage scale per displacement, theta/C_p min(1, w R C_p) [V/m] (settle test)
) = range(20)
NP = 20

# Metrics per point, in this order (names are the public interface, see datasets.METRICS).
METRIC_NAMES = (
    "power",
    "v_rms",
    "v_peak",
    "power_peak",
    "x_max",
    "x_min",
    "contact_force_max",
    "impacts_per_period",
    "approach_velocity",
    "orbit_period",
    "status",
    "periods_run",
)
NM = len(METRIC_NAMES)
(M_POWER, M_VRMS, M_VPEAK, M_PPEAK, M_XMAX, M_XMIN, M_FCMAX, M_IMPACTS, M_VIMP, M_ORBIT,
 M_STATUS, M_PERIODS) = range(NM)

SETTLED, NOT_SETTLED, DIVERGED = 0, 1, 2
TOO_STIFF = 3  # set by the sweep driver for a point refused before integration
STATUS_NAMES = ("settled", "not settled", "diverged", "too stiff")
MAX_ORBIT_PERIOD = 16  # longest orbit period p looked for, in forcing periods

# Per-period accumulators kept for the last MAX_ORBIT_PERIOD periods.
_A_Q, _A_XMAX, _A_XMIN, _A_VMAX, _A_VPK, _A_FCMAX, _A_NIMP, _A_SVIMP = range(8)
_NA = 8
_GAP_HISTORY = 4 * MAX_ORBIT_PERIOD  # periods of e_p(n) kept to estimate the decay rate


def pack_parameters(p: dict) -> np.ndarray:
    """Kernel parameter row from a validated parameter dict (SI units)."""
    wn = 2.0 * math.pi * p["natural_frequency"]
    m = p["mass"]
    latched = p["contact_damping"] is None and p["impact_velocity_mode"] == "latched"
    ch = contact_damping_value(p, p["impact_velocity"])
    row = np.zeros(NP)
    row[P_A] = p["amplitude"]
    row[P_WN2] = wn * wn
    row[P_CM] = 2.0 * p["damping_ratio"] * wn
    row[P_THM] = p["coupling"] / m
    row[P_KHM] = p["hertz_stiffness"] / m
    row[P_M] = m
    row[P_G] = p["gap"]
    row[P_CH] = ch
    row[P_LATCH] = damping_factor(p["contact_law"], p["restitution"]) if latched else 0.0
    row[P_IRC] = 1.0 / (p["resistance"] * p["capacitance"])
    row[P_THC] = p["coupling"] / p["capacitance"]
    row[P_R] = p["resistance"]
    row[P_T] = 1.0 / p["frequency"]
    row[P_N] = p["steps_per_period"]
    row[P_MAXP] = p["max_periods"]
    row[P_TOL] = p["settle_tolerance"]
    static = p["amplitude"] / (wn * wn) / max(2.0 * p["damping_ratio"], 1e-4)
    row[P_XLIM] = 1e3 * (abs(p["gap"]) + static + 1e-9)
    row[P_LOCATE] = 1.0 if p["locate_switches"] else 0.0
    w = 2.0 * math.pi * p["frequency"]
    row[P_VPERX] = w
    tau = p["resistance"] * p["capacitance"]
    row[P_EPERX] = p["coupling"] / p["capacitance"] * min(1.0, w * tau)
    return row


def initial_state(p: dict) -> np.ndarray:
    """State at rest, ``(x_0, 0, 0, impact_velocity)``.

    At rest the mass sits at its static equilibrium ``k x_0 + k_h (x_0 - g)^1.5 = 0``: 0
    unless the stop is preloaded (g < 0), then between g and 0 (found by bisection).
    """
    x0 = 0.0
    k = p["mass"] * (2.0 * math.pi * p["natural_frequency"]) ** 2
    kh, g = p["hertz_stiffness"], p["gap"]
    if g < 0.0 and kh > 0.0:
        low, high = g, 0.0
        for _ in range(200):
            x0 = 0.5 * (low + high)
            if k * x0 + kh * (x0 - g) ** 1.5 > 0.0:
                high = x0
            else:
                low = x0
    return np.array([x0, 0.0, 0.0, p["impact_velocity"]])


@njit(inline="always", **_JIT)
def _derivatives(x, v, V, f, wn2, cm, thm, khm, g, ch, irc, thc, contact=True):
    """Acceleration [m/s^2] and dV/dt [V/s]; the contact never pulls (factor clipped at 0).

    ``contact=False`` (a constant at the call) leaves the contact term out of the code: the
    same bits as khm = 0, without its square root. The square root comes last, times a
    factor computed while it runs: from one RK4 stage to the next the chain of dependent
    operations (x, x - g, the root, one multiply-add) is then as short as it can be, which
    is what a lone step in contact waits on (30 ns a sub-step against 36 ns with the
    root first, on the machine of benchmarks/results/speed.md).
    """
    a = f - wn2 * x + thm * V - cm * v
    if contact:
        d = max(x - g, 0.0)
        a = a - khm * d * max(1.0 + ch * v, 0.0) * math.sqrt(d)
    return a, -irc * V - thc * v


@njit(inline="always", **_JIT)
def _hermite(y0, d0, y1, d1, h):
    """Coefficients B, C of the cubic Hermite y0 + h d0 s + B s^2 + C s^3 on s in [0, 1]."""
    return 3.0 * (y1 - y0) - h * (2.0 * d0 + d1), 2.0 * (y0 - y1) + h * (d0 + d1)


@njit(inline="always", **_JIT)
def _hermite_extremum(y0, d0, y1, d1, h):
    """Value of the cubic Hermite interpolant where its derivative changes sign (d0 d1 <= 0).

    The derivative h d0 + 2 B s + 3 C s^2 is a quadratic in s, solved in closed form (q,
    the sum that does not cancel; the roots c / q, which is the one at a = 0, and q / a).
    Of the two roots the one further inside [0, 1] is taken (a root at an end is one of
    the step's ends, which callers take anyway), clamped to [0, 1] (rounding can put a
    root at an end just outside)."""
    B, C = _hermite(y0, d0, y1, d1, h)
    a, b, c = 3.0 * C, 2.0 * B, h * d0
    r = math.sqrt(max(b * b - 4.0 * a * c, 0.0))
    q = -0.5 * (b + r if b >= 0.0 else b - r)
    s1, s2 = c / q, q / a
    out1 = -s1 if s1 < 0.5 else s1 - 1.0  # how far outside [0, 1] (< 0: inside)
    out2 = -s2 if s2 < 0.5 else s2 - 1.0
    s = s2 if (out2 < out1) | (out1 != out1) else s1  # (a root 0 / 0 loses)
    s = 0.0 if s < 0.0 else (1.0 if s > 1.0 else s)
    s = s if s == s else 0.5  # (both 0 / 0: the derivative is 0 throughout)
    return y0 + s * (c + s * (B + s * C))


@njit(**_JIT)
def _hermite_root(y0, d0, y1, d1, h, level):
    """s in [0, 1] where the cubic Hermite interpolant crosses ``level`` (between y0 and y1)."""
    B, C = _hermite(y0, d0, y1, d1, h)
    s = (level - y0) / (y1 - y0) if y1 != y0 else 0.5
    for _ in range(4):
        dp = h * d0 + 2.0 * B * s + 3.0 * C * s * s
        if dp != 0.0:
            s = min(max(s - (y0 + h * d0 * s + B * s * s + C * s * s * s - level) / dp, 0.0), 1.0)
    return s


@njit(**_JIT)
def _hermite_crossing_rate(y0, d0, y1, d1, h, level):
    """Slope dy/dt of the cubic Hermite interpolant where it crosses ``level``."""
    B, C = _hermite(y0, d0, y1, d1, h)
    s = _hermite_root(y0, d0, y1, d1, h, level)
    return (h * d0 + 2.0 * B * s + 3.0 * C * s * s) / h


@njit(inline="always", **_JIT)
def _rk4_increment(x, v, V, dt, f0, fm, f1, wn2, cm, thm, khm, g, ch, irc, thc, contact=True):
    """The increments of x, v, V over one RK4 step (see _rk4), the integral of V^2 over
    the step [V^2 s] and the acceleration at the start [m/s^2]."""
    hh, h6 = 0.5 * dt, dt / 6.0
    a1, e1 = _derivatives(x, v, V, f0, wn2, cm, thm, khm, g, ch, irc, thc, contact)
    x2, v2, V2 = x + hh * v, v + hh * a1, V + hh * e1
    a2, e2 = _derivatives(x2, v2, V2, fm, wn2, cm, thm, khm, g, ch, irc, thc, contact)
    x3, v3, V3 = x + hh * v2, v + hh * a2, V + hh * e2
    a3, e3 = _derivatives(x3, v3, V3, fm, wn2, cm, thm, khm, g, ch, irc, thc, contact)
    x4, v4, V4 = x + dt * v3, v + dt * a3, V + dt * e3
    a4, e4 = _derivatives(x4, v4, V4, f1, wn2, cm, thm, khm, g, ch, irc, thc, contact)
    return (
        h6 * (v + 2.0 * (v2 + v3) + v4),
        h6 * (a1 + 2.0 * (a2 + a3) + a4),
        h6 * (e1 + 2.0 * (e2 + e3) + e4),
        h6 * (V * V + 2.0 * (V2 * V2 + V3 * V3) + V4 * V4),
        a1,
    )


@njit(inline="always", **_JIT)
def _rk4(x, v, V, dt, f0, fm, f1, wn2, cm, thm, khm, g, ch, irc, thc, contact=True):
    """One classical RK4 step of length dt [s].

    f0, fm, f1 are the forcing accelerations A sin(w t) at the start, middle and end of the
    step [m/s^2]; khm = 0 switches the contact off, and so does ``contact=False`` (see
    _derivatives). Returns x, v, V at the end, the integral of V^2 over the step [V^2 s]
    and the acceleration at the start [m/s^2].
    """
    dx, dv, dV, dq, a1 = _rk4_increment(x, v, V, dt, f0, fm, f1, wn2, cm, thm, khm, g, ch,
                                        irc, thc, contact)
    return x + dx, v + dv, V + dV, dq, a1


@njit(**_JIT)
def free_step_map(h, ca, sa, A, wn2, cm, thm, irc, thc):
    """The RK4 step of length h [s] without contact, as the linear map it is.

    Without the contact force the system is linear, so the increment of one RK4 step is
    linear in z = (x, v, V, sin phi_0, cos phi_0), phi_0 the forcing phase at the step's
    start (the forcing at the middle and the end of the step comes from phi_0 by rotating
    it by half a step: ca, sa = cos, sin of pi / steps per period, as in the lane loop).
    Returns the 3 x 5 matrix D that gives the increments of x, v, V from z, found by
    stepping the basis vectors of z: (x, v, V) + D z is the same step as :func:`_rk4`, up
    to rounding, for about a third of its floating-point operations. (The increment, not the
    whole step I + D, is stored: I + D rounded once would repeat the same relative error
    of ~1e-16 at every step, a drift that grows with the number of steps.)
    """
    out = np.empty((3, 5))
    basis = np.eye(5)
    for i in range(5):
        x, v, V, s0, c0 = basis[i, 0], basis[i, 1], basis[i, 2], basis[i, 3], basis[i, 4]
        sm, cmid = s0 * ca + c0 * sa, c0 * ca - s0 * sa
        out[0, i], out[1, i], out[2, i], _, _ = _rk4_increment(
            x, v, V, h, A * s0, A * sm, A * (sm * ca + cmid * sa), wn2, cm, thm, 0.0, 0.0, 0.0,
            irc, thc, False)
    return out


@njit(inline="always", **_JIT)
def _v2_integral(V0, dV0, V1, dV1, hh, h26):
    """int V^2 dt [V^2 s] over a step of length h from the voltage [V] and its rate [V/s] at
    both ends; hh = h/2, h26 = h^2/6 [s, s^2]. The trapezoidal rule with its
    Euler-Maclaurin end correction (h^2/12 times the change of d(V^2)/dt): local error
    h^5/720 max |d^4(V^2)/dt^4|, the order of the RK4 step, and no stage values needed."""
    return hh * (V0 * V0 + V1 * V1) + h26 * (V0 * dV0 - V1 * dV1)


@njit(inline="always", **_JIT)
def _forcing(A, s0, c0, d):
    """A sin(phi_0 + d) [m/s^2] from s0, c0 = sin, cos of the step's start phase phi_0 and
    Taylor series in the offset d [rad]; |d| <= 2 pi / 16 (16 steps per period at least),
    where it is within 2e-15 A of A sin (rounding included)."""
    d2 = d * d
    sd = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0 * (
        1.0 - d2 / 110.0)))))
    cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0 * (
        1.0 - d2 / 90.0 * (1.0 - d2 / 132.0)))))
    return A * (s0 * cd + c0 * sd)


# Sub-step fractions of a piece of step next to a touch or separation, finest at the
# switch: the Hertz force grows like (t - t_0)^1.5 there, which costs RK4 its order.
_GRADED = np.array([1 / 64, 1 / 64, 1 / 32, 1 / 16, 1 / 8, 1 / 4, 1 / 2])
_WHOLE = np.array([1.0])


@njit(**_JIT)
def _rk4_pieces(x, v, V, start, length, pieces, reverse, s0, c0, n_steps, h, A, wn2, cm, thm,
                khm, g, ch, irc, thc):
    """RK4 over the fraction [start, start + length] of a step whose forcing phase starts
    at sin, cos = s0, c0, in sub-steps of the given fractions of ``length`` (in reverse
    order when ``reverse``). Returns x, v, V, int V^2 dt."""
    w = math.pi / n_steps  # forcing phase per half step
    q = 0.0
    at = start
    f0 = _forcing(A, s0, c0, 2.0 * w * at)
    n = pieces.shape[0]
    for i in range(n):
        piece = pieces[n - 1 - i] if reverse else pieces[i]
        dt = piece * length
        f1 = _forcing(A, s0, c0, 2.0 * w * (at + dt))
        x, v, V, dq, _ = _rk4(x, v, V, dt * h, f0, _forcing(A, s0, c0, w * (2.0 * at + dt)),
                              f1, wn2, cm, thm, khm, g, ch, irc, thc)
        q += dq
        at += dt
        f0 = f1
    return x, v, V, q


# Newton on a switch stops once its correction to the switch time is below this fraction
# of a step, and leaves that correction out so that its last sub-step, which ends at the
# switch, can be kept: the switch is then off by at most 1e-10 of a step, which moves the
# state by far less than rounding (the force is continuous across a switch).
_THETA_TOL = 1e-10


@njit(**_JIT)
def _switch_step(x, v, V, a0, xn, vn, Vn, on, s0, c0, n_steps, h, A, wn2, cm, thm, khm, g,
                 ch, irc, thc):
    """Locate the contact switch inside a step.

    The switch is the earliest sign change of x - g (touch, separation) or of 1 + c_h v
    (the no-tension clip), first placed on the cubic Hermite interpolant of the trial step,
    then refined by Newton on RK4 sub-steps. The caller integrates up to the switch with
    the old contact state and after it with the new one, so that no RK4 step straddles the
    kink of the force. Returns the kind of switch (1: x = g, 2: 1 + c_h v = 0, 0: already
    across at the start of the step), the switch time as a fraction theta of the step,
    whether Newton converged, and then x, v, V and int V^2 dt at the end of its last
    sub-step, which ends at theta (the caller keeps them rather than step there again).
    s0, c0 are sin, cos of the forcing phase at the start of the step.
    """
    w = math.pi / n_steps  # forcing phase per half step
    f_end = _forcing(A, s0, c0, 2.0 * w)
    theta, kind = 2.0, 0
    if (x - g) * (xn - g) < 0.0:
        theta, kind = _hermite_root(x, v, xn, vn, h, g), 1
    if (1.0 + ch * v) * (1.0 + ch * vn) < 0.0:
        a_end, _ = _derivatives(xn, vn, Vn, f_end, wn2, cm, thm, on * khm, g, ch, irc, thc)
        s2 = _hermite_root(v, a0, vn, a_end, h, -1.0 / ch)
        if s2 < theta:
            theta, kind = s2, 2
    if kind == 0:  # no sign change in the step: the state was already across at its start
        theta = 0.0
    khm_old = on * khm
    f0 = A * s0
    xe, ve, Ve, qe = x, v, V, 0.0
    for _ in range(3):  # Newton on the sub-step length
        dt = theta * h
        xe, ve, Ve, qe, _ = _rk4(x, v, V, dt, f0,
                                 _forcing(A, s0, c0, w * theta),
                                 _forcing(A, s0, c0, 2.0 * w * theta),
                                 wn2, cm, thm, khm_old, g, ch, irc, thc)
        if kind == 1:
            residual, rate = xe - g, ve
        elif kind == 2:
            ae, _ = _derivatives(xe, ve, Ve, _forcing(A, s0, c0, 2.0 * w * theta), wn2, cm,
                                 thm, khm_old, g, ch, irc, thc)
            residual, rate = 1.0 + ch * ve, ch * ae
        else:
            break
        if rate == 0.0:
            break
        step = residual / (rate * h)
        if abs(step) <= _THETA_TOL:  # converged: theta stays, and so does its sub-step
            return kind, theta, True, xe, ve, Ve, qe
        theta = min(max(theta - step, 0.0), 1.0)
    return kind, theta, False, xe, ve, Ve, qe


@njit(**_JIT)
def _orbit_period(ring, acc, gaps, n, ring_len, tol, v_per_x, e_per_x):
    """Orbit period p once the transient left in y(nT) is below ``tol``, else 0.

    The gap e_p(n) = |y(nT) - y((n-p)T)| (largest over x, v, V, each relative to its
    amplitude over the last p periods) shrinks geometrically, by rho = e_p(n) / e_p(n-p)
    per p periods, so the transient still left is about e_p(n) / (1 - rho). Testing that
    estimate, not e_p(n) alone, keeps slow transients (rho near 1, light damping) and
    transients that alternate in sign (a multiplier near -1 mimics p = 2) from passing
    for a steady state; rho is the largest of the last three ratios because beating
    modes make single ratios jump. Once settled at p, the smallest divisor of p that
    also repeats is the orbit period.

    A period p is tested at the multiples of p only (n = p, 2p, ...; the ratios compare
    those, and a divisor of p is tested whenever p is): the 16 candidates cost about 3.4
    tests a period rather than 16, and a p-periodic orbit is found at most p - 1 periods
    later than it would be at every period.
    """
    row = n % _GAP_HISTORY
    found = 0
    xs, vs, es = 0.0, 0.0, 0.0  # amplitudes over the last `period` periods, grown with it
    for period in range(1, min(n, MAX_ORBIT_PERIOD) + 1):
        slot = (n - period) % MAX_ORBIT_PERIOD
        xs = max(xs, abs(acc[slot, _A_XMAX]), abs(acc[slot, _A_XMIN]))
        vs, es = max(vs, acc[slot, _A_VMAX]), max(es, acc[slot, _A_VPK])
        if n % period != 0:  # (a period p is tested every p periods: see above)
            continue
        e = _gap(ring, n, period, ring_len, xs, max(vs, v_per_x * xs), max(es, e_per_x * xs))
        gaps[row, period] = e
        if found == 0 and e <= tol:  # (else neither test below can pass)
            rho = 0.0
            for k in range(3):
                later = gaps[(n - k * period) % _GAP_HISTORY, period]
                earlier = gaps[(n - (k + 1) * period) % _GAP_HISTORY, period]
                rho = max(rho, later / earlier if 0.0 < earlier < np.inf else np.inf)
            # (or at the rounding floor, where ratios are noise)
            if e <= 1e-5 * tol or (rho < 1.0 and e <= tol * (1.0 - rho)):
                found = period
    if found > 1:
        for d in range(1, found):
            if found % d == 0 and gaps[row, d] <= 8.0 * tol:
                return d
    return found


@njit(inline="always", **_JIT)
def _gap(ring, n, period, ring_len, xs, vs, es):
    """max over (x, v, V) of |y(nT) - y((n-period)T)| / its amplitude (xs, vs, es) over the
    last ``period`` periods.

    The caller floors the velocity and voltage amplitudes at what the displacement
    amplitude implies (v ~ w x, V ~ theta x / C_p), so that a component at rest (pure
    rounding noise) does not hold the test back.
    """
    a, b = ring[n % ring_len], ring[(n - period) % ring_len]
    e = 0.0
    if xs > 0.0:
        e = max(e, abs(a[0] - b[0]) / xs)
    if vs > 0.0:
        e = max(e, abs(a[1] - b[1]) / vs)
    if es > 0.0:
        e = max(e, abs(a[2] - b[2]) / es)
    return e


@njit(**_JIT)
def _reduce(acc, n, periods, p, metrics):
    """Metrics over the last ``periods`` forcing periods from the per-period accumulators."""
    q, n_imp, sum_vimp = 0.0, 0.0, 0.0
    xmax, xmin, vpk, fcmax = -np.inf, np.inf, 0.0, 0.0
    for i in range(periods):
        slot = (n - 1 - i) % MAX_ORBIT_PERIOD
        q += acc[slot, _A_Q]
        xmax, xmin = max(xmax, acc[slot, _A_XMAX]), min(xmin, acc[slot, _A_XMIN])
        vpk, fcmax = max(vpk, acc[slot, _A_VPK]), max(fcmax, acc[slot, _A_FCMAX])
        n_imp += acc[slot, _A_NIMP]
        sum_vimp += acc[slot, _A_SVIMP]
    mean_v2 = q / (max(periods, 1) * p[P_T])
    metrics[M_POWER] = mean_v2 / p[P_R]
    metrics[M_VRMS] = math.sqrt(mean_v2)
    metrics[M_VPEAK] = vpk
    metrics[M_PPEAK] = vpk * vpk / p[P_R]
    metrics[M_XMAX], metrics[M_XMIN] = xmax, xmin
    metrics[M_FCMAX] = fcmax
    metrics[M_IMPACTS] = n_imp / max(periods, 1)
    metrics[M_VIMP] = sum_vimp / n_imp if n_imp > 0 else np.nan
