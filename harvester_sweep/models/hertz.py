"""The Hertz contact law, written once, with its clip and its switches.

A stop pressed in by ``delta`` [m] at the rate ``r`` [m/s] (d delta/dt) pushes back with::

    F_c = k_h delta^1.5 max(1 + c_h r, 0)   for delta > 0,   0 otherwise

(k_h [N/m^1.5], c_h [s/m] from a damping law of :mod:`harvester_sweep.contact`). The
force switches on or off on two surfaces: ``delta = 0`` (touch and separation) and
``1 + c_h r = 0`` (the clip: the stop pushes, never pulls). Between them it is smooth, so
that RK4 keeps its order once every switch is located inside its step. A model says how
its state makes delta and r (the tip-mass model: delta = x - g, r = x'; a stop on a
spring: the relative motion), and takes everything else from here.

The compiled functions are also read from Python through their ``py_func`` (the same
source, uncompiled): static equilibria and time scales use the same law.
"""

from __future__ import annotations

import math

from ..jit import JIT, njit

#: Kinds of switch, as the engine's switch location reports them.
TOUCH = 1  # delta = 0: touch or separation
CLIP = 2  # 1 + c_h r = 0: the force clipped at zero (no tension)


@njit(inline="always", **JIT)
def force(kh, delta, rate, ch):
    """F_c [N] (or F_c / m [m/s^2] for ``kh`` = k_h / m) at penetration ``delta`` [m] and
    rate ``rate`` [m/s]; ``kh`` 0 is no force. The square root comes last, times a factor
    computed while it runs: in an RK4 stage the chain of dependent operations is then as
    short as it can be, which is what a lone step in contact waits on."""
    d = max(delta, 0.0)
    return kh * d * max(1.0 + ch * rate, 0.0) * math.sqrt(d)


@njit(inline="always", **JIT)
def force_and_slopes(kh, delta, rate, ch):
    """:func:`force` and :func:`slopes` at once, from one square root."""
    d = max(delta, 0.0)
    c = max(1.0 + ch * rate, 0.0)
    root = math.sqrt(d)
    return kh * d * c * root, 1.5 * kh * root * c, (kh * d * root * ch if c > 0.0 else 0.0)


@njit(inline="always", **JIT)
def slopes(kh, delta, rate, ch):
    """The derivatives of :func:`force` by ``delta`` [N/m] and by ``rate`` [N s/m] (per
    unit mass for ``kh`` = k_h / m), 0 where the force is off: what the variational
    equations of a motion in contact take."""
    _, by_delta, by_rate = force_and_slopes(kh, delta, rate, ch)
    return by_delta, by_rate


@njit(inline="always", **JIT)
def clip(rate, ch):
    """1 + c_h r [-]: the clip's surface, positive where the stop can push."""
    return 1.0 + ch * rate


@njit(inline="always", **JIT)
def clip_rate(ch):
    """The rate r [m/s] on the clip's surface (1 + c_h r = 0), for c_h != 0 [s/m]."""
    return -1.0 / ch


@njit(inline="always", **JIT)
def pushes(delta, rate, ch):
    """Whether the stop pushes at penetration ``delta`` [m] and rate ``rate`` [m/s]: past
    both surfaces."""
    return (delta > 0.0) & (clip(rate, ch) > 0.0)


def stiffness(kh: float, delta: float) -> float:
    """dF_c/d delta [N/m] of the undamped law at penetration ``delta`` >= 0 [m]: the
    spring the contact is, linearised there (k_h [N/m^1.5])."""
    return 1.5 * kh * math.sqrt(delta)


def penetration(energy: float, kh: float) -> float:
    """The penetration [m] at which the undamped law has stored ``energy`` [J],
    ``2/5 k_h delta^2.5`` (k_h [N/m^1.5] > 0)."""
    return (2.5 * energy / kh) ** 0.4


def static_force(kh: float, delta: float) -> float:
    """F_c [N] at rest, pressed in by ``delta`` [m] (k_h [N/m^1.5])."""
    return force.py_func(kh, delta, 0.0, 0.0)
