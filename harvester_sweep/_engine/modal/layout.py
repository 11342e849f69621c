"""The modal engine's rows, declared once from named fields whose sizes follow a model's
dimensions: D state components, S contact surfaces, K booked outputs.

A point travels as one complex row (its system in the eigen-coordinates of the linear
part) and one real row (the contact laws, the step, the budget, the settle test). The
offsets are computed by :func:`complex_fields` and :func:`real_fields` (compiled: the
kernel calls them with the dimensions it is given; Python calls the same code).
"""

from __future__ import annotations

from collections import namedtuple

from ...jit import JIT, njit

#: The complex row, in order (a field is D long unless its meaning gives its shape):
COMPLEX = (
    ("lam", "eigenvalues of the linear system [1/s]"),
    ("grid", "exp(lam h): the exact flow over one grid step"),
    ("pen", "(S, D) the surfaces' penetrations as functionals of the eigen-coordinates [m]"),
    ("inp", "(S, D) a unit force of each surface in eigen-coordinates' rates [1/(N s)]"),
    ("pen_p", "(S,) the particular solution's penetration phasor: Im(pen_p e^{i w t}) [m]"),
    ("out", "(K, D) the booked outputs as functionals of the eigen-coordinates"),
    ("out_p", "(K,) the particular solution's output phasors"),
    ("strobe", "(D, D) the state from the eigen-coordinates: y = Re(strobe z) + y_p(0)"),
)

#: The real row, in order (a field is one value unless its meaning gives its shape).
REAL = (
    ("omega", "forcing angular frequency [rad/s]"),
    ("steps", "grid steps per forcing period [-]"),
    ("substep", "RK4 sub-step in contact [s]"),
    ("max_periods", "budget of forcing periods [-]"),
    ("settle", "settle tolerance, relative to each component's scale [-]"),
    ("limit", "divergence limit, in units of each component's scale [-]"),
    ("resistance", "load resistance [Ohm]"),
    ("volt_out", "index of the voltage among the outputs [-]"),
    ("gap", "(S,) each surface's gap [m]"),
    ("kh", "(S,) each surface's Hertz stiffness [N/m^1.5]"),
    ("ch", "(S,) each surface's contact damping [s/m]"),
    ("out_f", "(K, S) each output's rate per unit force of each surface"),
    ("scale", "(D,) each state component's scale"),
    ("y_p", "(D,) the particular solution at phase 0"),
)

ComplexFields = namedtuple("ComplexFields", tuple(n for n, _ in COMPLEX) + ("size",))
RealFields = namedtuple("RealFields", tuple(n for n, _ in REAL) + ("size",))


@njit(**JIT)
def complex_fields(D, S, K):
    """Offsets of the complex row's fields (:data:`COMPLEX`) and its size."""
    lam = 0
    grid = lam + D
    pen = grid + D
    inp = pen + S * D
    pen_p = inp + S * D
    out = pen_p + S
    out_p = out + K * D
    strobe = out_p + K
    return lam, grid, pen, inp, pen_p, out, out_p, strobe, strobe + D * D


@njit(**JIT)
def real_fields(D, S, K):
    """Offsets of the real row's fields (:data:`REAL`) and its size."""
    gap = 8
    kh = gap + S
    ch = kh + S
    out_f = ch + S
    scale = out_f + K * S
    y_p = scale + D
    return 0, 1, 2, 3, 4, 5, 6, 7, gap, kh, ch, out_f, scale, y_p, y_p + D


#: The metric row: a head of scalars, then each output's largest and smallest value.
METRIC_HEAD = (
    ("status", "outcome, a code of the lane engine's STATUS [-]"),
    ("periods_run", "forcing periods run [-]"),
    ("period", "orbit period in forcing periods [-]"),
    ("impacts", "first touches per forcing period, over the orbit [-]"),
    ("approach_velocity", "largest penetration rate at a first touch [m/s]"),
    ("contact_force", "largest contact force [N]"),
    ("power", "mean power V^2/R over the orbit [W]"),
    ("voltage_rms", "root mean square voltage over the orbit [V]"),
)
Head = namedtuple("Head", tuple(n for n, _ in METRIC_HEAD))
HEAD = Head(*range(len(METRIC_HEAD)))


def metric_size(K: int) -> int:
    """Columns of a metric row with K booked outputs: the head, then K maxima, K minima."""
    return len(METRIC_HEAD) + 2 * K


#: A recorded sample of a scene: time [s], the contact force of each surface [N], then
#: the booked outputs.
RECORD_HEAD = 1
