"""The stop as a rod: a fixed-free bar vibrating along its axis, mode by mode.

A rod of length ``L_r`` [m] and cross-section ``A_r`` [m^2] stands on the shaking base, fixed
there at ``z = 0``; its free end ``z = L_r`` is the face the beam strikes. Its axial
displacement relative to the base is ``u(z, t) = sum_j psi_j(z) q_j(t)`` with the mass-
normalised modes of the fixed-free bar (``int_0^L_r rho A psi_i psi_j dz = delta_ij``)::

    psi_j(z) = sqrt(2 / (rho A L_r)) sin((2j - 1) pi z / (2 L_r))            [1/sqrt(kg)]
    Omega_j  = (2j - 1) pi / (2 L_r) sqrt(E / rho)                           [rad/s]
    q_j'' + 2 zeta_s Omega_j q_j' + Omega_j^2 q_j = psi_j(L_r) F_c + beta_j A sin(w t)
    beta_j   = rho A int_0^L_r psi_j dz = sqrt(2 rho A L_r) 2 / ((2j - 1) pi)  [sqrt(kg)]

``u_c = u(L_r)`` is positive in the direction the beam pushes the face (docs/model.md, "The
beam"). One mode is a mass on a spring: :func:`equivalent` gives it in the terms of the
existing stop on a spring (``stop_mass``, ``stop_support_stiffness``).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from .materials import MATERIALS

MAX_MODES = 8
"""The most rod modes :func:`rod_modes` gives. [-]"""


def _positive(name: str, unit: str, value) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} [{unit}] = {value!r}: must be a finite number > 0")


@dataclass(frozen=True)
class Rod:
    """A fixed-free rod, the stop the beam strikes.

    Attributes
    ----------
    length : float
        Length L_r from the base to the contact face. [m]
    area : float
        Cross-section A_r. [m^2]
    material : str
        A name in :data:`harvester_sweep.materials.MATERIALS`.
    modulus : float or None
        Young's modulus E_r; None: the material's. [Pa]
    density : float or None
        Density rho_r; None: the material's. [kg/m^3]
    damping_ratio : float
        Modal damping ratio zeta_s, the same for every mode, in [0, 1). [-]
    """

    length: float
    area: float
    material: str = "steel"
    modulus: float | None = None
    density: float | None = None
    damping_ratio: float = 0.0

    def __post_init__(self):
        _positive("rod length", "m", self.length)
        _positive("rod area", "m^2", self.area)
        if self.material not in MATERIALS:
            raise ValueError(f"rod material [-] = {self.material!r}: must be one of "
                             f"{', '.join(MATERIALS)}")
        if self.modulus is not None:
            _positive("rod modulus", "Pa", self.modulus)
        if self.density is not None:
            _positive("rod density", "kg/m^3", self.density)
        zeta = self.damping_ratio
        if isinstance(zeta, bool) or not isinstance(zeta, numbers.Real) \
                or not (math.isfinite(zeta) and 0 <= zeta < 1):
            raise ValueError(f"rod damping_ratio [-] = {zeta!r}: must be in [0, 1)")

    @property
    def youngs_modulus(self) -> float:
        """Young's modulus E_r in use (the override or the material's). [Pa]"""
        return MATERIALS[self.material].youngs_modulus if self.modulus is None else self.modulus

    @property
    def mass_density(self) -> float:
        """Density rho_r in use (the override or the material's). [kg/m^3]"""
        return MATERIALS[self.material].density if self.density is None else self.density

    @property
    def mass(self) -> float:
        """The rod's mass rho_r A_r L_r. [kg]"""
        return self.mass_density * self.area * self.length

    @property
    def wave_speed(self) -> float:
        """Bar wave speed sqrt(E_r / rho_r). [m/s]"""
        return math.sqrt(self.youngs_modulus / self.mass_density)


@dataclass(frozen=True, eq=False)
class RodModes:
    """The first modes of a :class:`Rod`, mass-normalised.

    Attributes
    ----------
    rod : Rod
        The rod.
    omega : numpy.ndarray (m,)
        Natural angular frequencies Omega_j. [rad/s]
    face : numpy.ndarray (m,)
        psi_j(L_r), the modes at the contact face, sqrt(2 / (rho A L_r)) (-1)^(j+1).
        [1/sqrt(kg)]
    forcing : numpy.ndarray (m,)
        beta_j = rho A int_0^L_r psi_j dz, the modes' share of the base's inertial load.
        [sqrt(kg)]
    damping_ratio : numpy.ndarray (m,)
        zeta_s of each mode. [-]
    """

    rod: Rod
    omega: np.ndarray
    face: np.ndarray
    forcing: np.ndarray
    damping_ratio: np.ndarray

    def shape(self, z) -> np.ndarray:
        """psi_j(z), (m, len(z)), z [m] from the base (0) to the face (L_r). [1/sqrt(kg)]"""
        z = np.atleast_1d(np.asarray(z, dtype=float))
        length = self.rod.length
        if not np.all((z >= 0) & (z <= length)):
            raise ValueError(f"rod position z [m] must lie in [0, {length!r}]")
        k = (2 * np.arange(1, len(self.omega) + 1) - 1) * np.pi / (2 * length)
        return math.sqrt(2.0 / self.rod.mass) * np.sin(k[:, None] * z[None, :])


def rod_modes(rod: Rod, m: int) -> RodModes:
    """The first ``m`` (1 to 8) axial modes of the fixed-free ``rod``.

    Returns
    -------
    RodModes
        Omega_j [rad/s], psi_j(L_r) [1/sqrt(kg)], beta_j [sqrt(kg)].
    """
    if isinstance(m, bool) or not isinstance(m, (int, np.integer)) or not 1 <= m <= MAX_MODES:
        raise ValueError(f"number of rod modes m [-] = {m!r}: must be an integer from 1 to "
                         f"{MAX_MODES}")
    odd = 2 * np.arange(1, m + 1) - 1.0
    omega = odd * np.pi / (2 * rod.length) * rod.wave_speed
    amplitude = math.sqrt(2.0 / rod.mass)
    face = amplitude * np.where(np.arange(m) % 2 == 0, 1.0, -1.0)  # sin((2j - 1) pi / 2)
    # int_0^L sin(k z) dz = (1 - cos(k L)) / k = 1 / k: cos((2j - 1) pi / 2) = 0
    forcing = rod.mass / rod.length * amplitude * 2 * rod.length / (odd * np.pi)
    return RodModes(rod, omega, face, forcing, np.full(m, float(rod.damping_ratio)))


@dataclass(frozen=True)
class RodEquivalent:
    """A rod's first mode as a mass on a spring (the existing stop on a spring).

    Attributes
    ----------
    mass : float
        m_s = 1 / psi_1(L_r)^2 = rho A L_r / 2. [kg]
    stiffness : float
        k_s = Omega_1^2 m_s = pi^2 E A / (8 L_r). [N/m]
    damping : float
        c_s = 2 zeta_s Omega_1 m_s. [N s/m]
    natural_frequency : float
        Omega_1 / (2 pi). [Hz]
    forcing_factor : float
        beta_1 psi_1(L_r) = 4 / pi: the one-mode rod feels ``m_s * forcing_factor * A
        sin(w t)`` from the base where a lumped mass on a spring feels ``m_s A sin(w t)``.
        [-]
    """

    mass: float
    stiffness: float
    damping: float
    natural_frequency: float
    forcing_factor: float

    def as_stop_parameters(self) -> dict:
        """The tip-mass model's moving-stop parameters: ``stop_mass`` [kg],
        ``stop_support_stiffness`` [N/m], ``stop_support_damping`` [N s/m] (the lumped
        stop's base forcing has no factor: ``forcing_factor`` is left out)."""
        return {"stop_mass": self.mass, "stop_support_stiffness": self.stiffness,
                "stop_support_damping": self.damping}


def equivalent(rod: Rod) -> RodEquivalent:
    """The one-mode lumped version of ``rod`` (:class:`RodEquivalent`: m_s [kg], k_s [N/m],
    c_s [N s/m], f_1 [Hz], beta_1 psi_1(L_r) [-])."""
    first = rod_modes(rod, 1)
    mass = 1.0 / first.face[0] ** 2
    omega = float(first.omega[0])
    return RodEquivalent(mass=mass, stiffness=omega**2 * mass,
                         damping=2 * rod.damping_ratio * omega * mass,
                         natural_frequency=omega / (2 * math.pi),
                         forcing_factor=float(first.forcing[0] * first.face[0]))
