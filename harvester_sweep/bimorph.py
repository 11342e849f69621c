"""The piezoelectric bimorph as a continuous beam: its modes, its linear response and its
one-mode reduction to the tip-mass model.

An Euler-Bernoulli cantilever of length ``L`` [m] clamped to the shaking base at ``s = 0``,
with a tip mass ``M_t`` [kg] (rotary inertia ``I_t`` [kg m^2]) at ``s = L``, two piezoceramic
layers over the whole length in series or in parallel across the load ``R`` [Ohm] (Erturk
and Inman's modal form; docs/model.md, "The beam"). Deflection relative to the base
``w(s, t) = sum_r phi_r(s) eta_r(t)``; under the base acceleration ``-A sin(w t)``::

    eta_r'' + 2 zeta_r omega_r eta_r' + omega_r^2 eta_r - chi_r V = gamma_r A sin(w t)
    C_p V' + V / R + sum_r chi_r eta_r' = 0
    chi_r = theta_b phi_r'(L),   gamma_r = m_b int_0^L phi_r ds + M_t phi_r(L)

The mode shapes are evaluated in a form without the cancellation of ``cos - cosh`` (see
:class:`Modes`), so that the eighth mode (``lambda`` near 23.6, ``cosh`` near 1e10) keeps
its digits. :func:`exact_response` solves the same linear problem as a boundary-value
problem, with no modal truncation: the modal sum converges to it.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq

from .materials import MATERIALS, PIEZO_MATERIALS
from .rod import Rod

MAX_MODES = 8
"""The most beam modes :func:`modes` gives. [-]"""

CONNECTIONS = ("series", "parallel")


def _number(name: str, unit: str, value, allowed: str, ok) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(value) or not ok(value):
        raise ValueError(f"{name} [{unit}] = {value!r}: must be a finite number {allowed}")


@dataclass(frozen=True)
class Bimorph:
    """A symmetric bimorph cantilever: a substrate between two equal piezoceramic layers.

    Attributes
    ----------
    length : float
        Length L from the clamp to the tip. [m]
    width : float
        Width b. [m]
    substrate_thickness : float
        Thickness h_s of the substrate. [m]
    piezo_thickness : float
        Thickness h_p of each of the two piezo layers. [m]
    substrate : str
        The substrate's material, a name in :data:`harvester_sweep.materials.MATERIALS`.
    piezo : str
        The layers' material, a name in :data:`harvester_sweep.materials.PIEZO_MATERIALS`.
    tip_mass : float
        Tip mass M_t, >= 0. [kg]
    tip_inertia : float
        Rotary inertia I_t of the tip mass about the tip, >= 0. [kg m^2]
    connection : str
        "series" or "parallel": how the two layers' electrodes are connected to the load.
    substrate_modulus, substrate_density, piezo_modulus, piezo_density : float or None
        Overrides of Y_s [Pa], rho_s [kg/m^3], Y_p = 1/s11^E [Pa], rho_p [kg/m^3]; None: the
        named material's.
    d31 : float or None
        Override of the piezoelectric constant d31 [m/V]; None: the material's.
    permittivity : float or None
        Override of eps33^T [F/m]; None: the material's.
    """

    length: float
    width: float
    substrate_thickness: float
    piezo_thickness: float
    substrate: str
    piezo: str
    tip_mass: float = 0.0
    tip_inertia: float = 0.0
    connection: str = "series"
    substrate_modulus: float | None = None
    substrate_density: float | None = None
    piezo_modulus: float | None = None
    piezo_density: float | None = None
    d31: float | None = None
    permittivity: float | None = None

    def __post_init__(self):
        positive = ("> 0", lambda v: v > 0)
        for name in ("length", "width", "substrate_thickness", "piezo_thickness"):
            _number(name, "m", getattr(self, name), *positive)
        if self.substrate not in MATERIALS:
            raise ValueError(f"substrate [-] = {self.substrate!r}: must be one of "
                             f"{', '.join(MATERIALS)}")
        if self.piezo not in PIEZO_MATERIALS:
            raise ValueError(f"piezo [-] = {self.piezo!r}: must be one of "
                             f"{', '.join(PIEZO_MATERIALS)}")
        _number("tip_mass", "kg", self.tip_mass, ">= 0", lambda v: v >= 0)
        _number("tip_inertia", "kg m^2", self.tip_inertia, ">= 0", lambda v: v >= 0)
        if self.connection not in CONNECTIONS:
            raise ValueError(f"connection [-] = {self.connection!r}: must be 'series' or "
                             f"'parallel'")
        for name, unit in (("substrate_modulus", "Pa"), ("substrate_density", "kg/m^3"),
                           ("piezo_modulus", "Pa"), ("piezo_density", "kg/m^3"),
                           ("permittivity", "F/m")):
            if getattr(self, name) is not None:
                _number(name, unit, getattr(self, name), *positive)
        if self.d31 is not None:
            _number("d31", "m/V", self.d31, "(either sign)", lambda v: True)
        if not self.permittivity_strain > 0:
            raise ValueError(
                f"permittivity [F/m] = {self._piezo('permittivity')!r}: must exceed "
                f"d31^2 Y_p = {self._piezo('d31') ** 2 * self._piezo('youngs_modulus')!r} "
                f"(eps33^S = eps33^T - d31^2 Y_p > 0)")

    # the constants in use: the override where given, else the named material's
    def _substrate(self, name: str) -> float:
        override = {"youngs_modulus": self.substrate_modulus,
                    "density": self.substrate_density}[name]
        return getattr(MATERIALS[self.substrate], name) if override is None else override

    def _piezo(self, name: str) -> float:
        override = {"youngs_modulus": self.piezo_modulus, "density": self.piezo_density,
                    "d31": self.d31, "permittivity": self.permittivity}[name]
        return getattr(PIEZO_MATERIALS[self.piezo], name) if override is None else override

    @property
    def mass_per_length(self) -> float:
        """m_b = b (rho_s h_s + 2 rho_p h_p). [kg/m]"""
        return self.width * (self._substrate("density") * self.substrate_thickness
                             + 2 * self._piezo("density") * self.piezo_thickness)

    @property
    def bending_stiffness(self) -> float:
        """YI = (2 b / 3) [Y_s h_s^3 / 8 + Y_p ((h_p + h_s/2)^3 - h_s^3 / 8)]. [N m^2]"""
        hs, hp = self.substrate_thickness, self.piezo_thickness
        return 2 * self.width / 3 * (self._substrate("youngs_modulus") * hs**3 / 8
                                     + self._piezo("youngs_modulus")
                                     * ((hp + hs / 2) ** 3 - hs**3 / 8))

    @property
    def e31(self) -> float:
        """Piezoelectric stress constant e31 = d31 Y_p (negative for PZT). [C/m^2]"""
        return self._piezo("d31") * self._piezo("youngs_modulus")

    @property
    def permittivity_strain(self) -> float:
        """Permittivity at constant strain eps33^S = eps33^T - d31^2 Y_p. [F/m]"""
        return self._piezo("permittivity") - self._piezo("d31") ** 2 * \
            self._piezo("youngs_modulus")

    @property
    def coupling(self) -> float:
        """Electromechanical coupling theta_b: |e31| b (h_p + h_s) / 2 in series, |e31| b (h_p +
        h_s) in parallel. [N/V]

        Taken positive: the sign of e31 and of the poling only choose the sign of V, and the
        tip-mass model's coupling is >= 0, so that the one-mode reduction is that model with
        the same sign of V."""
        theta = abs(self.e31) * self.width * (self.piezo_thickness + self.substrate_thickness)
        return theta / 2 if self.connection == "series" else theta

    @property
    def capacitance(self) -> float:
        """C_p: eps33^S b L / (2 h_p) in series, 2 eps33^S b L / h_p in parallel. [F]"""
        c = self.permittivity_strain * self.width * self.length / self.piezo_thickness
        return c / 2 if self.connection == "series" else 2 * c

    @property
    def mass_ratio(self) -> float:
        """mu = M_t / (m_b L). [-]"""
        return self.tip_mass / (self.mass_per_length * self.length)

    @property
    def inertia_ratio(self) -> float:
        """j = I_t / (m_b L^3). [-]"""
        return self.tip_inertia / (self.mass_per_length * self.length**3)


def _characteristic(lam, mu: float, j: float):
    """The transcendental equation of the modes divided by cosh(lambda) (same roots, no
    overflow): sech + cos + l mu (cos tanh - sin) - l^3 j (sin + tanh cos)
    + l^4 mu j (sech - cos). [-]"""
    lam = np.asarray(lam, dtype=float)
    sech = 2 * np.exp(-lam) / (1 + np.exp(-2 * lam))
    tanh = np.tanh(lam)
    cos, sin = np.cos(lam), np.sin(lam)
    return (sech + cos + lam * mu * (cos * tanh - sin) - lam**3 * j * (sin + tanh * cos)
            + lam**4 * mu * j * (sech - cos))


def eigenvalues(mu: float, j: float, n: int) -> np.ndarray:
    """The first ``n`` roots lambda_r of the cantilever's transcendental equation [-]::

        1 + cos l cosh l + l mu (cos l sinh l - sin l cosh l)
          - l^3 j (cosh l sin l + sinh l cos l) + l^4 mu j (1 - cos l cosh l) = 0

    Parameters
    ----------
    mu : float
        Tip-mass ratio M_t / (m_b L), >= 0. [-]
    j : float
        Rotary-inertia ratio I_t / (m_b L^3), >= 0. [-]
    n : int
        How many roots, >= 1.

    The roots are bracketed by a scan (steps of 0.002, finer near 0 where a heavy tip mass
    brings the first root) and found by Brent's method. A tip mass and inertia only lower
    the clamped-free eigenvalues, and the r-th clamped-free root is below (2r - 1) pi / 2
    + 0.31, so the scan to (2n - 1) pi / 2 + 1 holds the first n roots.
    """
    _number("mu", "-", mu, ">= 0", lambda v: v >= 0)
    _number("j", "-", j, ">= 0", lambda v: v >= 0)
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
        raise ValueError(f"number of eigenvalues n [-] = {n!r}: must be an integer >= 1")
    top = (2 * n - 1) * math.pi / 2 + 1.0
    grid = np.unique(np.concatenate([[0.0], np.geomspace(1e-4, 0.5, 400),
                                     np.arange(0.5, top, 0.002), [top]]))
    values = _characteristic(grid, mu, j)
    roots = []
    for i in np.nonzero(np.sign(values[:-1]) * np.sign(values[1:]) <= 0)[0]:
        a, b = grid[i], grid[i + 1]
        if values[i] == 0:
            root = a
        elif values[i + 1] == 0:
            continue  # found as the left end of the next interval
        else:
            root = brentq(_characteristic, a, b, args=(mu, j), xtol=1e-15, rtol=8.9e-16,
                          maxiter=200)
        if root > 0:
            roots.append(root)
        if len(roots) == n:
            break
    if len(roots) < n:
        raise ValueError(f"found {len(roots)} of the {n} eigenvalues below {top:.3f} "
                         f"(mu = {mu!r}, j = {j!r})")
    return np.array(roots)


@dataclass(frozen=True, eq=False)
class Modes:
    """The first n short-circuit modes of a :class:`Bimorph`, mass-normalised so that
    ``int_0^L m_b phi_r phi_q ds + M_t phi_r(L) phi_q(L) + I_t phi_r'(L) phi_q'(L) = delta_rq``
    and ``phi_r(L) > 0``.

    With ``x = lambda_r s / L`` the mode is written without cancellation::

        phi_r(s) = A_r [cos x + sigma_r sin x - P_r e^(x - lambda_r) - Q_r e^(-x)]

    (``cos x - cosh x + sigma (sin x - sinh x)`` rewritten: ``P = (1 + sigma) e^lambda / 2``,
    ``Q = (1 - sigma) / 2``, and ``1 + sigma`` computed from a sum of bounded terms).

    Attributes
    ----------
    beam : Bimorph
        The beam.
    eigenvalues : numpy.ndarray (n,)
        lambda_r. [-]
    omega : numpy.ndarray (n,)
        Short-circuit natural angular frequencies lambda_r^2 sqrt(YI / (m_b L^4)). [rad/s]
    sigma : numpy.ndarray (n,)
        sigma_r of the mode shape. [-]
    amplitude : numpy.ndarray (n,)
        A_r, the normalisation (signed so that phi_r(L) > 0). [1/sqrt(kg)]
    growth, decay : numpy.ndarray (n,)
        P_r and Q_r of the stable form. [-]
    tip, tip_slope, root_curvature : numpy.ndarray (n,)
        phi_r(L) [1/sqrt(kg)], phi_r'(L) [1/(m sqrt(kg))], phi_r''(0) [1/(m^2 sqrt(kg))].
    coupling : numpy.ndarray (n,)
        chi_r = theta_b phi_r'(L). [N/(V sqrt(kg))]
    forcing : numpy.ndarray (n,)
        gamma_r = m_b int_0^L phi_r ds + M_t phi_r(L). [sqrt(kg)]
    """

    beam: Bimorph
    eigenvalues: np.ndarray
    omega: np.ndarray
    sigma: np.ndarray
    amplitude: np.ndarray
    growth: np.ndarray = field(repr=False)
    decay: np.ndarray = field(repr=False)
    tip: np.ndarray = field(init=False)
    tip_slope: np.ndarray = field(init=False)
    root_curvature: np.ndarray = field(init=False)
    coupling: np.ndarray = field(init=False)
    forcing: np.ndarray = field(init=False)

    def __post_init__(self):
        beam = self.beam
        length = beam.length
        tip = self.shape(length)[:, 0]
        tip_slope = self.slope(length)[:, 0]
        lam, sigma, p, q = self.eigenvalues, self.sigma, self.growth, self.decay
        decayed = np.exp(-lam)
        integral = length / lam * self.amplitude * (
            np.sin(lam) + sigma * (1 - np.cos(lam)) - (p + q) * (1 - decayed))
        object.__setattr__(self, "tip", tip)
        object.__setattr__(self, "tip_slope", tip_slope)
        object.__setattr__(self, "root_curvature", self.curvature(0.0)[:, 0])
        object.__setattr__(self, "coupling", beam.coupling * tip_slope)
        object.__setattr__(self, "forcing",
                           beam.mass_per_length * integral + beam.tip_mass * tip)

    def derivative(self, s, order: int) -> np.ndarray:
        """d^order phi_r / ds^order at ``s`` [m] (0 <= s <= L), shape (n, len(s)), order 0 to
        3. [1/(m^order sqrt(kg))]"""
        if order not in (0, 1, 2, 3):
            raise ValueError(f"derivative order [-] = {order!r}: must be 0, 1, 2 or 3")
        s = np.atleast_1d(np.asarray(s, dtype=float))
        length = self.beam.length
        if not np.all((s >= 0) & (s <= length)):
            raise ValueError(f"span position s [m] must lie in [0, {length!r}] (the beam's "
                             f"length)")
        lam = self.eigenvalues[:, None]
        x = lam * s[None, :] / length
        angle = x + order * math.pi / 2
        trig = np.cos(angle) + self.sigma[:, None] * np.sin(angle)
        hyper = -self.growth[:, None] * np.exp(x - lam) \
            - (-1) ** order * self.decay[:, None] * np.exp(-x)
        return (self.amplitude[:, None] * (lam / length) ** order) * (trig + hyper)

    def shape(self, s) -> np.ndarray:
        """phi_r(s), (n, len(s)), s [m] from the clamp. [1/sqrt(kg)]"""
        return self.derivative(s, 0)

    def slope(self, s) -> np.ndarray:
        """phi_r'(s), (n, len(s)). [1/(m sqrt(kg))]"""
        return self.derivative(s, 1)

    def curvature(self, s) -> np.ndarray:
        """phi_r''(s), (n, len(s)). [1/(m^2 sqrt(kg))]"""
        return self.derivative(s, 2)


_GAUSS = np.polynomial.legendre.leggauss(96)


def modes(beam: Bimorph, n: int) -> Modes:
    """The first ``n`` (1 to 8) short-circuit modes of ``beam`` (:class:`Modes`).

    The normalisation integral ``int_0^L phi^2 ds`` is taken by 96-point Gauss-Legendre
    quadrature on each of four panels: the integrand is smooth, with at most four
    oscillations, so the rule is exact to rounding."""
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or not 1 <= n <= MAX_MODES:
        raise ValueError(f"number of modes n [-] = {n!r}: must be an integer from 1 to "
                         f"{MAX_MODES}")
    return _modes(beam, n)


def _modes(beam: Bimorph, n: int) -> Modes:
    """:func:`modes` without its cap on n (the tests' convergence studies take up to 64;
    four panels of 96 points integrate up to about 60 modes' oscillations exactly)."""
    mu, j = beam.mass_ratio, beam.inertia_ratio
    lam = eigenvalues(mu, j, n)
    cos, sin, decayed = np.cos(lam), np.sin(lam), np.exp(-lam)
    # sigma from the shear condition at the tip; its denominator D = cos + cosh + l mu (sinh -
    # sin) is > 0 for l > 0. D e^-l and (1 + sigma) D are sums of bounded terms, so P =
    # (1 + sigma) e^l / 2 keeps its digits where 1 + sigma ~ e^-l
    d_scaled = cos * decayed + (1 + decayed**2) / 2 + lam * mu * (
        (1 - decayed**2) / 2 - sin * decayed)
    sigma = (sin * decayed - (1 - decayed**2) / 2 + lam * mu * (
        cos * decayed - (1 + decayed**2) / 2)) / d_scaled
    one_plus = cos + sin + decayed + lam * mu * (cos - sin - decayed)
    growth = one_plus / (2 * d_scaled)
    decay = (1 - sigma) / 2
    ones = np.ones(n)
    unit = Modes(beam, lam, np.zeros(n), sigma, ones, growth, decay)
    length = beam.length
    # int_0^L phi^2 ds for A_r = 1, on four panels
    edges = np.linspace(0.0, length, 5)
    nodes = ((edges[:-1, None] + edges[1:, None]) / 2
             + (edges[1:, None] - edges[:-1, None]) / 2 * _GAUSS[0][None, :]).ravel()
    weights = np.tile(_GAUSS[1] * (length / 8), 4)
    integral = (unit.shape(nodes) ** 2) @ weights
    norm = (beam.mass_per_length * integral + beam.tip_mass * unit.shape(length)[:, 0] ** 2
            + beam.tip_inertia * unit.slope(length)[:, 0] ** 2)
    amplitude = np.sign(unit.shape(length)[:, 0]) / np.sqrt(norm)
    omega = lam**2 * math.sqrt(beam.bending_stiffness / (beam.mass_per_length * length**4))
    return Modes(beam, lam, omega, sigma, amplitude, growth, decay)


@dataclass(frozen=True)
class TipMassEquivalent:
    """The one-mode reduction of a beam that strikes at its tip: the tip-mass model.

    Attributes
    ----------
    mass : float
        m_eq = 1 / phi_1(L)^2. [kg]
    stiffness : float
        k_eq = omega_1^2 m_eq. [N/m]
    natural_frequency : float
        omega_1 / (2 pi), short circuit. [Hz]
    coupling : float
        theta_eq = chi_1 / phi_1(L). [N/V]
    capacitance : float
        C_p. [F]
    forcing_factor : float
        mu_1 = gamma_1 phi_1(L): the base forcing is m_eq mu_1 A sin(w t). [-]
    """

    mass: float
    stiffness: float
    natural_frequency: float
    coupling: float
    capacitance: float
    forcing_factor: float


def reduction(beam: Bimorph) -> TipMassEquivalent:
    """The one-mode reduction of ``beam`` at its tip (:class:`TipMassEquivalent`): with
    ``x = phi_1(L) eta_1`` the first modal equation is ``m_eq x'' + c x' + k_eq x -
    theta_eq V = m_eq mu_1 A sin(w t)``."""
    first = modes(beam, 1)
    tip = float(first.tip[0])
    mass = 1.0 / tip**2
    omega = float(first.omega[0])
    return TipMassEquivalent(mass=mass, stiffness=omega**2 * mass,
                             natural_frequency=omega / (2 * math.pi),
                             coupling=float(first.coupling[0]) / tip,
                             capacitance=beam.capacitance,
                             forcing_factor=float(first.forcing[0]) * tip)


def as_tip_mass_parameters(beam: Bimorph, **extra) -> dict:
    """The tip-mass model's parameters of ``beam``'s one-mode reduction: ``mass`` [kg],
    ``natural_frequency`` [Hz], ``coupling`` [N/V], ``capacitance`` [F] and
    ``base_forcing_factor`` mu_1 [-], updated with ``extra`` (any other parameter)."""
    equivalent = reduction(beam)
    return {"mass": equivalent.mass, "natural_frequency": equivalent.natural_frequency,
            "coupling": equivalent.coupling, "capacitance": equivalent.capacitance,
            "base_forcing_factor": equivalent.forcing_factor, **extra}


def rayleigh_damping_ratios(omega, mass_damping: float, stiffness_damping: float):
    """Modal damping ratios of Rayleigh damping, zeta_r = alpha / (2 omega_r) + beta omega_r /
    2 [-], for ``omega`` [rad/s], ``mass_damping`` alpha [1/s] and ``stiffness_damping`` beta
    [s]: the damping :func:`exact_response` takes, as :func:`modal_response` takes it."""
    omega = np.asarray(omega, dtype=float)
    return mass_damping / (2 * omega) + stiffness_damping * omega / 2


def _frequency_and_load(frequency, resistance, amplitude):
    frequency = np.asarray(frequency, dtype=float)
    if not np.all(np.isfinite(frequency) & (frequency > 0)):
        raise ValueError("frequency [Hz] must be finite and > 0")
    if isinstance(resistance, bool) or not isinstance(resistance, numbers.Real) \
            or not resistance > 0 or math.isnan(resistance):
        raise ValueError(f"resistance [Ohm] = {resistance!r}: must be > 0 (inf: open circuit)")
    _number("amplitude", "m/s^2", amplitude, "(either sign)", lambda v: True)
    return 2 * np.pi * frequency, 1.0 / resistance


def modal_response(beam, frequency, resistance: float, *, n_modes: int | None = None,
                   damping_ratio=0.0, amplitude: float = 1.0, s=None):
    """The steady state of the N-mode model with no stop, as a sum of modal phasors.

    ``w(s, t) = Im(W(s) e^{i w t})`` (relative to the base) and ``V(t) = Im(V e^{i w t})``
    under the base acceleration ``-A sin(w t)``::

        (omega_r^2 - w^2 + 2 i zeta_r omega_r w) H_r - chi_r V = gamma_r A
        (1/R + i w C_p) V + i w sum_r chi_r H_r = 0,      W(s) = sum_r phi_r(s) H_r

    Parameters
    ----------
    beam : Bimorph or Modes
        The beam, or its modes (then ``n_modes`` of them are used).
    frequency : float or numpy.ndarray
        Excitation frequency f > 0. [Hz]
    resistance : float
        Load R > 0; inf: open circuit. [Ohm]
    n_modes : int or None
        Modes in the sum, 1 to 8; None: all of ``beam``'s if it is a Modes, else 8. [-]
    damping_ratio : float or sequence
        zeta_r, one for all modes or one per mode. [-]
    amplitude : float
        Base acceleration amplitude A. [m/s^2]
    s : float or numpy.ndarray or None
        Span positions [m]; None: the tip.

    Returns
    -------
    W : complex numpy.ndarray, shape frequency.shape + s.shape
        Deflection amplitude relative to the base. [m]
    V : complex numpy.ndarray, shape frequency.shape
        Voltage amplitude; the mean power is |V|^2 / (2 R). [V]
    """
    if isinstance(beam, Modes):
        shapes = beam
        n = len(shapes.omega) if n_modes is None else n_modes
        if isinstance(n, bool) or not isinstance(n, numbers.Integral) \
                or not 1 <= n <= len(shapes.omega):
            raise ValueError(f"n_modes [-] = {n_modes!r}: must be an integer from 1 to "
                             f"{len(shapes.omega)} (the modes given)")
    else:
        n = MAX_MODES if n_modes is None else n_modes
        shapes = modes(beam, n)
    bimorph = shapes.beam
    w, conductance = _frequency_and_load(frequency, resistance, amplitude)
    zeta = np.broadcast_to(np.asarray(damping_ratio, dtype=float), (n,))
    if not np.all(np.isfinite(zeta) & (zeta >= 0)):
        raise ValueError("damping_ratio [-] must be finite and >= 0")
    omega, chi, gamma = shapes.omega[:n], shapes.coupling[:n], shapes.forcing[:n]
    wc = w[..., None]
    receptance = 1.0 / (omega**2 - wc**2 + 2j * zeta * omega * wc)
    admittance = conductance + 1j * w * bimorph.capacitance
    voltage = -1j * w * amplitude * (receptance @ (chi * gamma)) \
        / (admittance + 1j * w * (receptance @ chi**2))
    h = receptance * (gamma * amplitude + chi * voltage[..., None])
    position = bimorph.length if s is None else s
    phi = shapes.shape(np.ravel(position))[:n]
    deflection = (h @ phi).reshape(w.shape + np.shape(position))
    return deflection, voltage


def exact_response(beam: Bimorph, frequency, resistance: float, *, amplitude: float = 1.0,
                   s=None, mass_damping: float = 0.0, stiffness_damping: float = 0.0):
    """The steady state with no stop from the distributed-parameter boundary-value problem,
    no modal truncation.

    With ``w(s, t) = Im(W(s) e^{i w t})``, ``V(t) = Im(V e^{i w t})``, ``W2 = w^2 - i w alpha``
    and ``YI* = YI (1 + i w beta)``::

        YI* W'''' - W2 m_b W = m_b A                          0 < s < L
        W(0) = 0,  W'(0) = 0                                  (the clamp)
        YI* W''(L) - W2 I_t W'(L) - theta_b V = 0             (moment: tip inertia, piezo)
        -YI* W'''(L) - W2 M_t W(L) = M_t A                    (shear: tip mass)
        (1/R + i w C_p) V + i w theta_b W'(L) = 0             (the circuit)

    ``W = c1 cos ks + c2 sin ks + c3 e^(-ks) + c4 e^(k(s - L)) - A / W2``, ``k^4 = W2 m_b /
    YI*``: one 5 x 5 complex solve per frequency, with the bounded exponentials in place of
    cosh and sinh. The piezo layers' moment theta_b V acts at the tip alone: over electrodes
    covering the whole length its distributed form integrates to theta_b V phi'(L), the
    modal equations' chi_r V.

    Damping is Rayleigh damping on the relative motion, ``alpha`` (``mass_damping`` [1/s], on
    the beam's, the tip mass's and its rotary inertia's) and ``beta`` (``stiffness_damping``
    [s]): exactly the modal model with ``zeta_r = alpha / (2 omega_r) + beta omega_r / 2``
    (:func:`rayleigh_damping_ratios`). A common zeta for all modes has no such
    distributed form; zero (the default) leaves the load as the only damping.

    Parameters and returns as :func:`modal_response` (amplitude [m/s^2], s [m]; W [m], V [V]).
    """
    w, conductance = _frequency_and_load(frequency, resistance, amplitude)
    _number("mass_damping", "1/s", mass_damping, ">= 0", lambda v: v >= 0)
    _number("stiffness_damping", "s", stiffness_damping, ">= 0", lambda v: v >= 0)
    length = beam.length
    position = np.ravel(length if s is None else s).astype(float)
    if not np.all((position >= 0) & (position <= length)):
        raise ValueError(f"span position s [m] must lie in [0, {length!r}]")
    m, yi = beam.mass_per_length, beam.bending_stiffness
    theta, cap = beam.coupling, beam.capacitance
    tip_mass, tip_inertia = beam.tip_mass, beam.tip_inertia
    w = w.ravel()
    w2 = w**2 - 1j * w * mass_damping
    stiff = yi * (1 + 1j * w * stiffness_damping)
    k = (w2 * m / stiff) ** 0.25  # principal root: Re k > 0, the exponentials decay inward
    kl = k * length
    cos, sin, e = np.cos(kl), np.sin(kl), np.exp(-kl)
    particular = -amplitude / w2
    r_inertia = w2 * tip_inertia / (stiff * k)
    r_mass = w2 * tip_mass / (stiff * k**3)
    zero, one = np.zeros_like(k), np.ones_like(k)
    coupled = 1j * w * theta * k
    matrix = np.stack([
        np.stack([one, zero, one, e, zero], -1),                       # W(0) = 0
        np.stack([zero, one, -one, e, zero], -1),                      # W'(0) / k = 0
        np.stack([-cos + r_inertia * sin, -sin - r_inertia * cos,      # moment / (YI* k^2)
                  e * (1 + r_inertia), 1 - r_inertia, -theta / (stiff * k**2)], -1),
        np.stack([sin + r_mass * cos, -cos + r_mass * sin,             # shear / (-YI* k^3)
                  e * (r_mass - 1), 1 + r_mass, zero], -1),
        np.stack([-coupled * sin, coupled * cos, -coupled * e,         # the circuit
                  coupled, conductance + 1j * w * cap], -1),
    ], -2)
    rhs = np.stack([-particular, zero, zero,
                    -(tip_mass * amplitude + w2 * tip_mass * particular) / (stiff * k**3),
                    zero], -1)
    # equilibrate rows and the voltage's column: metres and volts differ by orders
    rows = np.max(np.abs(matrix), axis=-1, keepdims=True)
    matrix, rhs = matrix / rows, rhs / rows[..., 0]
    column = np.max(np.abs(matrix[..., 4]), axis=-1)
    matrix[..., 4] /= column[:, None]
    solution = np.linalg.solve(matrix, rhs[..., None])[..., 0]
    c1, c2, c3, c4 = (solution[:, i, None] for i in range(4))
    voltage = solution[:, 4] / column
    ks = k[:, None] * position[None, :]
    deflection = (c1 * np.cos(ks) + c2 * np.sin(ks) + c3 * np.exp(-ks)
                  + c4 * np.exp(ks - kl[:, None]) + particular[:, None])
    shape = np.shape(frequency)
    return (deflection.reshape(shape + np.shape(length if s is None else s)),
            voltage.reshape(shape))


class BeamPreset(NamedTuple):
    """A beam scene: the beam, the stop it strikes and where.

    Attributes
    ----------
    beam : Bimorph
        The beam.
    rod : Rod or None
        The stop as a rod; None: the rigid (or lumped) stop of the tip-mass model.
    contact_position : float
        Span position s_c of the contact, 0 < s_c <= L. [m]
    """

    beam: Bimorph
    rod: Rod | None
    contact_position: float


# A PZT-5A bimorph on brass, 10 mm wide, 0.2 mm brass between two 0.25 mm layers, in series;
# length and tip mass solved (scipy.optimize) for the one-mode reduction of Table 1, 150 Hz
# and m_eq = 2.5 g, then rounded to four digits (docs/model.md, "The beam")
_TABLE_1_BEAM = Bimorph(length=28.81e-3, width=10e-3, substrate_thickness=0.2e-3,
                        piezo_thickness=0.25e-3, substrate="brass", piezo="PZT-5A",
                        tip_mass=2.118e-3, tip_inertia=0.0, connection="series")

BEAM_PRESETS: dict[str, BeamPreset] = {
    # the tip mass strikes (the paper's scene, Table 1's stop)
    "bimorph_tip": BeamPreset(_TABLE_1_BEAM, None, _TABLE_1_BEAM.length),
    # the beam strikes at 0.8 L a steel rod 40 mm long, 5 mm across (as Mak et al.)
    "mak_rod": BeamPreset(_TABLE_1_BEAM,
                          Rod(length=40e-3, area=math.pi * (2.5e-3) ** 2, material="steel"),
                          0.8 * _TABLE_1_BEAM.length),
}
