"""The stop as a rod: its modes against the fixed-free bar's closed form and quadrature, the
modal expansion of a rigid motion and of the static load, and the one-mode equivalent."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from harvester_sweep.bimorph import BEAM_PRESETS
from harvester_sweep.materials import MATERIALS
from harvester_sweep.rod import Rod, equivalent, rod_modes

STEEL = MATERIALS["steel"]
ROD = Rod(length=40e-3, area=math.pi * 2.5e-3**2, material="steel", damping_ratio=0.01)


def test_the_rod_modes_are_the_fixed_free_bar():
    modes = rod_modes(ROD, 8)
    c = math.sqrt(STEEL.youngs_modulus / STEEL.density)
    for j in range(1, 9):
        # the bar's frequencies: a quarter wavelength, three quarters, ... along the rod
        assert modes.omega[j - 1] == pytest.approx(2 * math.pi * (2 * j - 1) * c
                                                   / (4 * ROD.length), rel=1e-14)
    assert modes.omega[0] / (2 * math.pi) == pytest.approx(32.48e3, rel=1e-3)  # c / (4 L_r)
    mass = STEEL.density * ROD.area * ROD.length
    assert np.abs(modes.face) == pytest.approx(np.full(8, math.sqrt(2 / mass)), rel=1e-14)
    assert modes.face == pytest.approx(modes.shape(ROD.length)[:, 0], rel=1e-12)
    assert np.all(modes.damping_ratio == 0.01)


def test_the_rod_modes_are_orthonormal_and_their_forcing_is_their_integral():
    modes = rod_modes(ROD, 8)
    rho_a = STEEL.density * ROD.area
    for i in range(8):
        integral = quad(lambda z: modes.shape(z)[i, 0], 0, ROD.length, epsabs=0,
                        epsrel=1e-13)[0]
        assert modes.forcing[i] == pytest.approx(rho_a * integral, rel=1e-12)
        for j in range(i, 8):
            product = quad(lambda z: modes.shape(z)[i, 0] * modes.shape(z)[j, 0], 0,
                           ROD.length, epsabs=1e-13, epsrel=1e-13, limit=200)[0]
            assert rho_a * product == pytest.approx(float(i == j), abs=1e-12)


def test_a_rigid_rod_moves_with_the_base():
    """sum_j beta_j psi_j(L_r) -> 1: 4 / pi (1 - 1/3 + 1/5 - ...), Leibniz's series,
    alternating about 1 within its next term."""
    modes = rod_modes(ROD, 8)
    partial = np.cumsum(modes.forcing * modes.face)
    error = partial - 1
    assert np.all(np.sign(error) == np.where(np.arange(8) % 2 == 0, 1, -1))
    bound = 4 / (math.pi * (2 * np.arange(1, 9) + 1))
    assert np.all(np.abs(error) < bound)
    assert abs((partial[-1] + partial[-2]) / 2 - 1) < 3e-3  # the mean of two: 2.8e-3


def test_the_static_load_of_the_base_expands_onto_the_modes():
    """A steady base acceleration a compresses the rod by rho a L_r^2 / (2 E) at its face:
    sum_j psi_j(L_r) beta_j a / Omega_j^2 (falling like 1 / j^3)."""
    modes = rod_modes(ROD, 8)
    exact = STEEL.density * ROD.length**2 / (2 * STEEL.youngs_modulus)
    partial = np.cumsum(modes.face * modes.forcing / modes.omega**2)
    assert abs(partial[-1] / exact - 1) < 1e-3
    assert abs(partial[-1] / exact - 1) < abs(partial[0] / exact - 1) / 20


def test_the_one_mode_equivalent():
    lumped = equivalent(ROD)
    mass = STEEL.density * ROD.area * ROD.length
    assert lumped.mass == pytest.approx(mass / 2)
    assert lumped.stiffness == pytest.approx(math.pi**2 * STEEL.youngs_modulus * ROD.area
                                             / (8 * ROD.length))
    assert lumped.forcing_factor == pytest.approx(4 / math.pi)
    assert lumped.natural_frequency == pytest.approx(
        math.sqrt(lumped.stiffness / lumped.mass) / (2 * math.pi))
    assert lumped.damping == pytest.approx(2 * 0.01 * math.sqrt(lumped.stiffness * lumped.mass))
    assert lumped.as_stop_parameters() == {"stop_mass": lumped.mass,
                                           "stop_support_stiffness": lumped.stiffness,
                                           "stop_support_damping": lumped.damping}


def test_overrides_and_the_preset_rod():
    soft = Rod(length=0.05, area=1e-5, material="steel", modulus=1e9, density=1000.0)
    assert rod_modes(soft, 1).omega[0] == pytest.approx(math.pi / 0.1 * 1000.0)
    preset = BEAM_PRESETS["mak_rod"].rod
    assert preset.material == "steel" and 30e-3 <= preset.length <= 50e-3


@pytest.mark.parametrize("change, words", [
    ({"length": 0.0}, r"rod length \[m\]"),
    ({"area": -1.0}, r"rod area \[m\^2\]"),
    ({"material": "wood"}, r"rod material"),
    ({"modulus": float("inf")}, r"rod modulus \[Pa\]"),
    ({"density": 0.0}, r"rod density \[kg/m\^3\]"),
    ({"damping_ratio": 1.5}, r"rod damping_ratio \[-\]"),
])
def test_bad_rods_are_refused_naming_the_parameter(change, words):
    arguments = {"length": 0.04, "area": 2e-5, "material": "steel"} | change
    with pytest.raises(ValueError, match=words):
        Rod(**arguments)


def test_bad_mode_counts_are_refused():
    for m in (0, 9, 1.0, True):
        with pytest.raises(ValueError, match=r"number of rod modes m \[-\]"):
            rod_modes(ROD, m)
    with pytest.raises(ValueError, match=r"rod position z \[m\]"):
        rod_modes(ROD, 2).shape(-1e-3)
