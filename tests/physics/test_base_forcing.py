"""The base-forcing correction mu_1 (``base_forcing_factor``): the tip is forced by
m mu_1 A sin(w t), so a point with (mu_1, A) is the point with (1, mu_1 A) in everything the
tip-mass model computes, and refused beside a moving stop, which the base forces by A."""

from __future__ import annotations

import numpy as np
import pytest

from harvester_sweep import basin_fractions, cli, resolve_parameters, run_scene, run_sweep
from harvester_sweep.linear import linear_response
from harvester_sweep.parameters import ParameterError
from tests.helpers import phasor

MU = 1.566  # [-] about a cantilever's without tip mass (shared/BEAM.md)


def test_linear_response_is_the_phasor_of_mu_a():
    """The closed form (tests.helpers.phasor, written from docs/model.md) at mu_1 A."""
    p = resolve_parameters("strong_coupling", base_forcing_factor=MU, amplitude=0.7)
    frequency = np.array([50.0, 140.0, 150.0, 300.0])
    X, V = linear_response(**{**p, "frequency": frequency})
    free = {**p, "base_forcing_factor": 1.0, "amplitude": MU * 0.7}
    for mine, theirs in zip((X, V), phasor(**{**free, "frequency": frequency})):
        np.testing.assert_allclose(mine, theirs, rtol=1e-12, atol=0)
    # and mu_1 = 1 is the paper's model: the amplitude as given
    X1, _ = linear_response(**{**p, "base_forcing_factor": 1.0, "frequency": frequency})
    np.testing.assert_allclose(X, MU * X1, rtol=1e-13, atol=0)


def test_stop_free_orbit_is_the_phasor_of_mu_a():
    """The engine's orbit clear of the stop has the closed form's amplitude at mu_1 A."""
    result = run_scene("strong_coupling", gap=1.0, base_forcing_factor=MU,
                       steps_per_period=1024, settle_tolerance=1e-12)
    X, V = phasor(**result.parameters)
    m = result.metrics
    assert abs(X) == pytest.approx(MU * abs(phasor(**{**result.parameters,
                                                       "base_forcing_factor": 1.0})[0]))
    assert m["converged"] and m["impacts_per_period"] == 0
    assert m["x_max"] == pytest.approx(abs(X), rel=1e-6)
    assert m["v_peak"] == pytest.approx(abs(V), rel=1e-6)


def test_a_contact_point_with_mu_is_the_point_with_mu_a_bit_for_bit():
    """(mu_1, A) and (1, mu_1 A) give the engine the same numbers: the same step, budget,
    metrics and end state, to the bit, on a settled orbit that strikes the stop."""
    amplitude = 0.8  # [m/s^2]
    with_mu = run_scene("paper", base_forcing_factor=MU, amplitude=amplitude)
    plain = run_scene("paper", amplitude=MU * amplitude)
    assert with_mu.metrics["status"] == "settled" and with_mu.metrics["impacts_per_period"] > 0
    assert with_mu.parameters["steps_per_period"] == plain.parameters["steps_per_period"]
    a = {k: v for k, v in with_mu.metrics.items() if k != "run_time"}
    b = {k: v for k, v in plain.metrics.items() if k != "run_time"}
    assert a.keys() == b.keys()
    for name in a:
        np.testing.assert_array_equal(np.asarray(a[name]), np.asarray(b[name]), err_msg=name)
    np.testing.assert_array_equal(with_mu.state, plain.state)


@pytest.mark.parametrize("value", ["0", "-1", "10.5", "nan", "inf", "two"])
def test_a_bad_factor_is_refused_in_one_line(value, capsys):
    assert cli.main(["scene", "--set", f"base_forcing_factor={value}"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.count("\n") == 1
    assert captured.err.startswith("harvester-sweep: error: base_forcing_factor [-] = ")
    assert "(0, 10]" in captured.err


def test_the_range_is_open_at_0_and_closed_at_10():
    assert resolve_parameters(base_forcing_factor=10)["base_forcing_factor"] == 10.0
    assert resolve_parameters()["base_forcing_factor"] == 1.0  # the paper's model
    with pytest.raises(ParameterError, match=r"base_forcing_factor \[-\] = 0"):
        resolve_parameters(base_forcing_factor=0)
    with pytest.raises(ParameterError, match=r"base_forcing_factor \[-\] = True"):
        resolve_parameters(base_forcing_factor=True)


def test_a_moving_stop_takes_the_paper_forcing_only(capsys):
    """The engine forces a moving stop with the tip's acceleration; the stop, a lumped body
    on the base, is forced by A, not mu_1 A: mu_1 != 1 beside one is refused in one line."""
    moving = dict(stop_mass=1e-3, stop_support_stiffness=1e5)
    assert resolve_parameters(base_forcing_factor=1.0, **moving)["base_forcing_factor"] == 1.0
    with pytest.raises(ParameterError, match="moving stop"):
        resolve_parameters(base_forcing_factor=MU, **moving)
    argv = ["scene", "--set", f"base_forcing_factor={MU}", "--set", "stop_mass=1e-3",
            "--set", "stop_support_stiffness=1e5"]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(
        f"harvester-sweep: error: base_forcing_factor [-] = {MU}")


def test_a_sweep_over_the_factor_is_the_sweep_over_the_amplitude_bit_for_bit():
    """Along a grid axis (the step chosen per point, orbits with and without impacts)."""
    factors, amplitude = [1.0, MU, 2.5], 0.8  # [-], [m/s^2]
    with_mu = run_sweep({"parameters": {"amplitude": amplitude},
                         "grid": {"base_forcing_factor": factors, "gap": [1e-6, 12e-6]}},
                        None, progress=False)
    plain = run_sweep({"grid": {"amplitude": [mu * amplitude for mu in factors],
                                "gap": [1e-6, 12e-6]}}, None, progress=False)
    assert (with_mu.impacts_per_period > 0).any() and (with_mu.impacts_per_period == 0).any()
    for name, variable in with_mu.data_vars.items():
        np.testing.assert_array_equal(variable.values, plain[name].values, err_msg=name)


def test_a_base_shock_forces_the_tip_through_mu_too():
    """A base shock is an impulse of the base's acceleration: with (mu_1, A, shock) the
    starts, and so the basins, are those of (1, mu_1 A, mu_1 shock), bit for bit."""
    band = {"gap": 0.25e-6 + 18 * 3.75e-6 / 63, "frequency": 100 + 61 * 150 / 63,
            "steps_per_period": 1024}  # (tests/physics/test_basins.py: two orbits coexist)
    mu, amplitude, shock = 1.25, 0.8, 0.024  # [-], [m/s^2], [m/s]
    with_mu = basin_fractions(samples=16, shock=shock, base_forcing_factor=mu,
                              amplitude=amplitude, **band)
    plain = basin_fractions(samples=16, shock=mu * shock, amplitude=mu * amplitude, **band)
    for name, variable in with_mu.data_vars.items():
        np.testing.assert_array_equal(variable.values, plain[name].values, err_msg=name)
    assert with_mu.sizes["attractor"] == 2  # (the starts do leave the orbit from rest)
