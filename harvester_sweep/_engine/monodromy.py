"""A point's period map where its motion stays clear of the stops, in closed form.

There the model is linear and so is its RK4 step (tip_mass.free_step_map): deviations of
the model's state are carried by the step's matrix ``I + D`` (D's first columns, one for
each component), and over ``N`` steps by its power, taken here by repeated squaring
(:func:`free_monodromy`). The state's size is the model's (:data:`SIZE`): a 3-state
model's loops are written out, any other size takes the generic ones.
The orbit solver uses it as the Jacobian of Newton's first run where that run is expected
to stay clear of the stops, and :func:`free_extent` (the linear motion over one period at
a coarse step) as that expectation for a motion no run has taken yet.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import JIT, njit
from ..models import tip_mass
from ..models.tip_mass import free_step_map
from .layouts import PARAM, STATE


@njit(inline="always", **JIT)
def _product(a, b, out):
    """out = a @ b for n x n matrices, n >= 2 (out distinct from a and b), summed in index
    order. (The first two products in one expression, as a 3 x 3 product written out has
    them: LLVM fuses one of them into the sum, and these are its bits.)"""
    n = a.shape[0]
    for i in range(n):
        for j in range(n):
            total = a[i, 0] * b[0, j] + a[i, 1] * b[1, j]
            for k in range(2, n):
                total += a[i, k] * b[k, j]
            out[i, j] = total


#: The size of the state the contact-free step carries: the model's (tip_mass.STATE). A
#: compile-time constant: numba prunes the branches of the other sizes, so that a 3-state
#: model compiles only its own loops, written out. (Compiled beside the generic loops, even
#: untaken, the 3 x 3 squarings ran far slower, and both cost compile time:
#: benchmarks/results/structure_42_final.md.)
SIZE = len(tip_mass.STATE)


@njit(inline="always", **JIT)
def _product3(a, b, out):
    """:func:`_product` of 3 x 3 matrices, written out: the same sums, so the same bits."""
    for i in range(3):
        for j in range(3):
            out[i, j] = a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j]


@njit(**JIT)
def _power(step, power, out):
    """out = step ** power of a square ``step`` (overwritten) by repeated squaring."""
    size = step.shape[0]
    result, scratch = np.eye(size), np.empty((size, size))
    while power > 0:
        if power & 1:
            _product(result, step, scratch)
            result, scratch = scratch, result
        _product(step, step, scratch)
        step, scratch = scratch, step
        power >>= 1
    out[:, :] = result


@njit(**JIT)
def free_monodromy(rows, steps, periods, out):
    """Write into ``out`` (n, D, D) the monodromy of ``periods[i]`` periods at ``steps[i]``
    steps per period of each packed row ``rows[i]`` (layouts.PARAM), clear of the stops:
    the contact-free RK4 step's matrix to the power ``steps[i] * periods[i]``."""
    for i in range(rows.shape[0]):
        r, s = rows[i], steps[i]
        d = free_step_map(r[PARAM.period] / s, math.cos(math.pi / s), math.sin(math.pi / s),
                          r[PARAM.amplitude], r[PARAM.wn2], r[PARAM.cm], r[PARAM.thm],
                          r[PARAM.irc], r[PARAM.thc])
        step = np.eye(SIZE) + d[:, :SIZE]  # (the map's columns add the forcing phase)
        power = int(s) * int(periods[i])
        if SIZE == 3:  # (the tip-mass model's, written out here: see SIZE)
            result, scratch = np.eye(3), np.empty((3, 3))
            while power > 0:
                if power & 1:
                    _product3(result, step, scratch)
                    result, scratch = scratch, result
                _product3(step, step, scratch)
                step, scratch = scratch, step
                power >>= 1
            out[i] = result
        else:
            _power(step, power, out[i])


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
        if SIZE == 3:  # (the tip-mass model's, written out here: see SIZE)
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
        else:
            out[i, 0], out[i, 1] = _extent(d, states[i, :SIZE].copy(), r[PARAM.phase], steps)


@njit(**JIT)
def _extent(d, y, phase, steps):
    """The largest and smallest x [m] of ``y`` (layouts.STATE; overwritten) at the step
    ends of ``steps`` steps of the contact-free step's increments ``d`` (its columns: the
    state, then the forcing's sin and cos), from forcing phase ``phase``."""
    c2, s2 = math.cos(2.0 * math.pi / steps), math.sin(2.0 * math.pi / steps)
    size = y.shape[0]
    dy = np.empty(size)
    s, c = math.sin(phase), math.cos(phase)
    high = low = y[STATE.x]
    for _ in range(steps):
        for row in range(size):
            total = d[row, 0] * y[0] + d[row, 1] * y[1]  # (as _product)
            for col in range(2, size):
                total += d[row, col] * y[col]
            dy[row] = total + d[row, size] * s + d[row, size + 1] * c
        for row in range(size):
            y[row] += dy[row]
        s, c = s * c2 + c * s2, c * c2 - s * s2
        high, low = max(high, y[STATE.x]), min(low, y[STATE.x])
    return high, low
