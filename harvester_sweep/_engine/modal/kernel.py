"""The modal engine: any linear system with Hertz contact surfaces, integrated exactly
between contacts and by RK4 in the frame of the linear flow inside them.

A model in the form ``y' = M y + f A sin(w t) + sum_s b_s F_s`` (``models.beam``) comes
in the eigen-coordinates of M relative to the linear steady state ``y_p(t)``:
``y = y_p(t) + Re(W z)``, ``z' = lam z + sum_s inp_s F_s``. Out of contact the flow is
exact: ``z(t + tau) = exp(lam tau) z``, one complex product per component whatever the
modes' frequencies, so the fifth bending mode and the rod's modes (tens of kHz and
beyond) cost no step. A grid of ``steps`` per forcing period looks for contact: each
surface's penetration and rate are exact at the grid's ends, a maximum of the
penetration inside a step is found exactly (Newton on its rate), and a touch is located
on the exact flow. Where a bound on the penetration's rise above its chord cannot rule
out a touch inside a step (a rod ringing faster than the grid), the step is searched in
pieces down to an eighth of its fastest component's cycle (``_hidden``). In contact the
force enters through one vector per surface, and the step is the integrating-factor RK4
(Lawson): RK4 on ``exp(-lam t) z``, exact for the linear part, so that its stability
and error come from the contact alone. Its sub-steps grow from ``substep / 2^GRADES``
after a touch (the force starts as ``delta^1.5``), shrink towards the separation
predicted from the penetration (it ends so too), are cut to land on the period's end,
and the switch that ends the force (separation, or the clip of the damping law) is
located inside the sub-step by the Hermite interpolant of the switching function and
secant steps of the RK4 sub-step itself.

The period map is this integrator's own: a point's state at each forcing period's end,
every switch located by the same rules, so a settled orbit is a fixed point of it. A run
can carry tangents (the variational equations): exact and free clear of the stops, the
sub-steps' RK4 in contact, and at a contact's end a correction for the move of the
located switch it began at, which its sub-steps are laid out from; they give the map's
derivative without copies.
"""

from __future__ import annotations

import cmath
import math

import numpy as np

from ...jit import JIT, njit
from ...models import hertz
from .. import hermite
from ..atomic import fetch_add
from .layout import HEAD, complex_fields, real_fields

#: Sub-steps after a touch start at substep / 2^GRADES and double up to substep: the
#: force grows as delta^1.5 from the touch, which RK4 integrates to its order only on
#: steps that shrink towards it [-].
GRADES = 4
#: A sub-step is at most this fraction of the time left to the predicted separation (the
#: force ends as delta^1.5 too: a sub-step cut there errs by where it falls in it) [-].
APPROACH = 0.5
#: Strobes kept for the settle test, and the longest orbit it looks for [periods].
SAMPLES = 16
MAX_ORBIT = 8
#: A period-p match is a longer orbit only where no divisor of p repeats within NEAR times
#: the settle tolerance [-].
NEAR = 1e3
#: Iterations of a switch's Newton search on the exact flow (safeguarded by bisection: it
#: ends when the bracket is a few rounding units) [-].
SEARCH = 80
#: Secant steps of a contact sub-step onto the switch that ends it [-].
SECANT = 3
#: Pieces per cycle of the fastest component that a contact-free step is cut into where
#: the bound on its penetration cannot rule out a touch inside it (_hidden), and the
#: deepest halving of a step [-].
PIECES = 8
DEPTH = 48
#: A touch found within this fraction of a grid step after a separation from the same
#: surface is that graze found again, not a new touch: where the motion only grazes the
#: surface (no rate into it), the separation's root lies at the touch itself, and the
#: flow from it met the touch again at once, time no longer advancing (a point of the rod's
#: 64 x 64 grid never ended) [-].
GRAZE = 1e-9
#: A component of z that has decayed below this is set to zero at the period's end (in
#: the units of the state's components). Clear of the stops a damped mode decays as
#: exp(Re lam t) (the piezo's circuit by about exp(-100) a period), and a motion that
#: stays clear of them for a few periods takes it into the subnormal numbers, whose
#: arithmetic costs about a hundred times a normal one's on x86, and a slowly decaying
#: mode stays there for hundreds of periods. Far above the subnormals (2.2e-308), so that
#: no product of a kept component with a row's coefficients reaches them, and far below
#: any state's rounding unit, so that no output moves. (A mode that decays from it past
#: them within one period spends a part of that period there, once.)
TINY = 1e-200
#: Outcome codes, as the lane engine's STATUS.
SETTLED, NOT_SETTLED, DIVERGED = 0, 1, 2
#: Kinds of switch that turn a surface's force on or off.
TOUCH, CLIP = hertz.TOUCH, hertz.CLIP
# (as numpy integers where a function is called with either and with a variable: typed as
# int64, not each as a literal, a signature of its own, compiled again callees and all)
_TOUCH, _CLIP = np.int64(TOUCH), np.int64(CLIP)
_NH = len(HEAD)
_IMPACTS, _APPROACH, _FORCE, _POWER = (HEAD.impacts, HEAD.approach_velocity,
                                       HEAD.contact_force, HEAD.power)


@njit(inline="always", **JIT)
def _dot_re(a, s, z, D):
    """Re(sum_k a[s, k] z[k])."""
    acc = 0.0
    for k in range(D):
        acc += a[s, k].real * z[k].real - a[s, k].imag * z[k].imag
    return acc


@njit(inline="always", **JIT)
def _dot_re2(a, s, tan, c, D):
    """Re(sum_k a[s, k] v[k]) of tangent c of ``tan`` (2, D, m)."""
    acc = 0.0
    for k in range(D):
        acc += a[s, k].real * tan[0, k, c] - a[s, k].imag * tan[1, k, c]
    return acc


@njit(inline="always", **JIT)
def _phasor(p, sn, cs):
    """Im(p exp(i w t)) at sin(w t) = sn, cos(w t) = cs."""
    return p.real * sn + p.imag * cs


# (_forces and _surface are compiled into their callers: a contact sub-step takes the
# forces five times and a sample that books the outputs takes both, and inlined they run
# faster there; benchmarks/results/modal_period.md)
@njit(inline="always", **JIT)
def _forces(z, t, omega, pen, pl, pen_p, gap, kh, ch, F, D, S):
    """Each surface's force F[s] [N] at (z, t)."""
    sn, cs = math.sin(omega * t), math.cos(omega * t)
    for s in range(S):
        d = _dot_re(pen, s, z, D) + _phasor(pen_p[s], sn, cs) - gap[s]
        r = _dot_re(pl, s, z, D) + omega * _phasor(pen_p[s], cs, -sn)
        F[s] = hertz.force(kh[s], d, r, ch[s])


@njit(inline="always", **JIT)
def _surface(s, z, t, omega, pen, pl, pl2, pen_p, pab, gap, F, D, S):
    """Penetration [m], rate [m/s] and its rate [m/s^2] of surface s at (z, t) with the
    forces F [N] acting."""
    sn, cs = math.sin(omega * t), math.cos(omega * t)
    p = pen_p[s]
    d = _dot_re(pen, s, z, D) + _phasor(p, sn, cs) - gap[s]
    r = _dot_re(pl, s, z, D) + omega * _phasor(p, cs, -sn)
    a = _dot_re(pl2, s, z, D) - omega * omega * _phasor(p, sn, cs)
    for q in range(S):
        a += pab[s, q] * F[q]
    return d, r, a


@njit(**JIT)
def _reach(s, z, t, omega, pen, pl, pen_p, gap, D):
    """Penetration [m] and rate [m/s] of surface s at (z, t): what the contact-free step
    looks at (its rate's own rate is not needed there)."""
    return _reach_at(s, z, math.sin(omega * t), math.cos(omega * t), omega, pen, pl, pen_p,
                     gap, D)


@njit(**JIT)
def _reach_at(s, z, sn, cs, omega, pen, pl, pen_p, gap, D):
    """_reach at the time where sin(w t) = sn, cos(w t) = cs."""
    p = pen_p[s]
    return (_dot_re(pen, s, z, D) + _phasor(p, sn, cs) - gap[s],
            _dot_re(pl, s, z, D) + omega * _phasor(p, cs, -sn))


@njit(**JIT)
def _switch(kind, s, z, t, omega, pen, pl, pl2, pen_p, pab, gap, ch, F, D, S):
    """A switching function of surface s and its rate at (z, t): the penetration [m]
    (TOUCH) or the clip's 1 + c_h r [-] (CLIP); the force is on where both are > 0."""
    d, r, a = _surface(s, z, t, omega, pen, pl, pl2, pen_p, pab, gap, F, D, S)
    if kind == TOUCH:
        return d, r
    return hertz.clip(r, ch[s]), ch[s] * a


@njit(inline="always", **JIT)
def _until(d, r, a):
    """The time [s] left to the separation predicted at a penetration d > 0 [m], its rate
    r [m/s] and acceleration a [m/s^2]: the first root of d + r tau + a tau^2 / 2, or
    2 d / -r where that parabola turns back before zero (its discriminant clipped at
    zero, so that the prediction, and the sub-steps cut by it, move continuously with the
    state); inf where the penetration does not fall."""
    q = max(r * r - 2.0 * a * d, 0.0)
    if r < 0.0:
        return 2.0 * d / (math.sqrt(q) - r)
    if a < 0.0:
        return (r + math.sqrt(q)) / -a
    return math.inf


@njit(**JIT)
def _flow(lam, z, tau, out, D):
    """out = exp(lam tau) z: the exact contact-free flow over tau [s]."""
    for k in range(D):
        out[k] = cmath.exp(lam[k] * tau) * z[k]


@njit(**JIT)
def _exps(lam, tau, e1, eh, D):
    """exp(lam tau) and exp(lam tau / 2)."""
    for k in range(D):
        e1[k] = cmath.exp(lam[k] * tau)
        eh[k] = cmath.exp(lam[k] * (0.5 * tau))


@njit(**JIT)
def _locate(kind, s, z, t0, lo, hi, omega, lam, pen, pl, pl2, pen_p, pab, gap, ch, zero,
            buf, D, S):
    """The first tau in (lo, hi] [s] where switching function ``kind`` of surface s
    (<= 0 at lo, > 0 at hi) crosses zero along the contact-free flow from z at t0:
    Newton safeguarded by bisection, ending on the side where it is > 0."""
    tau = hi
    for _ in range(SEARCH):
        _flow(lam, z, tau, buf, D)
        f, df = _switch(kind, s, buf, t0 + tau, omega, pen, pl, pl2, pen_p, pab, gap, ch,
                        zero, D, S)
        if f > 0.0:
            hi = tau
        else:
            lo = tau
        if hi - lo <= 4e-16 * (abs(t0) + hi):
            break
        nxt = tau - f / df if df != 0.0 else 0.5 * (lo + hi)
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        tau = nxt
    return hi


@njit(**JIT)
def _peak(s, z, t0, lo, hi, omega, lam, pen, pl, pl2, pen_p, pab, gap, zero, buf, D, S):
    """Where the penetration of surface s, rising at lo and falling at hi, is largest
    along the contact-free flow from z at t0, and its value: (tau [s], delta [m])."""
    for _ in range(SEARCH):
        tau = 0.5 * (lo + hi)
        _flow(lam, z, tau, buf, D)
        d, r, a = _surface(s, buf, t0 + tau, omega, pen, pl, pl2, pen_p, pab, gap, zero, D, S)
        if r > 0.0:
            lo = tau
        else:
            hi = tau
        nxt = tau - r / a if a < 0.0 else tau
        if lo < nxt < hi:  # a Newton step inside the bracket: take it, then bisect again
            _flow(lam, z, nxt, buf, D)
            d2, r2, a2 = _surface(s, buf, t0 + nxt, omega, pen, pl, pl2, pen_p, pab, gap,
                                  zero, D, S)
            if r2 > 0.0:
                lo = nxt
            else:
                hi = nxt
            if abs(r2) * (hi - lo) <= 1e-15 * abs(d2) + 1e-300 or hi - lo <= 4e-16 * hi:
                return nxt, d2
        if hi - lo <= 4e-16 * (abs(t0) + hi):
            break
    _flow(lam, z, hi, buf, D)
    d, r, a = _surface(s, buf, t0 + hi, omega, pen, pl, pl2, pen_p, pab, gap, zero, D, S)
    return hi, d


@njit(inline="always", **JIT)
def _rise(s, z, tau, omega, lam, pen, pen_p, D):
    """The most the penetration of surface s can rise above its chord over a contact-free
    span of tau [s] from z at its start: a component Re(a e^{lam t}) (|e^{lam t}| <= 1)
    departs from its chord by at most |a| min(|lam|^2 tau^2 / 8, 2), the particular
    solution's by |pen_p| omega^2 tau^2 / 8."""
    q = 0.125 * tau * tau
    acc = abs(pen_p[s]) * omega * omega * q
    for k in range(D):
        acc += abs(pen[s, k]) * min(abs(lam[k]) ** 2 * q, 2.0) * abs(z[k])
    return acc


@njit(**JIT)
def _inside(s, z, t0, tau, omega, lam, pen, pl, pen_p, gap, buf, D):
    """Whether surface s penetrates (> 0) at tau [s] along the contact-free flow from z at
    t0."""
    _flow(lam, z, tau, buf, D)
    d, r = _reach(s, buf, t0 + tau, omega, pen, pl, pen_p, gap, D)
    return d > 0.0


@njit(**JIT)
def _leave(s, z, t0, lo, hi, c_lo, omega, lam, pen, pl, pen_p, gap, ch, buf, D):
    """The last tau in [lo, hi) [s] where surface s, penetrating at lo and not at hi,
    still penetrates along the contact-free flow from z at t0 (bisection to a few
    rounding units), and the clip 1 + c_h r [-] there (c_lo at lo)."""
    c = c_lo
    for _ in range(SEARCH):
        tau = 0.5 * (lo + hi)
        _flow(lam, z, tau, buf, D)
        d, r = _reach(s, buf, t0 + tau, omega, pen, pl, pen_p, gap, D)
        if d > 0.0:
            lo, c = tau, hertz.clip(r, ch[s])
        else:
            hi = tau
        if hi - lo <= 4e-16 * (abs(t0) + hi):
            break
    return lo, c


@njit(**JIT)
def _hidden(s, z, t0, tau, limit, d0, r0, c0, d1, r1, c1, omega, lam, pen, pl, pl2, pen_p,
            pab, gap, ch, zero, buf, stack, D, S):
    """The first entry of surface s into contact (penetration and clip both > 0) inside a
    contact-free step of tau [s] from z at t0 that the step's ends do not show: a rod
    ringing faster than the grid can touch and leave within one step.

    The step is halved where the bound on the penetration (the larger end value plus
    _rise over the piece) does not rule out a touch, down to pieces of
    1 / PIECES of a cycle of the fastest component, where the step's own rules apply:
    contact at a piece's end, or a rise and fall whose maximum (_peak) is above zero.
    After a clip, a piece the surface leaves is searched for the clip's return above
    zero before it does. Pieces are visited in time order; from the one that reaches
    ``limit`` [s] on they are left (a touch the step's rules found there stands).
    Returns (tau of the entry [s], kind), tau = -1 for none. ``stack`` (DEPTH, 8): room."""
    fast = 0.0
    for k in range(D):
        if pen[s, k] * z[k] != 0.0:
            fast = max(fast, abs(lam[k]))
    leaf = 2.0 * math.pi / (PIECES * fast) if fast > 0.0 else tau
    stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = 0.0, d0, r0, c0
    stack[0, 4], stack[0, 5], stack[0, 6], stack[0, 7] = tau, d1, r1, c1
    n = 1
    while n > 0:
        n -= 1
        a, da, ra, ca = stack[n, 0], stack[n, 1], stack[n, 2], stack[n, 3]
        b, db, rb, cb = stack[n, 4], stack[n, 5], stack[n, 6], stack[n, 7]
        if a >= limit:
            return -1.0, TOUCH
        if max(da, db) + _rise(s, z, b - a, omega, lam, pen, pen_p, D) <= 0.0:
            continue
        if b - a <= leaf or n + 2 > stack.shape[0]:
            if b >= limit:
                return -1.0, TOUCH
            if db > 0.0 and cb > 0.0:
                if da <= 0.0:
                    return _locate(_TOUCH, s, z, t0, a, b, omega, lam, pen, pl, pl2, pen_p,
                                   pab, gap, ch, zero, buf, D, S), TOUCH
                tc = _locate(_CLIP, s, z, t0, a, b, omega, lam, pen, pl, pl2, pen_p, pab, gap,
                             ch, zero, buf, D, S)
                if _inside(s, z, t0, tc, omega, lam, pen, pl, pen_p, gap, buf, D):
                    return tc, CLIP
                # out and back in between: the touch after the clip's crossing
                return _locate(_TOUCH, s, z, t0, tc, b, omega, lam, pen, pl, pl2, pen_p, pab,
                               gap, ch, zero, buf, D, S), TOUCH
            if da <= 0.0 and db <= 0.0 and ra > 0.0 and rb < 0.0:
                tm, dm = _peak(s, z, t0, a, b, omega, lam, pen, pl, pl2, pen_p, pab, gap,
                               zero, buf, D, S)
                if dm > 0.0:
                    return _locate(_TOUCH, s, z, t0, a, tm, omega, lam, pen, pl, pl2, pen_p,
                                   pab, gap, ch, zero, buf, D, S), TOUCH
            if da > 0.0 and ca <= 0.0 and db <= 0.0:
                # off at the clip, out by the piece's end: the clip may come back above
                # zero while the surface still penetrates
                td, cd = _leave(s, z, t0, a, b, ca, omega, lam, pen, pl, pen_p, gap, ch, buf,
                                D)
                if cd > 0.0:
                    tc = _locate(_CLIP, s, z, t0, a, td, omega, lam, pen, pl, pl2, pen_p, pab,
                                 gap, ch, zero, buf, D, S)
                    if _inside(s, z, t0, tc, omega, lam, pen, pl, pen_p, gap, buf, D):
                        return tc, CLIP
            continue
        m = 0.5 * (a + b)
        _flow(lam, z, m, buf, D)
        dm, rm = _reach(s, buf, t0 + m, omega, pen, pl, pen_p, gap, D)
        cm = hertz.clip(rm, ch[s])
        stack[n, 0], stack[n, 1], stack[n, 2], stack[n, 3] = m, dm, rm, cm
        stack[n, 4], stack[n, 5], stack[n, 6], stack[n, 7] = b, db, rb, cb
        stack[n + 1, 0], stack[n + 1, 1], stack[n + 1, 2], stack[n + 1, 3] = a, da, ra, ca
        stack[n + 1, 4], stack[n + 1, 5], stack[n + 1, 6], stack[n + 1, 7] = m, dm, rm, cm
        n += 2
    return -1.0, TOUCH


@njit(**JIT)
def _lawson(z, t, tau, e1, eh, out, omega, pen, pl, pen_p, inp, gap, kh, ch, F, w2, w3, w4,
            stages, D, S):
    """One integrating-factor RK4 step of length tau [s] from z at t into out (e1, eh:
    exp(lam tau), exp(lam tau / 2)); F holds the forces [N] at the step's end; ``stages``
    (3, S) is room for the first three stages' forces."""
    hh, h6 = 0.5 * tau, tau / 6.0
    f1, f2, f3 = stages[0], stages[1], stages[2]
    _forces(z, t, omega, pen, pl, pen_p, gap, kh, ch, f1, D, S)
    for k in range(D):
        g = 0j
        for s in range(S):
            g += inp[s, k] * f1[s]
        w2[k] = eh[k] * (z[k] + hh * g)
        out[k] = e1[k] * (z[k] + h6 * g)
    _forces(w2, t + hh, omega, pen, pl, pen_p, gap, kh, ch, f2, D, S)
    for k in range(D):
        g = 0j
        for s in range(S):
            g += inp[s, k] * f2[s]
        w3[k] = eh[k] * z[k] + hh * g
    _forces(w3, t + hh, omega, pen, pl, pen_p, gap, kh, ch, f3, D, S)
    for k in range(D):
        g2, g3 = 0j, 0j
        for s in range(S):
            g2 += inp[s, k] * f2[s]
            g3 += inp[s, k] * f3[s]
        w4[k] = e1[k] * z[k] + tau * eh[k] * g3
        out[k] += 2.0 * h6 * eh[k] * (g2 + g3)
    _forces(w4, t + tau, omega, pen, pl, pen_p, gap, kh, ch, F, D, S)
    for k in range(D):
        g = 0j
        for s in range(S):
            g += inp[s, k] * F[s]
        out[k] += h6 * g
    _forces(out, t + tau, omega, pen, pl, pen_p, gap, kh, ch, F, D, S)


@njit(**JIT)
def _carry(lam, tan, tau, D):
    """The tangents ``tan`` (2, D, m: real and imaginary parts, component by tangent)
    carried along tau [s] of the exact contact-free flow: exp(lam tau) each component."""
    if tau != 0.0:
        tr, ti = tan[0], tan[1]
        for k in range(D):
            e = cmath.exp(lam[k] * tau)
            er, ei = e.real, e.imag
            for c in range(tr.shape[1]):
                a, b = tr[k, c], ti[k, c]
                tr[k, c], ti[k, c] = er * a - ei * b, er * b + ei * a


# (_pushed is compiled once, not inlined into each of its four calls a sub-step: inlined,
# the modal engine's compile took 70 % longer)
@njit(**JIT)
def _pushed(sd, sr, xd, xr, pen, pl, inp, v, g, df, D, S):
    """g (2, D, m) = sum_s inp_s dF_s: how the forces' change along each tangent of v
    (2, D, m) drives z, dF_s = sd_s (Re(pen_s v) + xd_s) + sr_s (Re(pl_s v) + xr_s) (into
    df (S, m)); xd, xr (S,): the penetrations' and rates' own change, 0 but for the shift
    of a contact's start (_lawson_tangents). The loops run along the tangents, which lie
    next to each other, so that they vectorize."""
    m = v.shape[2]
    for s in range(S):
        for c in range(m):
            df[s, c] = sd[s] * xd[s] + sr[s] * xr[s]
        if sd[s] != 0.0 or sr[s] != 0.0:
            for k in range(D):
                a = sd[s] * pen[s, k].real + sr[s] * pl[s, k].real
                b = sd[s] * pen[s, k].imag + sr[s] * pl[s, k].imag
                for c in range(m):
                    df[s, c] += a * v[0, k, c] - b * v[1, k, c]
    for k in range(D):
        for c in range(m):
            g[0, k, c] = 0.0
            g[1, k, c] = 0.0
        for s in range(S):
            ar, ai = inp[s, k].real, inp[s, k].imag
            for c in range(m):
                g[0, k, c] += ar * df[s, c]
                g[1, k, c] += ai * df[s, c]


@njit(inline="always", **JIT)
def _axpy(e, x, h, y, out, k, m):
    """out[:, k] = e_k (x[:, k] + h y[:, k]) for complex e_k, over the m tangents."""
    er, ei = e.real, e.imag
    for c in range(m):
        a = x[0, k, c] + h * y[0, k, c]
        b = x[1, k, c] + h * y[1, k, c]
        out[0, k, c], out[1, k, c] = er * a - ei * b, er * b + ei * a


@njit(**JIT)
def _stage_slopes(z, w2, w3, w4, t, tau, omega, pen, pl, pen_p, gap, kh, ch, slope, timing,
                  D, S):
    """What the tangents take along _lawson's step of length tau [s] from z at t, whose
    stages it left in w2, w3, w4, into ``slope`` (16, S): each surface's dF/d delta [N/m]
    and dF/d rate [N s/m] at the four stages (rows 0-7, in pairs); with ``timing``, the
    rates [m/s] and their rates [m/s^2] at which its penetration and rate change with t
    alone, the state held (the forcing's linear steady state), at t, t + tau/2 and t + tau
    (rows 8-13). Rows 14 and 15 stay 0: those of a tangent that is not a shift in time."""
    for i in range(3):
        ti = t + 0.5 * i * tau
        sn, cs = math.sin(omega * ti), math.cos(omega * ti)
        for q in range(2 if i == 1 else 1):  # (stages 2 and 3 share t + tau/2)
            w = z if i == 0 else (w4 if i == 2 else (w2 if q == 0 else w3))
            row = 0 if i == 0 else (6 if i == 2 else 2 + 2 * q)
            for s in range(S):
                d = _dot_re(pen, s, w, D) + _phasor(pen_p[s], sn, cs) - gap[s]
                r = _dot_re(pl, s, w, D) + omega * _phasor(pen_p[s], cs, -sn)
                slope[row, s], slope[row + 1, s] = hertz.slopes(kh[s], d, r, ch[s])
        if timing:
            for s in range(S):
                slope[8 + 2 * i, s] = omega * _phasor(pen_p[s], cs, -sn)
                slope[9 + 2 * i, s] = -omega * omega * _phasor(pen_p[s], sn, cs)


@njit(**JIT)
def _lawson_tangents(tan, tau, e1, eh, slope, x, pen, pl, inp, work, df, D, S):
    """The tangents ``tan`` (2, D, m) carried along _lawson's step of length tau [s] (e1,
    eh: exp(lam tau), exp(lam tau / 2)), its stages' slopes in ``slope`` (_stage_slopes):
    the same RK4 on the variational equations, so that the tangents are the derivative of
    the step with its lengths held. ``x``: the first of the rows of the explicit rates, 8
    for the state's change by a shift of the step's start time (the stages' explicit
    times move too), 14 (zeros) for the others. ``work`` (4, 2, D, m) and ``df`` (S, m)
    are room."""
    m = tan.shape[2]
    hh, h6 = 0.5 * tau, tau / 6.0
    # (the explicit rates at t, t + tau/2 and t + tau; the same zero rows where x = 14)
    x0, x1, x2 = x, x + 2 * (x < 14), x + 4 * (x < 14)
    g, u, g2, o = work[0], work[1], work[2], work[3]
    _pushed(slope[0], slope[1], slope[x0], slope[x0 + 1], pen, pl, inp, tan, g, df, D, S)
    for k in range(D):
        _axpy(eh[k], tan, hh, g, u, k, m)
        _axpy(e1[k], tan, h6, g, o, k, m)
    _pushed(slope[2], slope[3], slope[x1], slope[x1 + 1], pen, pl, inp, u, g2, df, D, S)
    for k in range(D):
        _axpy(eh[k], tan, 0.0, g, u, k, m)
        for c in range(m):
            u[0, k, c] += hh * g2[0, k, c]
            u[1, k, c] += hh * g2[1, k, c]
    _pushed(slope[4], slope[5], slope[x1], slope[x1 + 1], pen, pl, inp, u, g, df, D, S)
    for k in range(D):
        _axpy(eh[k], g, 0.0, g, u, k, m)  # (eh g3, times tau below)
        er, ei = e1[k].real, e1[k].imag
        for c in range(m):
            a, b = tan[0, k, c], tan[1, k, c]
            u[0, k, c] = er * a - ei * b + tau * u[0, k, c]
            u[1, k, c] = er * b + ei * a + tau * u[1, k, c]
        _axpy(2.0 * h6 * eh[k], g2, 1.0, g, g2, k, m)  # (2 h6 eh (g2 + g3), into g2)
        for c in range(m):
            o[0, k, c] += g2[0, k, c]
            o[1, k, c] += g2[1, k, c]
    _pushed(slope[6], slope[7], slope[x2], slope[x2 + 1], pen, pl, inp, u, g, df, D, S)
    for k in range(D):
        for c in range(m):
            tan[0, k, c] = o[0, k, c] + h6 * g[0, k, c]
            tan[1, k, c] = o[1, k, c] + h6 * g[1, k, c]


@njit(**JIT)
def _step_tangents(z, w2, w3, w4, t, tau, e1, eh, tan, shifted, timing, omega, pen, pl,
                   pen_p, inp, gap, kh, ch, slope, work, df, shift_work, shift_df, D, S):
    """The tangents ``tan`` along _lawson's step (_lawson_tangents), and with ``timing``
    the state's change by a shift of the contact's start, ``shifted`` (2, D, 1), too; the
    stages' slopes taken once for both."""
    _stage_slopes(z, w2, w3, w4, t, tau, omega, pen, pl, pen_p, gap, kh, ch, slope, timing,
                  D, S)
    _lawson_tangents(tan, tau, e1, eh, slope, np.int64(14), pen, pl, inp, work, df, D, S)
    if timing:
        _lawson_tangents(shifted, tau, e1, eh, slope, np.int64(8), pen, pl, inp, shift_work,
                         shift_df, D, S)


@njit(**JIT)
def _moves(s, kind, z, t, lam, tan, moves, shifted, omega, pen, pl, pl2, pen_p, pab, gap,
           zero, D, S):
    """At a contact's start at a located switch of ``kind`` on surface s, at (z, t): each
    tangent's move of the switch [s] into ``moves`` (its switching function's change over
    that function's rate), and the state's change by a shift of the switch, the flow's
    vector field there, into ``shifted`` (2, D, 1)."""
    d, r, a = _surface(s, z, t, omega, pen, pl, pl2, pen_p, pab, gap, zero, D, S)
    for c in range(tan.shape[2]):
        if kind == TOUCH:
            moves[c] = -_dot_re2(pen, s, tan, c, D) / r
        else:
            moves[c] = -_dot_re2(pl, s, tan, c, D) / a
    for k in range(D):
        v = lam[k] * z[k]
        shifted[0, k, 0], shifted[1, k, 0] = v.real, v.imag


@njit(**JIT)
def _shift(lam, z, shifted, tan, moves, inp, F, D, S):
    """The tangents ``tan`` (2, D, m) corrected, at the end of a contact that began at a
    located switch, for that switch's move: each tangent c moved it by ``moves[c]`` [s],
    and the contact's sub-steps, laid out from it, moved with it. ``shifted`` (2, D, 1):
    the derivative of the state z at the contact's end by that shift, against which the
    flow that takes over (its vector field at z, with the forces F [N] where the end is
    a fixed time) has moved by the same shift. Where the flow is exact the two agree: the
    force switches on and off continuously. The sub-steps do not integrate the force's
    root at the switch to their order, and the correction is what makes the tangents the
    derivative of the engine's own map."""
    for k in range(D):
        f = lam[k] * z[k]
        for s in range(S):
            f += inp[s, k] * F[s]
        br, bi = shifted[0, k, 0] - f.real, shifted[1, k, 0] - f.imag
        for c in range(tan.shape[2]):
            tan[0, k, c] += br * moves[c]
            tan[1, k, c] += bi * moves[c]


@njit(**JIT)
def _lag(y, ring, n, p, scale, D):
    """The largest difference between strobe y (period n) and the strobe p periods before
    it in the ring, in units of each component's scale."""
    worst = 0.0
    for a in range(D):
        worst = max(worst, abs(y[a] - ring[(n - p) % SAMPLES, a]) / scale[a])
    return worst


@njit(**JIT)
def _sample(z, t, t_abs, book, acc, rec, nrec, prev, o_prev, do_prev, F, omega, pen, pl, pl2,
            pen_p, pab, gap, kh, ch, out, outl, out_p, out_f, volt, D, S, K):
    """A sample of the motion at (z, t [s] in the period; t_abs [s] from the start):
    ``book``: the outputs' extrema (with the Hermite interpolant's inside the interval
    since the previous sample, ``prev``, o_prev, do_prev: updated), int V^2 dt, the force's
    peak; ``nrec`` >= 0: a row of ``rec``. Returns the next row of ``rec``."""
    _forces(z, t, omega, pen, pl, pen_p, gap, kh, ch, F, D, S)
    sn, cs = math.sin(omega * t), math.cos(omega * t)
    Fsum, dFsum = 0.0, 0.0
    for s in range(S):
        Fsum += F[s]
        if F[s] > 0.0:
            d, r, a = _surface(s, z, t, omega, pen, pl, pl2, pen_p, pab, gap, F, D, S)
            # dF/dt of the law k d^1.5 (1 + c r): the rate the peak's Hermite interpolant
            # needs
            sq = math.sqrt(d)
            dFsum += kh[s] * (1.5 * sq * r * hertz.clip(r, ch[s]) + d * sq * ch[s] * a)
    hs = t - prev[0]
    inside = book and hs > 0.0
    for o in range(K):
        oo = _dot_re(out, o, z, D) + _phasor(out_p[o], sn, cs)
        do = _dot_re(outl, o, z, D) + omega * _phasor(out_p[o], cs, -sn)
        for s in range(S):
            do += out_f[o, s] * F[s]
        if book:
            if inside and do_prev[o] * do <= 0.0:
                e = hermite.extremum(o_prev[o], do_prev[o], oo, do, hs)
                acc[_NH + o] = max(acc[_NH + o], e)
                acc[_NH + K + o] = min(acc[_NH + K + o], e)
            if inside and o == volt:
                acc[_POWER] += hermite.v2_integral(o_prev[o], do_prev[o], oo, do, 0.5 * hs,
                                                   hs * hs / 6.0)
            acc[_NH + o] = max(acc[_NH + o], oo)
            acc[_NH + K + o] = min(acc[_NH + K + o], oo)
        if 0 <= nrec < rec.shape[0]:
            rec[nrec, 1 + S + o] = oo
        o_prev[o], do_prev[o] = oo, do
    if book:
        if inside and prev[2] > 0.0 > dFsum:
            acc[_FORCE] = max(acc[_FORCE], hermite.extremum(prev[1], prev[2], Fsum, dFsum, hs))
        acc[_FORCE] = max(acc[_FORCE], Fsum)
    prev[0], prev[1], prev[2] = t, Fsum, dFsum
    if 0 <= nrec < rec.shape[0]:
        rec[nrec, 0] = t_abs
        for s in range(S):
            rec[nrec, 1 + s] = F[s]
        nrec += 1
    return nrec


@njit(**JIT)
def _advance(z, st, periods, book, rec, nrec, omega, T, steps, substep, lam, grid, pen, pl, pl2,
             pen_p, pab, inp, gap, kh, ch, out, outl, out_p, out_f, volt, strobe, y_p,
             scale, settle, limit, ring, acc, tan, D, S, K):
    """Run ``periods`` forcing periods from z (modified) in the contact state ``st`` =
    (mode, surface, grade, periods run before) (modified), at ``steps`` grid steps per
    period T [s].

    ``settle`` > 0: stop at the first period whose strobe repeats one of the last
    MAX_ORBIT within ``settle`` times each component's scale. ``book``: accumulate into
    ``acc`` (the head's sums, then K maxima, K minima). ``nrec`` >= 0: record each sample
    into ``rec`` (time, forces, outputs) from row nrec on. ``tan`` (2, D, m): m tangents
    (changes of z: real and imaginary parts, component by tangent) carried along (modified;
    m = 0: none) by the variational equations: exact clear of the stops (one product per
    component and tangent for each stretch between contacts), the sub-steps' RK4 inside
    them, and at the end of a contact that began at a located switch the correction for
    that switch's move (_shift). Returns (orbit period p, 0 for none; status; periods run;
    rows recorded)."""
    h = T / steps
    F = np.zeros(S)
    zero = np.zeros(S)
    buf, zn = np.empty(D, np.complex128), np.empty(D, np.complex128)
    w2, w3, w4 = (np.empty(D, np.complex128), np.empty(D, np.complex128),
                  np.empty(D, np.complex128))
    e1, eh = np.empty(D, np.complex128), np.empty(D, np.complex128)
    stages = np.empty((3, S))
    tangents = tan.shape[2] > 0
    # (room for the tangents' steps, empty where there are none)
    m, m1 = tan.shape[2], 1 if tangents else 0
    slope, work, df = np.zeros((16 * m1, S)), np.empty((4, 2, D, m)), np.empty((S, m))
    # the shift of a contact's start at a located switch (_shift): each tangent's move of
    # it [s], the state's derivative by it, and whether a contact carries one
    moves, shifted = np.zeros(m), np.zeros((2, D, m1))
    shift_work, shift_df = np.empty((4, 2, D, m1)), np.empty((S, m1))
    timing = False
    t_tan = 0.0  # the time in the period the tangents have been carried to [s]
    # the bound on a surface's rise above its chord over a grid step, taken once per
    # contact-free stretch (|z_k| only decays along it): where it cannot rule out a touch,
    # the step is searched in pieces (_hidden)
    slack = np.empty(S)
    fresh = True
    stack = np.empty((DEPTH, 8))
    # sin(w t) and cos(w t) at the grid's times j h (the last: T), where every step clear of
    # the stops ends; as each step computed them
    sins, coss = np.empty(steps + 1), np.empty(steps + 1)
    for jj in range(steps + 1):
        tj = T if jj >= steps else jj * h
        sins[jj], coss[jj] = math.sin(omega * tj), math.cos(omega * tj)
    # each surface's penetration and rate at the last contact-free step's end
    end_d, end_r = np.empty(S), np.empty(S)
    sub1 = np.empty((GRADES + 1, D), np.complex128)
    subh = np.empty((GRADES + 1, D), np.complex128)
    for g in range(GRADES + 1):
        _exps(lam, substep * 0.5 ** (GRADES - g), e1, eh, D)
        sub1[g], subh[g] = e1, eh
    o_prev = np.empty(K)
    do_prev = np.empty(K)
    y = np.empty(D)
    prev = np.zeros(3)  # the last sample's time [s], force [N] and its rate [N/s]
    mode, act, grade = st[0], st[1], st[2]
    override = -1  # the kind of switch just crossed off (its function counts as <= 0)
    # how the present contact began, and whether it has taken a sub-step: a contact that
    # began where the damping law's clip let the force back on (the surface still in) and
    # would end at the clip within its first sub-step steps through that clip instead (the
    # force is continuous across it). Where the motion hugs the clip, each side's flow
    # pushing towards it, locating every crossing went on forever in steps of 1e-10 s.
    entered, stepped = TOUCH, True
    # the time left to the predicted separation of the surface in contact [s] (_until at
    # the present state)
    near = math.inf
    if mode == 1:
        _forces(z, 0.0, omega, pen, pl, pen_p, gap, kh, ch, F, D, S)
        d1, r1, a1 = _surface(act, z, 0.0, omega, pen, pl, pl2, pen_p, pab, gap, F, D, S)
        near = _until(d1, r1, a1) if d1 > 0.0 else math.inf
    status, p_found, run = SETTLED, 0, 0
    if book or nrec >= 0:  # the start is the first sample
        # (book and nrec as typed values: one compile of _sample, not one for each of
        # _advance's literals)
        nrec = _sample(z, 0.0, st[3] * T, np.bool_(book), acc, rec, np.int64(nrec), prev,
                       o_prev, do_prev, F, omega, pen, pl, pl2, pen_p, pab, gap, kh, ch, out,
                       outl, out_p, out_f, volt, D, S, K)
    blown = False  # a contact sub-step's state not finite
    for period in range(periods):
        t, j, on_grid = 0.0, 0, True
        while True:
            sample = False
            if mode == 0:  # ---- contact-free: exact flow to the next grid time
                jn = j + 1 if on_grid else int(t / h) + 1
                target = T if jn >= steps else jn * h
                jt = min(jn, steps)  # (target's row of sins, coss)
                tau = target - t
                if on_grid:
                    for k in range(D):
                        zn[k] = grid[k] * z[k]
                else:
                    _flow(lam, z, tau, zn, D)
                if fresh:
                    for s in range(S):
                        slack[s] = _rise(s, z, h, omega, lam, pen, pen_p, D)
                    fresh = False
                best, bkind, bs = tau, 0, -1
                for s in range(S):
                    if on_grid and j > 0:  # (a whole step's end: z and t as it left them)
                        d0, r0 = end_d[s], end_r[s]
                    else:
                        d0, r0 = _reach(s, z, t, omega, pen, pl, pen_p, gap, D)
                    d1, r1 = _reach_at(s, zn, sins[jt], coss[jt], omega, pen, pl, pen_p, gap,
                                       D)
                    end_d[s], end_r[s] = d1, r1
                    c0, c1 = hertz.clip(r0, ch[s]), hertz.clip(r1, ch[s])
                    if override == TOUCH:
                        d0 = min(d0, 0.0)
                    elif override == CLIP:
                        c0 = min(c0, 0.0)
                    # a touch of the surface just left, within GRAZE of the separation, is
                    # the same graze found again: not taken
                    floor = GRAZE * h if override == TOUCH and s == act else -1.0
                    mine = math.inf  # this surface's touch by the step's ends
                    # (the step's bound: where it cannot reach zero, no touch lies inside
                    # the step, and neither search for one runs)
                    reachable = max(d0, d1) + slack[s] > 0.0
                    if d1 > 0.0 and c1 > 0.0:
                        kind = TOUCH if d0 <= 0.0 else CLIP
                        found = _locate(kind, s, z, t, 0.0, tau, omega, lam, pen, pl, pl2,
                                        pen_p, pab, gap, ch, zero, buf, D, S)
                        # the clip's crossing counts where the surface still penetrates:
                        # fast ringing can take it out and back within the step
                        if (kind == TOUCH and found > floor) or (kind == CLIP and _inside(
                                s, z, t, found, omega, lam, pen, pl, pen_p, gap, buf, D)):
                            mine = found
                            if found < best or bs < 0:
                                best, bkind, bs = found, kind, s
                    elif reachable and d0 <= 0.0 and d1 <= 0.0 and r0 > 0.0 and r1 < 0.0:
                        tm, dm = _peak(s, z, t, 0.0, tau, omega, lam, pen, pl, pl2, pen_p, pab,
                                       gap, zero, buf, D, S)
                        if dm > 0.0:
                            found = _locate(_TOUCH, s, z, t, 0.0, tm, omega, lam, pen, pl,
                                            pl2, pen_p, pab, gap, ch, zero, buf, D, S)
                            if found > floor:
                                mine = found
                                if found < best or bs < 0:
                                    best, bkind, bs = found, TOUCH, s
                    if reachable:  # a touch the ends may not show
                        found, kind = _hidden(s, z, t, tau, mine, d0, r0, c0, d1, r1, c1,
                                              omega, lam, pen, pl, pl2, pen_p, pab, gap, ch,
                                              zero, buf, stack, D, S)
                        if found >= 0.0 and (found < best or bs < 0) and (
                                kind != TOUCH or found > floor):
                            best, bkind, bs = found, kind, s
                override = -1
                if bs >= 0:
                    _flow(lam, z, best, zn, D)
                    z[:] = zn
                    t += best
                    if tangents:  # (each tangent's move of the switch: _shift)
                        _carry(lam, tan, t - t_tan, D)
                        t_tan = t
                        _moves(np.int64(bs), np.int64(bkind), z, t, lam, tan, moves, shifted,
                               omega, pen, pl, pl2, pen_p, pab, gap, zero, D, S)
                        timing = True
                    on_grid = False
                    mode, act, grade = 1, bs, 0 if bkind == TOUCH else GRADES
                    entered, stepped = bkind, False
                    near = math.inf
                    fresh = True
                    if book and bkind == TOUCH:
                        d, r, a = _surface(bs, z, t, omega, pen, pl, pl2, pen_p, pab, gap, zero,
                                           D, S)
                        acc[_IMPACTS] += 1.0
                        acc[_APPROACH] = max(acc[_APPROACH], r)
                    sample = True
                else:
                    z[:] = zn
                    t, j, on_grid = target, jn, True
                    sample = True
            else:  # ---- in contact: RK4 sub-steps in the frame of the flow
                if tangents:
                    _carry(lam, tan, t - t_tan, D)
                    t_tan = t
                tau = substep * 0.5 ** (GRADES - grade)
                # shrinking towards the predicted separation (APPROACH)
                cut = max(APPROACH * near, substep * 0.5 ** GRADES)
                last = t + min(tau, cut) >= T * (1.0 - 1e-14)
                cut_here = last or cut < tau
                if cut_here:
                    tau = T - t if last else cut
                    _exps(lam, tau, e1, eh, D)
                    _lawson(z, t, tau, e1, eh, zn, omega, pen, pl, pen_p, inp, gap, kh, ch, F,
                            w2, w3, w4, stages, D, S)
                else:
                    _lawson(z, t, tau, sub1[grade], subh[grade], zn, omega, pen, pl, pen_p, inp,
                            gap, kh, ch, F, w2, w3, w4, stages, D, S)
                d1, r1, a1 = _surface(act, zn, t + tau, omega, pen, pl, pl2, pen_p, pab, gap, F,
                                      D, S)
                if not (math.isfinite(d1) and math.isfinite(r1)):
                    # the sub-step blew up (a state far deeper in the surface than its
                    # sub-step resolves, as a Newton iterate can be): the run diverged.
                    # Searched on as a separation, the state's NaN sent the time to -2^48 s,
                    # and the period never ended.
                    blown = True
                    break
                c1 = hertz.clip(r1, ch[act])
                if d1 > 0.0 and (c1 > 0.0 or (entered == CLIP and not stepped)):
                    if tangents:
                        ea, eb = (e1, eh) if cut_here else (sub1[grade], subh[grade])
                        _step_tangents(z, w2, w3, w4, t, tau, ea, eb, tan, shifted,
                                       np.bool_(timing), omega, pen, pl, pen_p, inp, gap, kh,
                                       ch, slope, work, df, shift_work, shift_df, D, S)
                        if timing and last:  # (the period's end, a fixed time, ends the shift)
                            _shift(lam, zn, shifted, tan, moves, inp, F, D, S)
                            timing = False
                        t_tan = t + tau
                    z[:] = zn
                    t += tau
                    grade = min(grade + 1, GRADES)
                    stepped = True
                    near = _until(d1, r1, a1)
                    sample = True
                else:
                    kind = TOUCH if d1 <= 0.0 else CLIP
                    _forces(z, t, omega, pen, pl, pen_p, gap, kh, ch, F, D, S)
                    f0, df0 = _switch(kind, act, z, t, omega, pen, pl, pl2, pen_p, pab, gap, ch,
                                      F, D, S)
                    _forces(zn, t + tau, omega, pen, pl, pen_p, gap, kh, ch, F, D, S)
                    f1, df1 = _switch(kind, act, zn, t + tau, omega, pen, pl, pl2, pen_p, pab,
                                      gap, ch, F, D, S)
                    lo, hi, flo, fhi = 0.0, tau, f0, f1
                    ts = tau * hermite.root(f0, df0, f1, df1, tau, 0.0)
                    # (the secant's next estimate is taken at the top of the loop, so that
                    # ts stays the time of zn, the last state computed, when the loop ends)
                    for i in range(SECANT):
                        if i > 0:
                            ts = lo - flo * (hi - lo) / (fhi - flo)
                        if not (lo < ts < hi):
                            ts = 0.5 * (lo + hi)
                        _exps(lam, ts, e1, eh, D)
                        _lawson(z, t, ts, e1, eh, zn, omega, pen, pl, pen_p, inp, gap, kh, ch, F,
                                w2, w3, w4, stages, D, S)
                        fs, dfs = _switch(kind, act, zn, t + ts, omega, pen, pl, pl2, pen_p, pab,
                                          gap, ch, F, D, S)
                        if fs > 0.0:
                            lo, flo = ts, fs
                        else:
                            hi, fhi = ts, fs
                        if fs == 0.0 or hi - lo <= 4e-16 * (t + hi):
                            break
                    if not math.isfinite(fs):
                        blown = True
                        break
                    if tangents:  # (along the last sub-step the secant steps computed)
                        _step_tangents(z, w2, w3, w4, t, ts, e1, eh, tan, shifted, np.bool_(timing),
                                       omega, pen, pl, pen_p, inp, gap, kh, ch, slope, work,
                                       df, shift_work, shift_df, D, S)
                        if timing:  # (the force is off: the free flow takes over)
                            _shift(lam, zn, shifted, tan, moves, inp, zero, D, S)
                            timing = False
                        t_tan = t + ts
                    z[:] = zn
                    t += ts
                    last = False
                    mode, override = 0, kind
                    on_grid = False
                    sample = True
                if last:
                    t = T
            if sample and (book or nrec >= 0):
                nrec = _sample(z, t, (st[3] + period) * T + t, np.bool_(book), acc, rec,
                               np.int64(nrec), prev, o_prev, do_prev, F, omega, pen, pl, pl2,
                               pen_p, pab, gap, kh, ch, out, outl, out_p, out_f, volt, D, S, K)
            if t >= T:
                break
        # ---- the period's end: its strobe (the next period's samples start from it)
        if tangents:
            _carry(lam, tan, T - t_tan, D)
            t_tan = 0.0
        prev[0] = 0.0
        run += 1
        if blown:
            status = DIVERGED
            break
        for k in range(D):
            if abs(z[k].real) + abs(z[k].imag) < TINY:
                z[k] = 0j
        for a in range(D):
            v = y_p[a]
            for k in range(D):
                v += strobe[a, k].real * z[k].real - strobe[a, k].imag * z[k].imag
            y[a] = v
        finite = True
        for a in range(D):
            if not (abs(y[a]) <= limit * scale[a]):
                finite = False
        if not finite:
            status = DIVERGED
            break
        n = st[3] + period
        if settle > 0.0:
            for p in range(1, min(MAX_ORBIT, n) + 1):
                if _lag(y, ring, n, p, scale, D) <= settle:
                    # a longer orbit only where no divisor of it nearly repeats: a transient
                    # decaying with multipliers near -1 can match at lag 2 before lag 1
                    for d in range(1, p):
                        if p % d == 0 and _lag(y, ring, n, d, scale, D) <= NEAR * settle:
                            break
                    else:
                        p_found = p
                    break
        ring[n % SAMPLES] = y
        if p_found > 0:
            break
    st[0], st[1], st[2] = mode, act, grade
    st[3] += run
    return p_found, status, run, nrec




@njit(**JIT)
def _tables(c, r, D, S, K):
    """A point's tables from its complex row c and real row r (layout.COMPLEX, REAL)."""
    lam_o, grid_o, pen_o, inp_o, penp_o, out_o, outp_o, strobe_o, _ = complex_fields(D, S, K)
    (_, _, _, _, _, _, _, _, gap_o, kh_o, ch_o, outf_o, scale_o, yp_o, _) = real_fields(D, S, K)
    lam = c[lam_o:lam_o + D].copy()
    pen = c[pen_o:pen_o + S * D].copy().reshape((S, D))
    inp = c[inp_o:inp_o + S * D].copy().reshape((S, D))
    out = c[out_o:out_o + K * D].copy().reshape((K, D))
    pl, pl2 = pen * lam, pen * lam * lam
    pab = np.empty((S, S))
    for s in range(S):
        for q in range(S):
            pab[s, q] = _dot_re(pl, s, inp[q], D)
    return (lam, c[grid_o:grid_o + D].copy(), pen, pl, pl2, c[penp_o:penp_o + S].copy(), pab,
            inp, r[gap_o:gap_o + S].copy(), r[kh_o:kh_o + S].copy(), r[ch_o:ch_o + S].copy(),
            out, out * lam, c[outp_o:outp_o + K].copy(),
            r[outf_o:outf_o + K * S].copy().reshape((K, S)),
            c[strobe_o:strobe_o + D * D].copy().reshape((D, D)), r[yp_o:yp_o + D].copy(),
            r[scale_o:scale_o + D].copy())


@njit(**JIT)
def _start(z, omega, pen, pen_p, pl, gap, ch, D, S):
    """The contact state (mode, surface, grade, periods run) of a start z at phase 0: in
    contact where a surface pushes."""
    st = np.zeros(4, np.int64)
    for s in range(S):
        d = _dot_re(pen, s, z, D) + _phasor(pen_p[s], 0.0, 1.0) - gap[s]
        rt = _dot_re(pl, s, z, D) + omega * _phasor(pen_p[s], 1.0, 0.0)
        if hertz.pushes(d, rt, ch[s]):
            st[0], st[1], st[2] = 1, s, GRADES
    return st


@njit(**JIT)
def run_point(c, r, z, metrics, ring, D, S, K):
    """One point from z (its eigen-coordinates, replaced by its end) to steady state, then
    its orbit measured: metrics (layout.HEAD, then each output's largest and smallest
    value), ring the last SAMPLES strobes (oldest first)."""
    tables = _tables(c, r, D, S, K)
    (lam, grid, pen, pl, pl2, pen_p, pab, inp, gap, kh, ch, out, outl, out_p, out_f, strobe,
     y_p, scale) = tables
    omega, steps, substep = r[0], int(r[1]), r[2]
    max_periods, settle, limit = int(r[3]), r[4], r[5]
    T = 2.0 * math.pi / omega
    st = _start(z, omega, pen, pen_p, pl, gap, ch, D, S)
    rec = np.empty((0, 1))
    buf = np.zeros((SAMPLES, D))
    acc = np.zeros(metrics.shape[0])
    p, status, run, _ = _advance(z, st, max_periods, False, rec, -1, omega, T, steps, substep,
                                 lam, grid, pen, pl, pl2, pen_p, pab, inp, gap, kh, ch, out,
                                 outl, out_p, out_f, int(r[7]), strobe, y_p, scale, settle,
                                 limit, buf, acc, np.empty((2, D, 0)), D, S, K)
    if status == SETTLED and p == 0:
        status = NOT_SETTLED
    _measure(tables, r, z, st, max(p, 1), status, metrics, buf, D, S, K)
    metrics[HEAD.period] = p
    n = st[3]
    for k in range(SAMPLES):
        ring[k] = buf[(n + k) % SAMPLES]


@njit(**JIT)
def _measure(tables, r, z, st, periods, status, metrics, buf, D, S, K):
    """Measure ``periods`` forcing periods from z (modified) in contact state ``st``
    (modified) into metrics (layout.HEAD, then each output's largest and smallest value);
    ``tables`` the point's (_tables), ``status`` the outcome so far (not measured where it
    is DIVERGED)."""
    (lam, grid, pen, pl, pl2, pen_p, pab, inp, gap, kh, ch, out, outl, out_p, out_f, strobe,
     y_p, scale) = tables
    omega, steps, substep, limit, R = r[0], int(r[1]), r[2], r[5], r[6]
    T = 2.0 * math.pi / omega
    acc = np.zeros(metrics.shape[0])
    acc[_NH:_NH + K] = -np.inf
    acc[_NH + K:] = np.inf
    if status != DIVERGED:
        _, status2, _, _ = _advance(z, st, periods, True, np.empty((0, 1)), -1, omega, T,
                                    steps, substep, lam, grid, pen, pl, pl2, pen_p, pab, inp,
                                    gap, kh, ch, out, outl, out_p, out_f, int(r[7]), strobe,
                                    y_p, scale, 0.0, limit, buf, acc,
                                    np.empty((2, D, 0)), D, S, K)
        if status2 == DIVERGED:
            status = DIVERGED
    metrics[:] = acc
    metrics[HEAD.status] = status
    metrics[HEAD.periods_run] = st[3]
    metrics[HEAD.period] = periods
    metrics[_IMPACTS] = acc[_IMPACTS] / periods
    span = periods * T
    metrics[_POWER] = acc[_POWER] / (R * span)
    metrics[HEAD.voltage_rms] = math.sqrt(acc[_POWER] / span)
    if acc[_IMPACTS] == 0.0:
        metrics[_APPROACH] = np.nan


#: What take_points does with each point it takes: run it to steady state and measure its
#: orbit, measure its orbit over given periods, or run its period map with tangents
#: carried along.
SETTLE, MEASURE, MAP = 0, 1, 2


@njit(nogil=True, **JIT)
def take_points(kind, crows, rrows, z, periods, metrics, strobes, tangents, ok, taken, D, S,
                K):
    """Points of one call, each taken by the calling thread from the shared counter
    ``taken[0]`` (until ``taken[1]`` is set: stop) and done as ``kind`` says: SETTLE, every
    point (complex rows (n, ...), real rows (n, ...), eigen-coordinates z (n, D), replaced by
    the end) to steady state: metrics (n, metric_size(K)), strobes (n, SAMPLES, D);
    MEASURE, its orbit measured over its ``periods[i]`` forcing periods from z (replaced by
    the end), taken to be on the orbit: metrics as SETTLE's with the status SETTLED unless
    the run diverged, strobes the last ``periods[i]`` strobes (oldest first) at the end,
    zero before them; MAP, the period map: z replaced by its state after periods[i]
    forcing periods, the tangents ``tangents[i]`` (2, D, m: changes of z, real and
    imaginary parts, component by tangent; m = 0: none) carried along (replaced: the
    map's derivative applied to them), ok[i] False where the run diverged. The arguments
    a kind does not use are any arrays of their types.

    Each point is run alone, so its numbers do not depend on the threads or the other
    points; the threads share one counter, so that one slow point does not hold back
    others. The caller starts the threads (modal_map), and one compiled entry serves the
    three kinds: a parallel loop for each kind compiled again, in each, all it calls."""
    n = crows.shape[0]
    i = fetch_add(taken, 0)
    while i < n and taken[1] == 0:
        if kind == SETTLE:
            run_point(crows[i], rrows[i], z[i], metrics[i], strobes[i], D, S, K)
        elif kind == MEASURE:
            _measure_point(crows[i], rrows[i], z[i], periods[i], metrics[i], strobes[i], D, S,
                           K)
        else:
            ok[i] = _map_point(crows[i], rrows[i], z[i], periods[i], tangents[i], D, S, K)
        i = fetch_add(taken, 0)


@njit(**JIT)
def _measure_point(c, r, z, periods, metrics, ring, D, S, K):
    """One point of take_points' MEASURE."""
    tables = _tables(c, r, D, S, K)
    pen, pl, pen_p, gap, ch = tables[2], tables[3], tables[5], tables[8], tables[10]
    st = _start(z, r[0], pen, pen_p, pl, gap, ch, D, S)
    buf = np.zeros((SAMPLES, D))
    # (SETTLED as an int64, not the literal: numba compiles _measure again for each
    # literal value)
    _measure(tables, r, z, st, periods, np.int64(SETTLED), metrics, buf, D, S, K)
    for k in range(SAMPLES):
        ring[k] = buf[(st[3] + k) % SAMPLES]


@njit(**JIT)
def record_samples(c, r, z, periods, rec, D, S, K):
    """One point from z (modified) over ``periods`` forcing periods, every sample (grid
    times, contact sub-steps, switches) into rec (rows: time [s], each surface's force
    [N], each output); returns the rows recorded (at most len(rec))."""
    (lam, grid, pen, pl, pl2, pen_p, pab, inp, gap, kh, ch, out, outl, out_p, out_f, strobe,
     y_p, scale) = _tables(c, r, D, S, K)
    omega, steps, substep = r[0], int(r[1]), r[2]
    limit, volt = r[5], int(r[7])
    T = 2.0 * math.pi / omega
    st = _start(z, omega, pen, pen_p, pl, gap, ch, D, S)
    acc = np.zeros(len(HEAD) + 2 * K)
    buf = np.zeros((SAMPLES, D))
    _, _, _, n = _advance(z, st, periods, False, rec, 0, omega, T, steps, substep, lam, grid,
                          pen, pl, pl2, pen_p, pab, inp, gap, kh, ch, out, outl, out_p, out_f,
                          volt, strobe, y_p, scale, 0.0, limit, buf, acc,
                          np.empty((2, D, 0)), D, S, K)
    return n


@njit(**JIT)
def _map_point(c, r, z, periods, tan, D, S, K):
    """One point of take_points' MAP: z (D,) replaced by its state after ``periods`` forcing
    periods, the tangents ``tan`` (2, D, m) carried along; False where the run diverged."""
    (lam, grid, pen, pl, pl2, pen_p, pab, inp, gap, kh, ch, out, outl, out_p, out_f,
     strobe, y_p, scale) = _tables(c, r, D, S, K)
    omega, steps, substep, limit, volt = r[0], int(r[1]), r[2], r[5], int(r[7])
    st = _start(z, omega, pen, pen_p, pl, gap, ch, D, S)
    acc = np.zeros(len(HEAD) + 2 * K)
    buf = np.zeros((SAMPLES, D))
    _, status, _, _ = _advance(z, st, periods, False, np.empty((0, 1)), -1, omega,
                               2.0 * math.pi / omega, steps, substep, lam, grid, pen, pl,
                               pl2, pen_p, pab, inp, gap, kh, ch, out, outl, out_p, out_f,
                               volt, strobe, y_p, scale, 0.0, limit, buf, acc, tan, D, S, K)
    return status != DIVERGED
