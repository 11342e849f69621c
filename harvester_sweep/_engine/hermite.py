"""The cubic Hermite interpolant of a step: extrema, level crossings, int V^2 dt.

A step's ends and their derivatives define the cubic y0 + h d0 s + B s^2 + C s^3 on
s in [0, 1]; it is accurate to O(h^4), like the RK4 step, which is what locating a peak
or a contact switch inside a step needs.
"""

from __future__ import annotations

import math

from ..jit import JIT, njit


@njit(inline="always", **JIT)
def coefficients(y0, d0, y1, d1, h):
    """Coefficients B, C of the cubic Hermite y0 + h d0 s + B s^2 + C s^3 on s in [0, 1]."""
    return 3.0 * (y1 - y0) - h * (2.0 * d0 + d1), 2.0 * (y0 - y1) + h * (d0 + d1)


@njit(inline="always", **JIT)
def extremum(y0, d0, y1, d1, h):
    """Value of the cubic Hermite interpolant where its derivative changes sign (d0 d1 <= 0).

    The derivative h d0 + 2 B s + 3 C s^2 is a quadratic in s, solved in closed form (q,
    the sum that does not cancel; the roots c / q, which is the one at a = 0, and q / a).
    Of the two roots the one further inside [0, 1] is taken (a root at an end is one of
    the step's ends, which callers take anyway), clamped to [0, 1] (rounding can put a
    root at an end just outside)."""
    B, C = coefficients(y0, d0, y1, d1, h)
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


@njit(**JIT)
def root(y0, d0, y1, d1, h, level):
    """s in [0, 1] where the cubic Hermite interpolant crosses ``level`` (between y0 and y1)."""
    B, C = coefficients(y0, d0, y1, d1, h)
    s = (level - y0) / (y1 - y0) if y1 != y0 else 0.5
    for _ in range(4):
        dp = h * d0 + 2.0 * B * s + 3.0 * C * s * s
        if dp != 0.0:
            s = min(max(s - (y0 + h * d0 * s + B * s * s + C * s * s * s - level) / dp, 0.0), 1.0)
    return s


@njit(**JIT)
def crossing_rate(y0, d0, y1, d1, h, level):
    """Slope dy/dt of the cubic Hermite interpolant where it crosses ``level``."""
    B, C = coefficients(y0, d0, y1, d1, h)
    s = root(y0, d0, y1, d1, h, level)
    return (h * d0 + 2.0 * B * s + 3.0 * C * s * s) / h


@njit(inline="always", **JIT)
def v2_integral(V0, dV0, V1, dV1, hh, h26):
    """int V^2 dt [V^2 s] over a step of length h from the voltage [V] and its rate [V/s] at
    both ends; hh = h/2, h26 = h^2/6 [s, s^2]. The trapezoidal rule with its
    Euler-Maclaurin end correction (h^2/12 times the change of d(V^2)/dt): local error
    h^5/720 max |d^4(V^2)/dt^4|, the order of the RK4 step, and no stage values needed."""
    return hh * (V0 * V0 + V1 * V1) + h26 * (V0 * dV0 - V1 * dV1)
