"""The cubic Hermite interpolant's extremum, which places x_max, x_min and v_peak inside a
step: exact for data taken from a cubic (the interpolant is then that cubic)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from harvester_sweep._engine import hermite

H = 1e-4  # step [s]


def _extremum(t1, t2, p3, p0):
    """Hermite data on [0, H] of y(t) = p0 + p3 (t^3 / 3 - (t1 + t2) t^2 / 2 + t1 t2 t),
    whose derivative p3 (t - t1) (t - t2) changes sign at t1 only, and y(t1)."""
    def y(t):
        return p0 + p3 * (t ** 3 / 3 - (t1 + t2) * t ** 2 / 2 + t1 * t2 * t)

    def dy(t):
        return p3 * (t - t1) * (t - t2)

    return (y(0.0), dy(0.0), y(H), dy(H)), y(t1)


@settings(max_examples=300, deadline=None)
@given(s1=st.floats(0.0, 1.0), s2=st.one_of(st.floats(-50.0, -1e-3), st.floats(1.001, 50.0)),
       p3=st.sampled_from([-1e9, -3.0, 2.0, 5e8]), p0=st.floats(-1e-5, 1e-5))
def test_extremum_of_a_cubic(s1, s2, p3, p0):
    """The critical value of a cubic through the step's ends, wherever it lies in the step
    (ends included), with the other critical point anywhere outside."""
    data, exact = _extremum(s1 * H, s2 * H, p3, p0)
    swing = abs(p3) * H ** 3 * (1.0 + abs(s2)) + abs(p0)
    assert abs(hermite.extremum(*data, H) - exact) <= 1e-12 * swing


@given(s1=st.floats(0.0, 1.0), curvature=st.sampled_from([-4.0, 1e3]))
def test_extremum_of_a_parabola(s1, curvature):
    """No cubic term (the derivative's quadratic degenerates to a line)."""
    t1 = s1 * H
    data = (curvature * t1 ** 2, -2 * curvature * t1, curvature * (H - t1) ** 2,
            2 * curvature * (H - t1))
    assert abs(hermite.extremum(*data, H)) <= 1e-12 * abs(curvature) * H ** 2


def test_extremum_of_a_sampled_cosine():
    """A peak of cos inside a step of 1/64 period: within the interpolant's error,
    O((w h)^4), of the true peak, wherever the peak falls in the step."""
    w = 2 * np.pi * 140.0
    h = 2 * np.pi / w / 64
    for t0 in np.linspace(-h, 0.0, 11):
        data = (np.cos(w * t0), -w * np.sin(w * t0), np.cos(w * (t0 + h)),
                -w * np.sin(w * (t0 + h)))
        assert abs(hermite.extremum(*data, h) - 1.0) <= (w * h) ** 4 / 100
