"""The contact force's peak inside a step (booking.peak): the top of the quartic through the
force at three step ends and its rate at the last two, exact for data taken from a quartic,
and of RK4's order or better on a smooth pulse, where the parabola through the three
values (what the peak was before, and is still for a contact of two steps) is of lower
order."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize_scalar

from harvester_sweep._engine import booking
from harvester_sweep._engine.layouts import LANE, LANES

H = 2e-6  # step [s]


def top(fcp, fc, fcn, dfc, dfcn, h=H):
    """The peak booking.peak books for lane 0 from its samples [N] and rates [N/s]."""
    L = np.zeros(len(LANE) * LANES)
    L[LANE.fc_max] = -np.inf
    booking.peak(L, 0, fcp, fc, fcn, dfc, dfcn, h, False)
    return L[LANE.fc_max]


def samples(f, df, t0, h=H):
    """The samples of booking.peak at t0 - h, t0, t0 + h and the rates at t0, t0 + h."""
    return f(t0 - h), f(t0), f(t0 + h), df(t0), df(t0 + h)


@settings(max_examples=300, deadline=None)
@given(s0=st.floats(-0.5, 0.49), a=st.floats(0.5, 2.0), b=st.floats(0.0, 1.0),
       height=st.floats(1e-6, 1e3))
def test_the_top_of_a_quartic_is_exact(s0, a, b, height):
    """F(t) = F0 (10 - a u^2 - b u^4), u = t / H - s0, positive at the three samples: a top
    10 F0 at s0 steps from the middle sample, which is then the largest of the three. (Its
    curvature dominates, as a peak's does that lasts tens of steps: Newton from the
    parabola's vertex is then at rounding within booking.PEAK_ITERATIONS.)"""
    def f(t):
        u = t / H - s0
        return height * (10.0 - a * u * u - b * u ** 4)

    def df(t):
        u = t / H - s0
        return height * (-2.0 * a * u - 4.0 * b * u ** 3) / H

    assert abs(top(*samples(f, df, 0.0)) - 10.0 * height) <= 1e-13 * height


def pulse(t, tc):
    """A Hertz-like pulse of duration tc [s], lopsided as a damped contact's is: the force
    sin(pi t / tc)^1.5 (1 + t / (2 tc)) [N] and its rate [N/s] at t [s]."""
    w = math.pi / tc
    s, c = math.sin(w * t), math.cos(w * t)
    return s ** 1.5 * (1 + 0.5 * t / tc), 1.5 * s ** 0.5 * c * w * (1 + 0.5 * t / tc) \
        + s ** 1.5 * 0.5 / tc


@pytest.mark.parametrize("past", [0.1, 1 / 3, 0.45])
def test_a_smooth_pulse_converges_at_fourth_order_or_better(past):
    """The pulse sampled at steps of tc / n, its top ``past`` of a step after the largest
    sample: the quartic's error falls at least as h^4 (as h^5 here), the parabola's through
    the three values (the fcn = 0 fallback) as h^3, 4 to 5 orders of ten above it at 128
    steps a contact."""
    tc = 2.7e-4
    found = minimize_scalar(lambda t: -pulse(t, tc)[0], bounds=(0.3 * tc, 0.8 * tc),
                            method="bounded", options={"xatol": 1e-16})
    peak, at = -found.fun, found.x
    quartic, parabola = [], []
    for n in (16, 32, 64, 128):
        h = tc / n
        (fcp, _), (fc, dfc), (fcn, dfcn) = (pulse(at - past * h + k * h, tc) for k in (-1, 0, 1))
        quartic.append(abs(top(fcp, fc, fcn, dfc, dfcn, h) - peak))
        a, b = 0.5 * (fcp + fcn) - fc, 0.5 * (fcn - fcp)
        parabola.append(abs(fc - b * b / (4 * a) - peak))
    assert np.all(-np.diff(np.log2(quartic)) >= 4.0), quartic
    assert np.all(-np.diff(np.log2(parabola)) < 3.6), parabola
    assert quartic[-1] < parabola[-1] / 1e4
