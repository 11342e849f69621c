"""The bimorph's modes and linear response, each against something computed another way:
published eigenvalues, the transcendental equation's residual, orthonormality by adaptive
quadrature, the boundary conditions, high-precision mode shapes (mpmath), the
distributed-parameter solution the modal sum converges to, and the tip-mass model's phasor."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from harvester_sweep import bimorph
from harvester_sweep.bimorph import (
    BEAM_PRESETS,
    as_tip_mass_parameters,
    eigenvalues,
    exact_response,
    modal_response,
    modes,
    rayleigh_damping_ratios,
    reduction,
)
from harvester_sweep.materials import EPSILON_0, MATERIALS, PIEZO_MATERIALS
from tests.helpers import phasor

PRESET = BEAM_PRESETS["bimorph_tip"].beam
BARE = dataclasses.replace(PRESET, tip_mass=0.0)
# a tip body with rotary inertia: a 2.118 g block 4 mm long about the tip (m l^2 / 3)
BLOCK = dataclasses.replace(PRESET, tip_inertia=PRESET.tip_mass * 4e-3**2 / 3)
MUS = [0.0, 0.1, 1.0, 10.0, 100.0]


def _terms(lam, mu, j):
    """The transcendental equation's five terms (docs/model.md, "The beam"), written again."""
    c, s, ch, sh = math.cos(lam), math.sin(lam), math.cosh(lam), math.sinh(lam)
    return [1.0, c * ch, lam * mu * (c * sh - s * ch), -lam**3 * j * (ch * s + sh * c),
            lam**4 * mu * j * (1 - c * ch)]


def _clamped_pinned(n):
    """Roots of tan l = tanh l (the tip held, free to turn): a heavy tip mass's limit."""
    f = lambda x: math.sin(x) * math.cosh(x) - math.cos(x) * math.sinh(x)  # noqa: E731
    return [brentq(f, (r + 0.25) * math.pi - 0.3, (r + 0.25) * math.pi + 0.3, xtol=1e-15)
            for r in range(1, n + 1)]


def test_eigenvalues_without_tip_mass_are_the_clamped_free_ones():
    lam = eigenvalues(0.0, 0.0, 8)
    assert lam[:3] == pytest.approx([1.87510407, 4.69409113, 7.85475744], abs=5e-9)
    # the asymptote (2r - 1) pi / 2: cos l = -1 / cosh l puts the root 2 e^-l from it
    asymptote = (2 * np.arange(1, 9) - 1) * np.pi / 2
    offset = (lam - asymptote) * (-1) ** np.arange(0, 8)
    assert offset[3:] == pytest.approx(2 * np.exp(-asymptote[3:]), rel=1e-3)


@pytest.mark.parametrize("mu", MUS)
@pytest.mark.parametrize("j", [0.0, 0.01, 1.0])
def test_eigenvalues_solve_the_transcendental_equation(mu, j):
    lam = eigenvalues(mu, j, 8)
    assert np.all(np.diff(lam) > 0) and lam[0] > 0
    for root in lam:
        # each term's size: its trigonometric factors at their largest (cos l cosh l is
        # near -1 at a clamped-free root, but one ulp of l moves it by cosh l ulp)
        ch = math.cosh(root)
        size = 1 + ch * (1 + root * mu + root**3 * j + root**4 * mu * j)
        assert abs(sum(_terms(root, mu, j))) < 1e-14 * size
        # and the root to 1e-13: the sign changes across it
        below, above = (sum(_terms(root * (1 + d), mu, j)) for d in (-1e-13, 1e-13))
        assert below * above <= 0
    # a tip mass and inertia only lower the clamped-free eigenvalues
    assert np.all(lam <= eigenvalues(0.0, 0.0, 8) + 1e-12)
    if j == 0:  # and a tip mass alone (one constraint) keeps lambda_r above the (r-1)-th
        # root with the tip held (rank-one interlacing)
        assert np.all(lam[1:] >= np.array(_clamped_pinned(7)) - 1e-12)
    # no root missed: the equation keeps its sign between consecutive roots
    for a, b in zip(np.concatenate([[1e-6], lam[:-1]]), lam):
        grid = np.linspace(a, b, 4001)[1:-1]
        values = bimorph._characteristic(grid, mu, j)  # the same sign: divided by cosh
        assert np.all(np.sign(values) == np.sign(values[0]))


def test_a_heavy_tip_mass_brings_the_modes_to_the_pinned_tip():
    lam = eigenvalues(1e4, 0.0, 4)
    assert lam[0] == pytest.approx((3 / 1e4) ** 0.25, rel=1e-3)  # k = 3 YI / L^3 on M_t
    assert lam[1:] == pytest.approx(_clamped_pinned(3), rel=1e-3)


@pytest.mark.parametrize("beam", [PRESET, BARE, BLOCK], ids=["tip_mass", "bare", "inertia"])
def test_modes_are_orthonormal_by_quadrature(beam):
    md = modes(beam, 8)
    gram = np.empty((8, 8))
    for r in range(8):
        for q in range(r, 8):
            integral = quad(lambda s: md.shape(s)[r, 0] * md.shape(s)[q, 0], 0, beam.length,
                            limit=200, epsabs=0, epsrel=1e-13)[0]
            gram[r, q] = gram[q, r] = (beam.mass_per_length * integral
                                       + beam.tip_mass * md.tip[r] * md.tip[q]
                                       + beam.tip_inertia * md.tip_slope[r] * md.tip_slope[q])
    assert np.max(np.abs(gram - np.eye(8))) < 1e-9


@pytest.mark.parametrize("beam", [PRESET, BARE, BLOCK], ids=["tip_mass", "bare", "inertia"])
def test_modes_meet_the_boundary_conditions(beam):
    md = modes(beam, 8)
    length, yi = beam.length, beam.bending_stiffness
    scale = np.abs(md.amplitude) * (md.eigenvalues / length) ** 2  # phi'' [1/(m^2 kg^.5)]
    assert np.all(np.abs(md.shape(0.0)[:, 0]) < 1e-12 * np.abs(md.amplitude))
    assert np.all(np.abs(md.slope(0.0)[:, 0]) < 1e-12 * scale * length)
    w2 = md.omega**2
    moment = yi * md.curvature(length)[:, 0] - w2 * beam.tip_inertia * md.tip_slope
    shear = yi * md.derivative(length, 3)[:, 0] + w2 * beam.tip_mass * md.tip
    assert np.all(np.abs(moment) < 1e-11 * yi * scale)
    assert np.all(np.abs(shear) < 1e-11 * yi * scale * md.eigenvalues / length)
    assert np.all(md.tip > 0)
    assert md.root_curvature == pytest.approx(md.curvature(0.0)[:, 0], rel=1e-15)
    assert md.coupling == pytest.approx(beam.coupling * md.tip_slope, rel=1e-15)


def _textbook_shape(lam, mu, x):
    """cos x - cosh x + sigma (sin x - sinh x) as docs/model.md writes it, in floats."""
    c, sn, ch, sh = np.cos(lam), np.sin(lam), np.cosh(lam), np.sinh(lam)
    sigma = (sn - sh + lam * mu * (c - ch)) / (c + ch - lam * mu * (sn - sh))
    return np.cos(x) - np.cosh(x) + sigma * (np.sin(x) - np.sinh(x))


@pytest.mark.parametrize("beam", [PRESET, BARE], ids=["tip_mass", "bare"])
def test_mode_shapes_are_the_textbook_form_where_it_has_its_digits(beam):
    """Modes 1 to 4 (cosh lambda < 3e4: the textbook form loses under 1e-11) against the
    textbook form, to 1e-10 of the mode's size, one factor A_r apart."""
    md = modes(beam, 4)
    s = np.linspace(0, beam.length, 11)
    for r in range(4):
        textbook = _textbook_shape(md.eigenvalues[r], beam.mass_ratio,
                                   md.eigenvalues[r] * s / beam.length)
        ours = md.shape(s)[r]
        assert np.max(np.abs(ours - ours[-1] / textbook[-1] * textbook)) < 1e-10 * np.max(
            np.abs(ours))


@pytest.mark.parametrize("beam", [PRESET, BARE], ids=["tip_mass", "bare"])
def test_mode_shapes_keep_their_digits_to_the_eighth_mode(beam):
    """cos - cosh + sigma (sin - sinh) at 40 digits (mpmath) against the stable form, where
    the textbook form in floats loses six digits (cosh lambda ~ 1e10)."""
    mpmath = pytest.importorskip("mpmath")
    md = modes(beam, 8)
    with mpmath.workdps(40):
        mu = mpmath.mpf(beam.mass_ratio)
        s = np.linspace(0, beam.length, 9)
        for r in (5, 6, 7):
            lam = mpmath.findroot(lambda x: 1 + mpmath.cos(x) * mpmath.cosh(x) + x * mu * (
                mpmath.cos(x) * mpmath.sinh(x) - mpmath.sin(x) * mpmath.cosh(x)),
                mpmath.mpf(md.eigenvalues[r]))
            assert float(lam) == pytest.approx(md.eigenvalues[r], rel=1e-14)
            c, sn, ch, sh = mpmath.cos(lam), mpmath.sin(lam), mpmath.cosh(lam), mpmath.sinh(lam)
            sigma = (sn - sh + lam * mu * (c - ch)) / (c + ch - lam * mu * (sn - sh))
            x = [lam * mpmath.mpf(v) / mpmath.mpf(beam.length) for v in s]
            shape = [mpmath.cos(v) - mpmath.cosh(v) + sigma * (mpmath.sin(v) - mpmath.sinh(v))
                     for v in x]
            ratio = md.shape(s)[r][-1] / float(shape[-1])
            size = np.max(np.abs(md.shape(s)[r]))
            # one factor A_r: the shapes agree to 1e-10 of the mode's size
            reference = ratio * np.array([float(v) for v in shape])
            assert np.max(np.abs(md.shape(s)[r] - reference)) < 1e-10 * size


def test_forcing_is_the_integral_of_the_mode():
    for beam in (PRESET, BLOCK):
        md = modes(beam, 8)
        for r in range(8):
            integral = quad(lambda s: md.shape(s)[r, 0], 0, beam.length, limit=200,
                            epsabs=0, epsrel=1e-13)[0]
            expected = beam.mass_per_length * integral + beam.tip_mass * md.tip[r]
            assert md.forcing[r] == pytest.approx(expected, rel=1e-10, abs=1e-12)


def test_base_forcing_factor_is_1_566_bare_and_tends_to_1_with_a_heavy_tip():
    assert reduction(BARE).forcing_factor == pytest.approx(1.566, abs=5e-4)
    factors = [reduction(dataclasses.replace(PRESET, tip_mass=mu * BARE.mass_per_length
                                             * BARE.length)).forcing_factor
               for mu in (0.1, 1.0, 10.0, 100.0, 1e4)]
    assert np.all(np.diff(factors) < 0) and 1 < factors[-1] < 1 + 1e-4


def test_the_sum_of_modal_forcings_is_the_rigid_motion():
    """sum_r gamma_r phi_r(s) -> 1: the base's inertial load expands onto the modes as a rigid
    translation does (the mass-weighted completeness of the modes)."""
    md = modes(BLOCK, 8)
    partial = np.cumsum(md.forcing[:, None] * md.shape([0.5 * BLOCK.length, BLOCK.length]),
                        axis=0)
    assert np.all(np.abs(partial[-1] - 1) < np.abs(partial[0] - 1))


def test_natural_frequencies_grow_like_lambda_squared():
    md = modes(BARE, 5)
    assert md.omega[4] / md.omega[0] == pytest.approx((md.eigenvalues[4] / 1.87510407) ** 2)
    assert 56 < md.omega[4] / md.omega[0] < 57  # (14.137 / 1.875)^2
    assert md.omega[0] == pytest.approx(1.87510407**2 * math.sqrt(
        BARE.bending_stiffness / (BARE.mass_per_length * BARE.length**4)))


def test_the_layer_formulas():
    pzt, brass = PIEZO_MATERIALS["PZT-5A"], MATERIALS["brass"]
    b, hs, hp, length = 10e-3, 0.2e-3, 0.25e-3, 28.81e-3
    assert pzt.youngs_modulus == pytest.approx(61e9, rel=1e-3)
    assert PIEZO_MATERIALS["PZT-5H"].permittivity == pytest.approx(3400 * EPSILON_0)
    assert PRESET.mass_per_length == pytest.approx(b * (brass.density * hs
                                                        + 2 * pzt.density * hp))
    # the composite section: substrate's and the layers' second moments about the middle
    yi = brass.youngs_modulus * b * hs**3 / 12 + 2 * pzt.youngs_modulus * (
        b * hp**3 / 12 + b * hp * (hs / 2 + hp / 2) ** 2)
    assert PRESET.bending_stiffness == pytest.approx(yi, rel=1e-12)
    eps_s = pzt.permittivity - pzt.d31**2 * pzt.youngs_modulus
    assert PRESET.permittivity_strain == pytest.approx(eps_s)
    assert PRESET.e31 == pytest.approx(pzt.d31 * pzt.youngs_modulus) and PRESET.e31 < 0
    assert PRESET.coupling == pytest.approx(-PRESET.e31 * b * (hp + hs) / 2)
    assert PRESET.capacitance == pytest.approx(eps_s * b * length / (2 * hp))
    parallel = dataclasses.replace(PRESET, connection="parallel")
    assert parallel.coupling == pytest.approx(2 * PRESET.coupling)
    assert parallel.capacitance == pytest.approx(4 * PRESET.capacitance)
    overridden = dataclasses.replace(PRESET, piezo_modulus=50e9, d31=-100e-12)
    assert overridden.e31 == pytest.approx(-5.0)


# The modal sum against the distributed-parameter solution. Frequencies off resonance: half
# the first mode's, and between the first two (geometric mean).
def _frequencies(beam):
    f = modes(beam, 2).omega / (2 * np.pi)
    return [0.5 * f[0], math.sqrt(f[0] * f[1])]


def _errors(beam, frequency, resistance, **damping):
    exact_w, exact_v = exact_response(beam, frequency, resistance, amplitude=9.81, **damping)
    md = modes(beam, 8)
    zeta = rayleigh_damping_ratios(md.omega, damping.get("mass_damping", 0.0),
                                   damping.get("stiffness_damping", 0.0))
    errors = []
    for n in range(1, 9):
        w, v = modal_response(md, frequency, resistance, n_modes=n, amplitude=9.81,
                              damping_ratio=zeta[:n])
        errors.append((abs(w - exact_w) / abs(exact_w), abs(v - exact_v) / abs(exact_v)))
    return np.array(errors)


@pytest.mark.parametrize("beam", [PRESET, BARE], ids=["tip_mass", "bare"])
@pytest.mark.parametrize("which", [0, 1])
def test_the_modal_sum_converges_to_the_exact_solution(beam, which):
    """The piezo layers act on the beam as a moment theta_b V at the tip, and a point moment
    expands slowly onto the modes: the neglected sum_{r>N} chi_r^2 / omega_r^2 (chi_r ~
    lambda_r, omega_r ~ lambda_r^2) falls like 1/N. Measured at eight modes: tip
    displacement 2e-5 to 2e-4 of its amplitude, voltage 1e-3 to 6e-3. Past eight modes
    (the uncapped modes, to 64) the error halves as N doubles, and the Richardson
    extrapolation 2 X_64 - X_32 meets the exact solution to 6e-6 (measured): the modal sum's
    limit is the boundary-value problem's solution, signs included."""
    frequency = _frequencies(beam)[which]
    errors = _errors(beam, frequency, 1e5)
    assert errors[7, 0] < 3e-4 and errors[7, 1] < 8e-3
    assert np.all(errors[7] < errors[0] / 10) and np.all(errors[7] < errors[3])
    exact_w, exact_v = exact_response(beam, frequency, 1e5, amplitude=9.81)
    many = bimorph._modes(beam, 64)
    sums = {n: modal_response(many, frequency, 1e5, n_modes=n, amplitude=9.81)
            for n in (8, 16, 32, 64)}
    assert sums[8][1] == pytest.approx(modal_response(beam, frequency, 1e5, amplitude=9.81)[1],
                                       rel=1e-12)
    for exact, k in ((exact_w, 0), (exact_v, 1)):
        error = {n: abs(sums[n][k] - exact) / abs(exact) for n in sums}
        for n in (8, 16, 32):  # the voltage like 1/N; the displacement as fast or faster
            assert error[2 * n] / error[n] < 0.6 and (k == 0 or error[2 * n] / error[n] > 0.4)
        assert abs(2 * sums[64][k] - sums[32][k] - exact) / abs(exact) < 2e-5


@pytest.mark.parametrize("which", [0, 1])
def test_with_rotary_inertia_the_modal_sum_converges_fast(which):
    """Tip inertia holds back the tip's turning in the high modes (phi_r'(L) bounded), so
    the point moment's series converges fast, with Rayleigh damping in both: at eight modes
    within 3e-6 (measured 2e-8 to 8e-7)."""
    damping = {"mass_damping": 2.0, "stiffness_damping": 2e-6}
    errors = _errors(BLOCK, _frequencies(BLOCK)[which], 1e5, **damping)
    assert np.all(errors[7] < 3e-6)
    assert np.all(errors[7] < errors[0] * 1e-3)


@pytest.mark.parametrize("resistance", [1e3, math.inf], ids=["load", "open"])
def test_far_above_the_first_mode_the_series_still_converges(resistance):
    """Between the fifth and sixth modes, damped (Rayleigh), loaded or open: the sum over
    64 modes meets the exact solution along the span to 1e-6 (measured 6e-8 and 6e-10), and
    eight modes miss by under 1e-2 (measured 4e-3)."""
    f = modes(BLOCK, 6).omega[4:6] / (2 * np.pi)
    frequency, s = math.sqrt(f[0] * f[1]), np.array([0.3, 1.0]) * BLOCK.length
    exact_w, exact_v = exact_response(BLOCK, frequency, resistance, s=s, mass_damping=5.0,
                                      stiffness_damping=1e-7)
    many = bimorph._modes(BLOCK, 64)
    zeta = rayleigh_damping_ratios(many.omega, 5.0, 1e-7)
    for n, tolerance in ((8, 1e-2), (64, 1e-6)):
        w, v = modal_response(many, frequency, resistance, n_modes=n, damping_ratio=zeta[:n],
                              s=s)
        assert np.max(np.abs(w - exact_w) / np.abs(exact_w)) < tolerance
        assert abs(v - exact_v) < tolerance * abs(exact_v)


def test_with_a_short_circuit_the_displacement_converges_fast():
    """With V ~ 0 only the inertial load's expansion remains: gamma_r phi_r(L) / omega_r^2
    falls like lambda_r^-5: at eight modes within 3e-7 (measured 9e-8)."""
    errors = _errors(PRESET, _frequencies(PRESET)[1], 1e-6)
    assert errors[7, 0] < 3e-7 and errors[7, 0] < errors[0, 0] * 1e-4


def test_the_exact_solution_along_the_span():
    """W(s) from the boundary-value problem against the modal sum along the span (where the
    curvature series converges: the deflection), and its clamp."""
    frequency = _frequencies(BLOCK)[1]
    s = np.linspace(0, BLOCK.length, 7)
    exact_w, exact_v = exact_response(BLOCK, np.array([frequency]), 1e4, s=s)
    modal_w, modal_v = modal_response(BLOCK, np.array([frequency]), 1e4, s=s)
    assert exact_w.shape == (1, 7) and exact_v.shape == (1,)
    assert exact_w[0, 0] == 0 or abs(exact_w[0, 0]) < 1e-12 * np.max(np.abs(exact_w))
    assert np.max(np.abs(modal_w - exact_w)) < 2e-5 * np.max(np.abs(exact_w))


def test_one_mode_at_the_tip_is_the_tip_mass_model():
    """The one-mode response equals the tip-mass phasor (tests/helpers.py) with the reduced
    parameters and base_forcing_factor mu_1."""
    for beam in (PRESET, BARE):
        params = as_tip_mass_parameters(beam, damping_ratio=0.01, resistance=1e5,
                                        amplitude=9.81)
        for frequency in (60.0, 150.0, 400.0):
            x, v = phasor(frequency=frequency, **params)
            w1, v1 = modal_response(beam, frequency, 1e5, n_modes=1, damping_ratio=0.01,
                                    amplitude=9.81)
            assert w1 == pytest.approx(x, rel=1e-12) and v1 == pytest.approx(v, rel=1e-12)


def test_the_preset_meets_table_1():
    equivalent = reduction(PRESET)
    assert equivalent.natural_frequency == pytest.approx(150.0, rel=1e-3)
    assert equivalent.mass == pytest.approx(2.5e-3, rel=1e-3)
    assert equivalent.stiffness == pytest.approx(
        equivalent.mass * (2 * np.pi * equivalent.natural_frequency) ** 2)
    params = as_tip_mass_parameters(PRESET)
    assert set(params) == {"mass", "natural_frequency", "coupling", "capacitance",
                           "base_forcing_factor"}
    assert params["coupling"] > 0 and 1 < params["base_forcing_factor"] < 1.1
    rod_scene = BEAM_PRESETS["mak_rod"]
    assert rod_scene.beam == PRESET and rod_scene.rod is not None
    assert rod_scene.contact_position == pytest.approx(0.8 * PRESET.length)
    assert BEAM_PRESETS["bimorph_tip"].contact_position == PRESET.length


@pytest.mark.parametrize("change, words", [
    ({"length": -1.0}, "length [m]"),
    ({"width": 0.0}, "width [m]"),
    ({"substrate_thickness": float("nan")}, "substrate_thickness [m]"),
    ({"piezo_thickness": "1"}, "piezo_thickness [m]"),
    ({"tip_mass": -1e-3}, "tip_mass [kg]"),
    ({"tip_inertia": -1.0}, "tip_inertia [kg m^2]"),
    ({"connection": "serial"}, "connection"),
    ({"substrate": "wood"}, "substrate"),
    ({"piezo": "PVDF"}, "piezo"),
    ({"piezo_modulus": 0.0}, "piezo_modulus [Pa]"),
    ({"substrate_density": -1.0}, "substrate_density [kg/m^3]"),
    ({"permittivity": 1e-12}, "permittivity [F/m]"),
    ({"d31": float("inf")}, "d31 [m/V]"),
])
def test_bad_beams_are_refused_naming_the_parameter(change, words):
    with pytest.raises(ValueError, match=words.replace("[", r"\[").replace("^", r"\^")):
        dataclasses.replace(PRESET, **change)


def test_bad_calls_are_refused():
    for n in (0, 9, 2.0, True):
        with pytest.raises(ValueError, match="number of modes"):
            modes(PRESET, n)
    with pytest.raises(ValueError, match=r"mu \[-\]"):
        eigenvalues(-1.0, 0.0, 3)
    with pytest.raises(ValueError, match=r"span position s \[m\]"):
        modes(PRESET, 2).shape([2 * PRESET.length])
    with pytest.raises(ValueError, match=r"frequency \[Hz\]"):
        modal_response(PRESET, 0.0, 1e5)
    with pytest.raises(ValueError, match=r"resistance \[Ohm\]"):
        exact_response(PRESET, 100.0, 0.0)
    with pytest.raises(ValueError, match=r"n_modes \[-\]"):
        modal_response(modes(PRESET, 3), 100.0, 1e5, n_modes=4)
    with pytest.raises(ValueError, match=r"amplitude \[m/s\^2\]"):
        modal_response(PRESET, 100.0, 1e5, amplitude=float("nan"))
    with pytest.raises(ValueError, match=r"mass_damping \[1/s\]"):
        exact_response(PRESET, 100.0, 1e5, mass_damping=-1.0)
    assert bimorph.MAX_MODES == 8
