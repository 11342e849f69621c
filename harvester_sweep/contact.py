"""Contact damping laws of the Hertz family.

Every law here gives the damping factor of ``F_c = k_h delta^1.5 (1 + c_h v)`` as
``c_h = factor(e) / v_imp`` [s/m], with ``e`` the coefficient of restitution and ``v_imp``
the approach velocity [m/s] (docs/model.md):

- Lankarani-Nikravesh: ``3 (1 - e^2) / 4`` (the paper's law, Eq. 7 corrected);
- Hunt-Crossley: ``3 (1 - e) / 2``;
- Flores et al.: ``8 (1 - e) / (5 e)``;
- Gonthier et al.: ``(1 - e^2) / e``.

The approach velocity is either fixed (the paper holds it at 1.76e-3 m/s) or latched from
each impact's own velocity at first touch (the textbook use of these laws).
"""

from __future__ import annotations

CONTACT_LAWS = {
    "lankarani_nikravesh": lambda e: 0.75 * (1.0 - e * e),
    "hunt_crossley": lambda e: 1.5 * (1.0 - e),
    "flores": lambda e: 8.0 * (1.0 - e) / (5.0 * e),
    "gonthier": lambda e: (1.0 - e * e) / e,
}

IMPACT_VELOCITY_MODES = ("fixed", "latched")


def damping_factor(law: str, restitution: float) -> float:
    """Dimensionless factor ``c_h v_imp`` of a contact law. [-]

    Parameters
    ----------
    law : str
        A key of :data:`CONTACT_LAWS`.
    restitution : float
        Coefficient of restitution e, in (0, 1]. [-]
    """
    return CONTACT_LAWS[law](restitution)


def contact_damping(law: str, restitution: float, impact_velocity: float) -> float:
    """Contact damping ``c_h = factor(e) / v_imp``. [s/m]

    Parameters
    ----------
    law : str
        A key of :data:`CONTACT_LAWS`.
    restitution : float
        Coefficient of restitution e, in (0, 1]. [-]
    impact_velocity : float
        Approach velocity v_imp, > 0. [m/s]
    """
    return damping_factor(law, restitution) / impact_velocity


def contact_damping_of(p: dict, impact_velocity: float) -> float:
    """c_h [s/m] of a validated parameter set ``p``: ``contact_damping`` when given, else
    its law at the fixed ``impact_velocity`` of ``p`` or, in latched mode, at the given
    ``impact_velocity`` [m/s]."""
    if p["contact_damping"] is not None:
        return p["contact_damping"]
    velocity = p["impact_velocity"] if p["impact_velocity_mode"] == "fixed" else impact_velocity
    return contact_damping(p["contact_law"], p["restitution"], velocity)


def lower_stop(p: dict) -> dict | None:
    """The lower stop of parameter set ``p`` as a parameter set of its own, with it as the
    upper stop (gap, hertz_stiffness and restitution its own, the rest ``p``'s): the model
    is odd without its stops (docs/model.md). None without a lower stop."""
    if p["lower_gap"] is None:
        return None
    return {**p, "gap": p["lower_gap"],
            "hertz_stiffness": (p["hertz_stiffness"] if p["lower_hertz_stiffness"] is None
                                else p["lower_hertz_stiffness"]),
            "restitution": (p["restitution"] if p["lower_restitution"] is None
                            else p["lower_restitution"])}
