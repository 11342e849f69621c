"""The lane loop's contact-free step: RK4 as a linear map, and its int V^2 dt quadrature."""

import math

import numpy as np
import pytest

from harvester_sweep import packing, resolve_parameters
from harvester_sweep._engine import PARAM, hermite
from harvester_sweep.models import tip_mass as model


@pytest.mark.parametrize("preset", ["paper", "strong_coupling"])
@pytest.mark.parametrize("steps", [32, 1024])
def test_free_step_map_is_the_rk4_step(preset, steps):
    """The map gives what the RK4 stages give, to rounding, from any state and phase."""
    p = resolve_parameters(preset, steps_per_period=steps)
    row = packing.pack_parameters(p)
    h = row[PARAM.period] / steps
    ca, sa = math.cos(math.pi / steps), math.sin(math.pi / steps)
    args = row[[PARAM.amplitude, PARAM.wn2, PARAM.cm, PARAM.thm]]
    irc, thc = row[PARAM.irc], row[PARAM.thc]
    m = model.free_step_map(h, ca, sa, *args, irc, thc)
    A, wn2, cm, thm = args
    scale = np.array([1e-6, 1e-6 * 2 * math.pi * p["frequency"], thc * 1e-6])
    rng = np.random.default_rng(1)
    for _ in range(50):
        y = rng.normal(size=3) * scale
        phi = rng.uniform(0, 2 * math.pi)
        s0, c0 = math.sin(phi), math.cos(phi)
        stages = model.rk4(*y, h, A * s0, A * math.sin(phi + math.pi / steps),
                           A * math.sin(phi + 2 * math.pi / steps),
                           model.Coefficients(wn2, cm, thm, 0.0, 0.0, 0.0, irc, thc))[:3]
        mapped = y + m @ np.array([*y, s0, c0])
        assert np.all(np.abs(mapped - stages) <= 1e-13 * (scale + np.abs(stages))), (
            mapped, stages)


def test_v2_integral_exact_for_linear_voltage():
    """The corrected trapezoidal rule integrates V^2 exactly when V is linear in time."""
    a, b, h = 0.3, -2.0e3, 1e-4
    exact = ((a + b * h) ** 3 - a ** 3) / (3 * b)
    value = hermite.v2_integral(a, b, a + b * h, b, 0.5 * h, h * h / 6.0)
    assert value == pytest.approx(exact, rel=1e-14)


def test_v2_integral_local_error_falls_at_fifth_order():
    w, phi = 2 * math.pi * 140.0, 0.4
    errors = []
    for h in (1e-4, 5e-5, 2.5e-5):
        V0, V1 = math.sin(phi), math.sin(w * h + phi)
        dV0, dV1 = w * math.cos(phi), w * math.cos(w * h + phi)
        exact = h / 2 - (math.sin(2 * (w * h + phi)) - math.sin(2 * phi)) / (4 * w)
        errors.append(abs(hermite.v2_integral(V0, dV0, V1, dV1, 0.5 * h, h * h / 6.0) - exact))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 4.8) & (orders < 5.2)), orders
