"""A point's period map where its motion stays clear of the stops, in closed form.

There the model is linear and so is its RK4 step (tip_mass.free_step_map): deviations of
``(x, v, V)`` are carried by the step's matrix ``I + D`` (D's first three columns), and
over ``N`` steps by its power, taken here by repeated squaring (:func:`free_monodromy`).
The orbit solver uses it as the Jacobian of Newton's first run where that run is expected
to stay clear of the stops, and :func:`free_extent` (the linear motion over one period at
a coarse step) as that expectation for a motion no run has taken yet.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..jit import JIT
from ..models.tip_mass import free_step_map
from .layouts import PARAM, STATE


@njit(inline="always", **JIT)
def _product(a, b, out):
    """out = a @ b for 3 x 3 matrices (out distinct from a and b)."""
    for i in range(3):
        for j in range(3):
            out[i, j] = a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j]


@njit(**JIT)
def free_monodromy(rows, steps, periods, out):
    """Write into ``out`` (n, 3, 3) the monodromy of ``periods[i]`` periods at ``steps[i]``
    steps per period of each packed row ``rows[i]`` (layouts.PARAM), clear of the stops:
    the contact-free RK4 step's matrix to the power ``steps[i] * periods[i]``."""
    for i in range(rows.shape[0]):
        r, s = rows[i], steps[i]
        d = free_step_map(r[PARAM.period] / s, math.cos(math.pi / s), math.sin(math.pi / s),
                          r[PARAM.amplitude], r[PARAM.wn2], r[PARAM.cm], r[PARAM.thm],
                          r[PARAM.irc], r[PARAM.thc])
        step = np.eye(3) + d[:, :3]
        result, scratch = np.eye(3), np.empty((3, 3))
        power = int(s) * int(periods[i])
        while power > 0:
            if power & 1:
                _product(result, step, scratch)
                result, scratch = scratch, result
            _product(step, step, scratch)
            step, scratch = scratch, step
            power >>= 1
        out[i] = result


@njit(**JIT)
def free_extent(rows, states, steps, out):
    """Write into ``out`` (n, 2) the largest and smallest x [m] at the step ends of one
    period of each row's motion from ``states[i]`` (layouts.STATE, at the row's forcing
    phase) were it clear of the stops, at ``steps`` steps per period: whether a run from
    there will touch a stop, guessed for the cost of a few steps a point."""
    for i in range(rows.shape[0]):
        r = rows[i]
        d = free_step_map(r[PARAM.period] / steps, math.cos(math.pi / steps),
                          math.sin(math.pi / steps), r[PARAM.amplitude], r[PARAM.wn2],
                          r[PARAM.cm], r[PARAM.thm], r[PARAM.irc], r[PARAM.thc])
        c2, s2 = math.cos(2.0 * math.pi / steps), math.sin(2.0 * math.pi / steps)
        x, v, V = states[i, STATE.x], states[i, STATE.v], states[i, STATE.voltage]
        s, c = math.sin(r[PARAM.phase]), math.cos(r[PARAM.phase])
        high = low = x
        for _ in range(steps):
            dx = d[0, 0] * x + d[0, 1] * v + d[0, 2] * V + d[0, 3] * s + d[0, 4] * c
            dv = d[1, 0] * x + d[1, 1] * v + d[1, 2] * V + d[1, 3] * s + d[1, 4] * c
            de = d[2, 0] * x + d[2, 1] * v + d[2, 2] * V + d[2, 3] * s + d[2, 4] * c
            x, v, V = x + dx, v + dv, V + de
            s, c = s * c2 + c * s2, c * c2 - s * s2
            high, low = max(high, x), min(low, x)
        out[i, 0], out[i, 1] = high, low
