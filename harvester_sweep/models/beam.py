"""The beam model, declared once: a bimorph cantilever in N bending modes striking a stop
at a span position, the stop rigid or a rod in M longitudinal modes, as one linear system
with Hertz contact surfaces.

State (:func:`state`): the modal coordinates ``eta_1..eta_N`` [m sqrt(kg)] and their
rates, the voltage across the load [V], and with a rod its modal coordinates ``q_1..q_M``
[m sqrt(kg)] and their rates::

    eta_r'' + 2 zeta_r w_r eta_r' + w_r^2 eta_r - chi_r V = gamma_r a(t) - phi_r(s_c) F_c
    C_p V' + V / R + sum_r chi_r eta_r' = 0
    q_j'' + 2 zeta_s W_j q_j' + W_j^2 q_j = psi_j F_c + beta_j a(t)

with ``a(t) = A sin(w t)`` and ``F_c`` the one Hertz law (:mod:`.hertz`) at the
penetration ``w(s_c) - g - u_c`` (``u_c = sum_j psi_j q_j``, the rod face) and its rate.
A second stop below, at ``w(s_c) = -g_l``, pushes the other way with the same law.

The whole model is ``y' = M y + f a(t) + sum_s b_s F_s``, each contact surface ``s`` a
penetration ``c_s . y - g_s`` whose rate is ``c_s . M y`` (the force does not reach the
penetration's rate directly: it acts on accelerations). The modal engine
(``_engine.modal``) integrates exactly this form, whatever the model: out of contact by
the exact flow of the linear system, in contact by RK4 in the frame of that flow. So the
declaration is :func:`modal_system`: the matrices, from the modal quantities that
``harvester_sweep.bimorph`` and ``harvester_sweep.rod`` compute; and the outputs the
engine books are linear functionals of the state (:func:`outputs`).

numpy only: this module sits below the engine with the other models.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from .state import Component

#: The linear system with its contact surfaces and booked outputs, in SI units: ``matrix``
#: M (D, D) [1/s, ...]; ``forcing`` f (D,) (times a(t) [m/s^2]); ``surfaces`` (S, D): the
#: penetrations' functionals c_s [m per state unit]; ``gaps`` (S,) [m]; ``inputs`` (S, D):
#: where a unit force of each surface enters the state's rates b_s [per N];
#: ``outputs`` (O, D): the booked outputs' functionals; ``output_names`` (O,).
LinearSystem = namedtuple("LinearSystem", ("matrix", "forcing", "surfaces", "gaps", "inputs",
                                           "outputs", "output_names"))

#: The outputs every beam books, in order, before the modal coordinates: the tip's and the
#: contact point's displacement [m], the voltage [V], the root strain at the outer piezo
#: surface [-] and the rod face's displacement [m] (0 with a rigid stop).
OUTPUTS = ("tip_displacement", "contact_displacement", "voltage", "root_strain", "stop_face")


def state(n_modes: int, rod_modes: int = 0) -> tuple:
    """The state's components, in order, for ``n_modes`` bending modes and ``rod_modes``
    modes of a rod stop (0: a rigid stop)."""
    comps = [Component(f"eta_{r}", "m kg^0.5", "displacement", f"bending mode {r}")
             for r in range(1, n_modes + 1)]
    comps += [Component(f"eta_{r}_rate", "m kg^0.5/s", "velocity", f"rate of bending mode {r}")
              for r in range(1, n_modes + 1)]
    comps.append(Component("voltage", "V", "voltage", "voltage across the load"))
    comps += [Component(f"q_{j}", "m kg^0.5", "displacement", f"rod mode {j}")
              for j in range(1, rod_modes + 1)]
    comps += [Component(f"q_{j}_rate", "m kg^0.5/s", "velocity", f"rate of rod mode {j}")
              for j in range(1, rod_modes + 1)]
    return tuple(comps)


def modal_system(omega, zeta, chi, gamma, phi_tip, phi_contact, root_strain, capacitance,
                  resistance, gap, lower_gap=None, rod_omega=(), rod_zeta=0.0, rod_face=(),
                  rod_forcing=()) -> LinearSystem:
    """The beam as ``y' = M y + f a(t) + sum_s b_s F_s`` with its contact surfaces.

    omega (N,) [rad/s], zeta (N,) [-], chi (N,) [N/(V kg^0.5)], gamma (N,) [kg^0.5]:
    the bending modes' short-circuit frequencies, damping ratios, couplings and base
    forcings; phi_tip, phi_contact (N,) [1/kg^0.5]: the mode shapes at the tip and at
    the contact point; root_strain (N,) [1/(m kg^0.5)]: strain at the root's outer piezo
    surface per unit modal coordinate; capacitance [F]; resistance [Ohm]; gap [m];
    lower_gap [m] or None: a rigid stop below at the contact point; rod_omega (M,)
    [rad/s], rod_zeta [-], rod_face (M,) [1/kg^0.5], rod_forcing (M,) [kg^0.5]: the rod's
    modes (M = 0: a rigid stop).
    """
    omega, zeta, chi, gamma = (np.asarray(a, dtype=float) for a in (omega, zeta, chi, gamma))
    rod_omega, rod_face, rod_forcing = (np.asarray(a, dtype=float).reshape(-1)
                                        for a in (rod_omega, rod_face, rod_forcing))
    n, m = len(omega), len(rod_omega)
    d = 2 * n + 1 + 2 * m
    eta, rate, volt = np.arange(n), n + np.arange(n), 2 * n
    q, q_rate = 2 * n + 1 + np.arange(m), 2 * n + 1 + m + np.arange(m)
    M = np.zeros((d, d))
    M[eta, rate] = 1.0
    M[rate, eta] = -omega ** 2
    M[rate, rate] = -2.0 * zeta * omega
    M[rate, volt] = chi
    M[volt, volt] = -1.0 / (resistance * capacitance)
    M[volt, rate] = -chi / capacitance
    M[q, q_rate] = 1.0
    M[q_rate, q] = -rod_omega ** 2
    M[q_rate, q_rate] = -2.0 * rod_zeta * rod_omega
    f = np.zeros(d)
    f[rate] = gamma
    f[q_rate] = rod_forcing
    upper = np.zeros(d)
    upper[eta] = phi_contact
    upper[q] = -rod_face
    push = np.zeros(d)
    push[rate] = -np.asarray(phi_contact, dtype=float)
    push[q_rate] = rod_face
    surfaces, gaps, inputs = [upper], [gap], [push]
    if lower_gap is not None:
        lower = np.zeros(d)
        lower[eta] = -np.asarray(phi_contact, dtype=float)
        lift = np.zeros(d)
        lift[rate] = phi_contact
        surfaces.append(lower)
        gaps.append(lower_gap)
        inputs.append(lift)
    out = np.zeros((len(OUTPUTS) + n, d))
    out[0, eta] = phi_tip
    out[1, eta] = phi_contact
    out[2, volt] = 1.0
    out[3, eta] = root_strain
    out[4, q] = rod_face
    out[len(OUTPUTS) + np.arange(n), eta] = 1.0
    names = OUTPUTS + tuple(f"eta_{r}" for r in range(1, n + 1))
    return LinearSystem(M, f, np.array(surfaces), np.array(gaps, dtype=float),
                        np.array(inputs), out, names)


def tip_mass_system(mass, stiffness, damping, coupling, capacitance, resistance, gap,
                    forcing_factor=1.0, lower_gap=None) -> LinearSystem:
    """The tip-mass model ``(x, v, V)`` in the same form (m [kg], k [N/m], c [N s/m],
    theta [N/V], C_p [F], R [Ohm], g [m], mu_1 [-]): the one-mode beam striking at its
    tip is this system in the coordinate ``x = phi_1(L) eta_1``."""
    M = np.array([[0.0, 1.0, 0.0],
                  [-stiffness / mass, -damping / mass, coupling / mass],
                  [0.0, -coupling / capacitance, -1.0 / (resistance * capacitance)]])
    f = np.array([0.0, forcing_factor, 0.0])
    surfaces, gaps, inputs = [[1.0, 0.0, 0.0]], [gap], [[0.0, -1.0 / mass, 0.0]]
    if lower_gap is not None:
        surfaces.append([-1.0, 0.0, 0.0])
        gaps.append(lower_gap)
        inputs.append([0.0, 1.0 / mass, 0.0])
    out = np.zeros((len(OUTPUTS), 3))
    out[0, 0] = out[1, 0] = 1.0
    out[2, 2] = 1.0
    return LinearSystem(M, f, np.array(surfaces, dtype=float), np.array(gaps, dtype=float),
                        np.array(inputs, dtype=float), out, OUTPUTS)
