"""The monodromy of a point's period map where its motion stays clear of the stops.

There the model is linear and so is its RK4 step (model.free_step_map): deviations of
``(x, v, V)`` are carried by the step's matrix ``I + D`` (D's first three columns), and
over ``N`` steps by its power, taken here by repeated squaring. The orbit solver uses it
as the Jacobian of Newton's first run from a motion that stayed clear of the stops.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .flags import JIT
from .layouts import PARAM
from .model import free_step_map


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
