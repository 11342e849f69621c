"""Stiff and extreme cases: each converges to the independent reference or stops clearly."""

import math

import numpy as np
import pytest

from harvester_sweep import ParameterError, run_scene, run_sweep
from harvester_sweep.cli import main
from tests.helpers import phasor, reference_orbit

# (overrides, SciPy method of the reference, reference periods to settle, peaks compared?)
# The reference samples its dense output 40000 times per period: it cannot resolve the
# contact-force peak of a plastic or violent impact, where only integrals are compared.
CASES = {
    "literal contact damping 1.07e11": ({"contact_damping": 1.07e11}, "Radau", 3, False),
    "hertz_stiffness x1000": ({"hertz_stiffness": 9.03e11}, "DOP853", 5, True),
    "gap 0": ({"gap": 0.0}, "DOP853", 5, True),
    "preloaded stop": ({"gap": -1e-7}, "DOP853", 5, True),
    "restitution 1": ({"restitution": 1.0}, "DOP853", 5, True),
    "restitution 0.05": ({"restitution": 0.05}, "DOP853", 5, True),
    "resistance 1 Ohm": ({"resistance": 1.0}, "Radau", 3, True),
    "resistance 1 GOhm": ({"resistance": 1e9}, "DOP853", 5, True),
    "amplitude 1000": ({"amplitude": 1000.0}, "DOP853", 5, False),
    "frequency 1 Hz": ({"frequency": 1.0}, "DOP853", 1, True),
}


@pytest.mark.parametrize("case", CASES)
def test_extreme_case_matches_reference(case):
    overrides, method, settle, peaks = CASES[case]
    result = run_scene("paper", **overrides)
    m = result.metrics
    assert m["status"] == "settled", m
    ref = reference_orbit(result, periods_to_settle=settle, method=method,
                          rtol=1e-10 if method == "Radau" else 1e-12)
    assert m["impacts_per_period"] == ref["impacts_per_period"]
    assert m["v_rms"] == pytest.approx(ref["v_rms"], rel=2e-6)
    assert m["approach_velocity"] == pytest.approx(ref["approach_velocity"], rel=2e-6)
    assert m["x_min"] == pytest.approx(ref["x_min"], rel=2e-6)
    if peaks:
        assert m["x_max"] == pytest.approx(ref["x_max"], rel=5e-6)
        assert m["v_peak"] == pytest.approx(ref["v_peak"], rel=5e-6)
        assert m["contact_force_max"] == pytest.approx(ref["contact_force_max"], rel=2e-4)
    else:  # the engine resolves the peak the sampled reference misses
        assert m["contact_force_max"] >= ref["contact_force_max"] * (1 - 1e-6)


def test_literal_contact_damping_needs_a_tiny_step():
    """The paper's printed c_h makes the stop plastic: stability needs a step ~1e-8 s."""
    result = run_scene("paper", contact_damping=1.07e11)
    step = 1 / (result.parameters["frequency"] * result.metrics["steps_per_period"])
    assert step < 1e-7
    assert result.metrics["x_max"] == pytest.approx(1e-6, rel=1e-3)  # it stops dead at g


def test_high_frequency_is_linear_and_matches_phasor():
    result = run_scene("paper", frequency=1e4)
    X, V = phasor(**result.parameters)
    assert result.metrics["status"] == "settled" and result.metrics["impacts_per_period"] == 0
    assert result.metrics["x_max"] == pytest.approx(abs(X), rel=1e-6)
    assert result.metrics["v_peak"] == pytest.approx(abs(V), rel=1e-6)


def test_chattering_preload_says_it_did_not_settle(capsys):
    """Pressed 1 um into the stop the mass chatters without settling: flagged, not hidden."""
    result = run_scene("paper", gap=-1e-6)
    m = result.metrics
    assert m["status"] == "not settled" and not m["converged"] and m["orbit_period"] == 0
    assert all(math.isfinite(m[k]) for k in ("power", "v_peak", "x_max", "x_min"))
    assert main(["scene", "--set", "gap=-1e-6"]) == 0
    assert "no steady state within max_periods" in capsys.readouterr().err


def test_a_motion_cut_short_says_how_many_periods_its_metrics_cover(capsys):
    """Two periods from rest cannot settle: the line said its metrics were over the last 16
    periods; they are over the two it ran."""
    assert run_scene("paper", max_periods=2).metrics["periods_run"] == 2
    assert main(["scene", "--set", "max_periods=2"]) == 0
    err = capsys.readouterr().err
    assert "the metrics are over the last 2 periods" in err and "16" not in err


def test_too_stiff_stops_with_message_and_is_flagged_in_a_sweep(capsys):
    with pytest.raises(ParameterError, match="too stiff: the contact damping .* steps per"):
        run_scene("paper", contact_damping=1.07e11, max_steps_per_period=100_000)
    assert main(["scene", "--set", "contact_damping=1.07e11",
                 "--set", "max_steps_per_period=100000"]) == 2
    assert "too stiff" in capsys.readouterr().err
    ds = run_sweep({"preset": "paper", "parameters": {"max_steps_per_period": 100_000},
                    "grid": {"contact_damping": [118.25, 1e5, 1.07e11]},
                    "sweep": {"outputs": ["power", "strobe"], "samples": 2}}, progress=False)
    assert ds.status.values.tolist() == [0, 0, 3]
    assert np.isnan(ds.power.values[2]) and np.all(np.isfinite(ds.power.values[:2]))
    assert np.isnan(ds.strobe_voltage.values[2]).all()  # nothing ran: no sample either
    assert np.isfinite(ds.strobe_voltage.values[:2]).all()


def test_diverging_explicit_step_is_flagged_never_garbage():
    with pytest.warns(UserWarning, match="stability bound"):
        result = run_scene("paper", hertz_stiffness=9.03e11, steps_per_period=128)
    assert result.metrics["status"] == "diverged"
    assert result.metrics["power"] is None and result.metrics["x_max"] is None
