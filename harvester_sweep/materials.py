"""Materials of the tip mass, the stop and the beam, and Hertz stiffness from two bodies.

Elastic constants: N. E. Dowling, *Mechanical Behavior of Materials*, 4th ed. (Pearson, 2013),
Table 5.2, which takes the metals from H. E. Boyer and T. L. Gall (eds.), *Metals Handbook Desk
Edition* (ASM, 1985), p. 216 -- the handbook the paper cites. Densities at room temperature:
*CRC Handbook of Chemistry and Physics*, 97th ed. (2016), "Density of solids" (pure metals), and
ASM Metals Handbook Desk Edition for steel and brass.

Piezoceramics (the bimorph's layers, harvester_sweep/bimorph.py): the manufacturers' data
sheets for PZT-5A and PZT-5H (Morgan Electro Ceramics, Piezo Systems), the constants A. Erturk
and D. J. Inman, *Piezoelectric Energy Harvesting* (Wiley, 2011) use for their bimorphs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    """Isotropic elastic material.

    Attributes
    ----------
    youngs_modulus : float
        Young's modulus E. [Pa]
    poissons_ratio : float
        Poisson's ratio nu. [-]
    density : float
        Mass density rho. [kg/m^3]
    source : str
        Where the values come from.
    """

    youngs_modulus: float
    poissons_ratio: float
    density: float
    source: str


_DOWLING = "Dowling (2013) Table 5.2 after Boyer & Gall (1985) p. 216"
MATERIALS: dict[str, Material] = {
    "copper": Material(130e9, 0.343, 8960.0, _DOWLING + "; density CRC Handbook"),
    "steel": Material(212e9, 0.293, 7850.0, _DOWLING + " (iron; mild steel); density ASM"),
    "aluminium": Material(70.3e9, 0.345, 2700.0, _DOWLING + "; density CRC Handbook"),
    "brass": Material(101e9, 0.350, 8530.0, _DOWLING + " (70Cu-30Zn); density ASM"),
    "titanium": Material(120e9, 0.361, 4506.0, _DOWLING + "; density CRC Handbook"),
    "tungsten": Material(411e9, 0.280, 19300.0, _DOWLING + "; density CRC Handbook"),
}


EPSILON_0 = 8.854187817e-12
"""Vacuum permittivity. [F/m]"""


@dataclass(frozen=True)
class PiezoMaterial:
    """Piezoelectric ceramic of a bending layer, poled through its thickness (3), strained
    along the beam (1).

    Attributes
    ----------
    youngs_modulus : float
        Young's modulus at constant electric field, Y_p = 1 / s11^E. [Pa]
    density : float
        Mass density rho_p. [kg/m^3]
    d31 : float
        Piezoelectric strain constant (negative for PZT: a field along the poling shortens
        the layer). [m/V]
    permittivity : float
        Permittivity at constant stress, eps33^T. [F/m]
    source : str
        Where the values come from.
    """

    youngs_modulus: float
    density: float
    d31: float
    permittivity: float
    source: str


_ERTURK = "manufacturer data sheet, as used by Erturk & Inman (2011)"
PIEZO_MATERIALS: dict[str, PiezoMaterial] = {
    # Y_p = 1 / s11^E with s11^E = 16.4e-12 m^2/N; eps33^T = 1700 eps_0
    "PZT-5A": PiezoMaterial(1.0 / 16.4e-12, 7750.0, -171e-12, 1700 * EPSILON_0,
                            _ERTURK + ": s11E 16.4e-12 m^2/N, eps33T/eps0 1700"),
    # s11^E = 16.5e-12 m^2/N; eps33^T = 3400 eps_0
    "PZT-5H": PiezoMaterial(1.0 / 16.5e-12, 7500.0, -274e-12, 3400 * EPSILON_0,
                            _ERTURK + ": s11E 16.5e-12 m^2/N, eps33T/eps0 3400"),
}


def equivalent_radius(mass: float, density: float) -> float:
    """Radius of the sphere of the same mass, R = (3 m / (4 pi rho))^(1/3). [m]

    Parameters
    ----------
    mass : float
        Body mass. [kg]
    density : float
        Body density. [kg/m^3]
    """
    return (3.0 * mass / (4.0 * math.pi * density)) ** (1.0 / 3.0)


def hertz_stiffness_from_bodies(
    mass_1: float, material_1: str, mass_2: float, material_2: str
) -> float:
    """Hertz stiffness of two bodies as equivalent spheres (Goldsmith). [N/m^1.5]

    ``k_h = 4 / (3 pi (h_1 + h_2)) * sqrt(R_1 R_2 / (R_1 + R_2))`` with
    ``h_i = (1 - nu_i^2) / (pi E_i)`` and ``R_i`` from :func:`equivalent_radius`
    (the paper's Eqs. 4-6 as corrected in docs/model.md: the square root and ``1 - nu^2``).

    Parameters
    ----------
    mass_1, mass_2 : float
        Masses of the two bodies. [kg]
    material_1, material_2 : str
        Names in :data:`MATERIALS`.
    """
    bodies = []
    for mass, name in ((mass_1, material_1), (mass_2, material_2)):
        if name not in MATERIALS:
            raise ValueError(f"material {name!r} is unknown: must be one of {', '.join(MATERIALS)}")
        if not (math.isfinite(mass) and mass > 0):
            raise ValueError(f"body mass {mass!r} [kg] must be a finite number > 0")
        material = MATERIALS[name]
        h = (1.0 - material.poissons_ratio**2) / (math.pi * material.youngs_modulus)
        bodies.append((h, equivalent_radius(mass, material.density)))
    (h1, r1), (h2, r2) = bodies
    return 4.0 / (3.0 * math.pi * (h1 + h2)) * math.sqrt(r1 * r2 / (r1 + r2))
