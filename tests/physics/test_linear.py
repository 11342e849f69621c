"""With the stop out of reach the harvester is linear: compare with the phasor solution."""

import numpy as np
import pytest

from harvester_sweep import run_scene
from tests.helpers import phasor

FREQUENCIES = [50.0, 100.0, 140.0, 150.0, 200.0, 300.0]  # Hz
RESISTANCES = [10.0, 1e3, 1e5, 1e7]  # Ohm


def _steps(frequency, resistance, capacitance=100e-9):
    """Enough steps for the 1e-6 target and RK4 stability on the load circuit."""
    return max(1024, int(np.ceil(1.0 / (frequency * resistance * capacitance))))


@pytest.mark.parametrize("frequency", FREQUENCIES)
@pytest.mark.parametrize("resistance", RESISTANCES)
def test_linear_amplitudes_match_phasor(frequency, resistance):
    # Strong coupling so that the load matters; the stop is 1 m away.
    result = run_scene("paper", gap=1.0, coupling=3e-3, frequency=frequency,
                       resistance=resistance, steps_per_period=_steps(frequency, resistance),
                       settle_tolerance=1e-12, max_periods=20000)
    X, V = phasor(**result.parameters)
    m = result.metrics
    assert m["converged"] and m["orbit_period"] == 1 and m["impacts_per_period"] == 0
    assert m["x_max"] == pytest.approx(abs(X), rel=1e-6)
    assert -m["x_min"] == pytest.approx(abs(X), rel=1e-6)
    assert m["v_peak"] == pytest.approx(abs(V), rel=1e-6)
    assert m["v_rms"] == pytest.approx(abs(V) / np.sqrt(2), rel=1e-6)
    assert m["power"] == pytest.approx(abs(V) ** 2 / (2 * resistance), rel=2e-6)


def test_rk4_error_falls_at_fourth_order():
    steps = np.array([48, 96, 192, 384])
    errors = []
    for n in steps:
        result = run_scene("paper", gap=1.0, coupling=3e-3, steps_per_period=int(n),
                           settle_tolerance=1e-13)
        _, V = phasor(**result.parameters)
        errors.append(abs(result.metrics["v_rms"] / (abs(V) / np.sqrt(2)) - 1))
    orders = -np.diff(np.log(errors)) / np.diff(np.log(steps))
    assert errors[-1] < 1e-7
    assert np.all((orders > 3.7) & (orders < 4.3)), orders


@pytest.mark.parametrize("clearance", [0.3, 0.05])
@pytest.mark.parametrize("side", ["upper", "lower"])
def test_near_miss_is_the_gap_less_the_phasor_amplitude(clearance, side):
    """A stop just beyond the linear amplitude |X|, above or below, is never touched, and
    the orbit's near_miss is its gap less |X| (the closed form's top or bottom of the
    swing), to the step's error; it has no impact (approach_velocity_min None: NaN)."""
    X, _ = phasor(**run_scene("paper", gap=1.0).parameters)
    gap = (1 + clearance) * abs(X)
    stops = dict(gap=gap) if side == "upper" else dict(gap=1.0, lower_gap=gap)
    m = run_scene("paper", steps_per_period=1024, settle_tolerance=1e-12, **stops).metrics
    assert m["impacts_per_period"] == m["impacts_per_period_lower"] == 0
    assert m["approach_velocity_min"] is None
    assert m["near_miss"] == pytest.approx(clearance * abs(X), rel=1e-5)


@pytest.mark.parametrize("steps", [576, 704, 896])
def test_the_error_estimate_holds_the_error_of_extrema_placed_on_multi_steps(steps):
    """Below 1024 steps a period the engine's multi-steps (lanes.multi_steps) take half
    the steps they take at twice the steps, and span as much of the period; the turns of
    x and V placed on their interpolants err alike in both runs. The run that estimates
    the error takes the coarse run's multi-steps, so that the change it measures holds
    that error: against the closed form, above resonance where it is the larger part, the
    error of x_max, x_min and v_peak is about 16/15 of the estimate (with the finer run's
    own multi-steps it was several times the estimate)."""
    result = run_scene("paper", gap=1.0, frequency=250.0, steps_per_period=steps,
                       settle_tolerance=1e-13)
    X, V = phasor(**result.parameters)
    m = result.metrics
    error = max(abs(m["x_max"] / abs(X) - 1), abs(-m["x_min"] / abs(X) - 1),
                abs(m["v_peak"] / abs(V) - 1))
    assert error <= 1.5 * m["error_estimate"], (error, m["error_estimate"])
