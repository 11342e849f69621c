"""The tip-mass model's declaration (harvester_sweep.models) against independent forms: the
textbook phasor solution, the compiled right-hand side, the Hertz law's closed forms and a
SciPy integration of the free motion that the energy bound must contain."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from harvester_sweep import resolve_parameters
from harvester_sweep.linear import linear_response
from harvester_sweep.models import hertz, tip_mass


def _textbook_system(p):
    """d(x, v, V)/dt = M (x, v, V) + b a(t) without the stop, from docs/model.md's
    equations: m x'' = m a - k x - c x' + theta V, C_p V' = -V / R - theta x'."""
    m, wn = p["mass"], 2 * np.pi * p["natural_frequency"]
    k, c = m * wn**2, 2 * p["damping_ratio"] * m * wn
    th, cp, r = p["coupling"], p["capacitance"], p["resistance"]
    return (np.array([[0, 1, 0], [-k / m, -c / m, th / m], [0, -th / cp, -1 / (r * cp)]]),
            np.array([0.0, 1.0, 0.0]))


def _textbook(p, frequency):
    """X and V of the harvester without its stop, in closed form (docs/model.md)."""
    m, wn = p["mass"], 2 * np.pi * p["natural_frequency"]
    w = 2 * np.pi * np.asarray(frequency)
    k, c = m * wn**2, 2 * p["damping_ratio"] * m * wn
    load = 1 + 1j * w * p["resistance"] * p["capacitance"]
    X = m * p["amplitude"] / (k - m * w**2 + 1j * w * c
                              + 1j * w * p["coupling"] ** 2 * p["resistance"] / load)
    return X, -1j * w * p["coupling"] * p["resistance"] * X / load


@pytest.mark.parametrize("preset", ["paper", "strong_coupling"])
def test_linear_response_is_the_textbook_phasor(preset):
    p = resolve_parameters(preset)
    f = np.linspace(0.3, 3.0, 41) * p["natural_frequency"]
    X, V = linear_response(**{**p, "frequency": f})
    X0, V0 = _textbook(p, f)
    assert np.allclose(X, X0, rtol=1e-12, atol=0) and np.allclose(V, V0, rtol=1e-12, atol=0)
    # parameters broadcast against each other, as the closed form's do
    R = np.array([1e3, 1e5])[:, None]
    X, V = linear_response(**{**p, "frequency": f, "resistance": R})
    X0, V0 = _textbook({**p, "resistance": R}, f)
    assert X.shape == (2, 41) and np.allclose(V, V0, rtol=1e-12, atol=0)


@pytest.mark.parametrize("preset", ["paper", "strong_coupling"])
def test_linear_system_is_the_compiled_right_hand_side_off_the_stop(preset):
    """The declared linear system, and the compiled right-hand side with the coefficients
    packing gives the engine, are both the textbook equations."""
    from harvester_sweep import packing
    from harvester_sweep._engine import PARAM
    p = resolve_parameters(preset)
    M, b = _textbook_system(p)
    declared, declared_b = tip_mass.linear_system(**p)
    assert np.allclose(declared, M, rtol=1e-14, atol=0) and np.array_equal(declared_b, b)
    r = packing.pack_parameters(p)
    k = tip_mass.Coefficients(r[PARAM.wn2], r[PARAM.cm], r[PARAM.thm], 1e9, 1.0, 0.0,
                              r[PARAM.irc], r[PARAM.thc])
    rng = np.random.default_rng(3)
    for _ in range(20):
        y = rng.normal(size=3) * np.array([1e-6, 1e-3, 1.0])
        f = rng.normal()
        a, dV = tip_mass.derivatives(*y, f, k)  # x far below the stop at g = 1 m
        expected = M @ y + b * f
        assert np.allclose([y[1], a, dV], expected, rtol=1e-13, atol=0)


def test_hertz_law_closed_form_clip_and_switches():
    kh, ch = 3.4e9, 250.0
    for delta, rate in [(2e-7, 1e-3), (2e-7, -1e-3), (2e-7, -5e-3), (-1e-7, 1e-3), (0.0, 1.0)]:
        expected = kh * max(delta, 0) ** 1.5 * max(1 + ch * rate, 0)
        assert hertz.force(kh, delta, rate, ch) == pytest.approx(expected, rel=1e-15, abs=0)
        # the stop pushes exactly where the force is on: past both surfaces
        assert hertz.pushes(delta, rate, ch) == (expected > 0)
    assert hertz.clip(hertz.clip_rate(ch), ch) == pytest.approx(0.0, abs=1e-15)
    # stored energy 2/5 k_h delta^2.5, and the linearised spring dF/d delta
    delta = hertz.penetration(1.7e-9, kh)
    assert 0.4 * kh * delta**2.5 == pytest.approx(1.7e-9, rel=1e-13)
    d = 1e-3 * delta
    slope = (hertz.static_force(kh, delta + d) - hertz.static_force(kh, delta - d)) / (2 * d)
    assert hertz.stiffness(kh, delta) == pytest.approx(slope, rel=1e-6)


@pytest.mark.parametrize("preset", ["paper", "strong_coupling"])
def test_excursion_bound_contains_the_free_motion(preset):
    """No free, decaying motion from a deviation goes beyond the energy bound (SciPy)."""
    p = resolve_parameters(preset)
    M, _ = _textbook_system(p)
    wn2, thm, thc = -M[1, 0], M[1, 2], -M[2, 1]
    rng = np.random.default_rng(7)
    T = 1 / p["natural_frequency"]
    for _ in range(5):
        e = rng.normal(size=3) * np.array([1e-6, 1e-6 * math.sqrt(wn2), 1e-6 * thc])
        run = solve_ivp(lambda t, y: M @ y, (0, 20 * T), e, rtol=1e-10, atol=1e-20,
                        max_step=T / 50)
        bound = tip_mass.excursion_bound(*e, wn2, thm, thc)
        assert np.abs(run.y[0]).max() <= bound * (1 + 1e-9)
        assert np.abs(run.y[0]).max() >= 0.3 * bound  # a bound, not a blanket


@pytest.mark.parametrize("coupling", [0.5, 1.0, 10.0])
def test_the_step_resolves_the_coupled_mode_of_a_strong_coupling(coupling):
    """With a strong coupling the load stiffens the mode far beyond the natural frequency
    (issue 46, item 9: the step was chosen from the parts and the run diverged): the
    scene settles on the stop-free orbit, the textbook phasor's, to its accuracy."""
    from harvester_sweep import run_scene
    result = run_scene("paper", coupling=coupling)
    p = result.parameters
    X, V = _textbook(p, p["frequency"])
    assert result.metrics["status"] == "settled"
    assert result.metrics["power"] == pytest.approx(abs(V) ** 2 / (2 * p["resistance"]),
                                                    rel=1e-6)
    assert result.metrics["x_max"] == pytest.approx(abs(X), rel=1e-6)


def test_phasor_at_an_undamped_resonance_is_unbounded_and_leaves_the_others():
    from harvester_sweep.linear import phasor
    wn2 = 100.0
    m, b = tip_mass.linear_matrix(np.array([wn2, wn2]), np.array([0.0, 1.0]), 0.0, 1.0, 0.0)
    X, _ = phasor(m, b, 1.0, math.sqrt(wn2) / (2 * math.pi))
    assert np.isinf(X[0]) and X[1] == pytest.approx(-1j / math.sqrt(wn2), rel=1e-12)


@pytest.mark.parametrize("preset", ["paper", "strong_coupling"])
def test_free_amplitude_in_engine_coefficients_is_the_phasor(preset):
    from harvester_sweep import packing
    from harvester_sweep._engine import PARAM
    p = resolve_parameters(preset)
    r = packing.pack_parameters(p)
    f = np.linspace(0.5, 2.0, 7) * p["natural_frequency"]
    x = tip_mass.free_amplitude(r[PARAM.amplitude], 2 * np.pi * f, r[PARAM.wn2], r[PARAM.cm],
                                r[PARAM.thm], r[PARAM.irc], r[PARAM.thc])
    assert np.allclose(x, np.abs(_textbook(p, f)[0]), rtol=1e-12, atol=0)
