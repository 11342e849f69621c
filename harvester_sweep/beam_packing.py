"""A beam parameter set made into the modal engine's rows: its modes, its linear system
with contact surfaces, the step's first choice.

The only place a beam parameter dict becomes engine rows (as ``packing`` is for the
tip-mass model's lane engine).
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass

import numpy as np

from . import bimorph as _bimorph
from . import rod as _rod
from ._engine import NO_STOP
from .beam_parameters import BEAM_PARAMETERS, bimorph, contact_position, rod
from .contact import contact_damping
from .modal_map import ModalPoint, pack
from .models import beam as beam_model
from .models import hertz
from .parameters import StabilityWarning, TooStiffError
from .timescales import RK4_STABILITY

#: Grid steps per period at least, and per period of the highest bending mode: the grid
#: looks for touches and samples the outputs, whose extrema and int V^2 dt it
#: interpolates [-].
MIN_STEPS = 128
STEPS_PER_MODE_CYCLE = 4
#: RK4 sub-steps per estimated contact duration, the first choice before the step-halving
#: check [-].
SUBSTEPS_PER_CONTACT = 64
#: Divergence limit, in units of each component's scale [-].
LIMIT = 1e6


# The modes of a beam (a frozen, hashable Bimorph) and of a rod, computed once for every
# point of a sweep that shares them: the grid's frequencies, gaps and loads do not change
# them.
_modes = functools.lru_cache(maxsize=256)(_bimorph.modes)
_rod_modes = functools.lru_cache(maxsize=256)(_rod.rod_modes)


@dataclass
class BeamSystem:
    """A beam parameter set's model: its modes, its rod's, the linear system."""

    modes: _bimorph.Modes
    rod_modes: _rod.RodModes | None
    system: beam_model.LinearSystem
    contact_damping: float
    scale: np.ndarray
    linear: np.ndarray  # |Y| (D,): each component's amplitude in the linear steady state


def beam_system(p: dict) -> BeamSystem:
    """The model of a validated beam parameter set (beam_parameters.resolve_beam_parameters)."""
    beam = bimorph(p)
    modes = _modes(beam, p["n_modes"])
    stop = rod(p)
    rm = None if stop is None else _rod_modes(stop, p["rod_modes"])
    n = p["n_modes"]
    strain = (beam.substrate_thickness / 2 + beam.piezo_thickness) * modes.root_curvature
    # (hertz_stiffness 0 is no stop, as for the tip mass: its surfaces placed beyond any
    # motion, so that no touch is counted)
    stops = p["hertz_stiffness"] > 0
    system = beam_model.modal_system(
        omega=modes.omega,
        zeta=(np.full(n, p["damping_ratio"]) if p["mode_damping_ratios"] is None
              else np.array(p["mode_damping_ratios"])), chi=modes.coupling,
        gamma=modes.forcing, phi_tip=modes.tip,
        phi_contact=modes.shape(contact_position(p))[:, 0], root_strain=strain,
        capacitance=beam.capacitance, resistance=p["resistance"],
        gap=p["gap"] if stops else NO_STOP,
        lower_gap=p["lower_gap"] if stops or p["lower_gap"] is None else NO_STOP,
        **_stop(p, rm))
    ch = (p["contact_damping"] if p["contact_damping"] is not None
          else contact_damping(p["contact_law"], p["restitution"], p["impact_velocity"]))
    linear = _linear_amplitudes(p, system)
    return BeamSystem(modes, rm, system, ch, _scales(p, system, linear), linear)


def _stop(p: dict, rm) -> dict:
    """The stop's modes for models.beam.modal_system: a rod's; a stop on a spring as one
    mode of mass m_s (its face 1/sqrt(m_s), its base forcing sqrt(m_s): a lumped body
    feels m_s A); none for a rigid stop."""
    if rm is not None:
        return dict(rod_omega=rm.omega, rod_zeta=p["rod_damping_ratio"], rod_face=rm.face,
                    rod_forcing=rm.forcing)
    if p["stop_support_stiffness"] is not None:
        m, k = p["stop_mass"], p["stop_support_stiffness"]
        return dict(rod_omega=[math.sqrt(k / m)],
                    rod_zeta=p["stop_support_damping"] / (2 * math.sqrt(k * m)),
                    rod_face=[1 / math.sqrt(m)], rod_forcing=[math.sqrt(m)])
    return {}


def _linear_amplitudes(p: dict, system) -> np.ndarray:
    """|Y| (D,): each component's amplitude in the linear steady state (no stop)."""
    omega = 2 * math.pi * p["frequency"]
    M = system.matrix
    return np.abs(np.linalg.solve(1j * omega * np.eye(len(M)) - M,
                                  system.forcing * p["amplitude"]))


def _scales(p: dict, system, amp: np.ndarray) -> np.ndarray:
    """Each component's scale (D,), what the settle test and the divergence limit measure
    it against (``amp``: the linear amplitudes). The modal coordinates are
    mass-normalised, so one displacement scale
    serves every mode (beam's and rod's) and their rates take it times their own
    frequency: a norm of the motion's energy. That scale is the largest modal amplitude
    of the linear response, or where the stop caps the motion, the gap's share of the
    first mode; the voltage's is its linear amplitude."""
    M = system.matrix
    # the displacement coordinates: rows of M that say "its rate is that component"
    pairs = [(k, int(np.flatnonzero(row)[0])) for k, row in enumerate(M)
             if np.count_nonzero(row) == 1 and row.max() == 1.0]
    size = float(max(amp[k] for k, _ in pairs))
    first = abs(float(system.surfaces[0][pairs[0][0]]))
    if p["gap"] > 0 and first > 0:
        size = min(size, p["gap"] / first)
    scale = np.full(len(M), size)
    for k, rate in pairs:  # a rate's row of M holds its mode's -omega^2 at column k
        scale[rate] = size * math.sqrt(abs(M[rate, k]))
    volt = list(system.output_names).index("voltage")
    v = int(np.flatnonzero(system.outputs[volt])[0])
    scale[v] = max(float(amp[v]), 1e-300)
    return scale


def first_steps(p: dict, bs: BeamSystem) -> tuple[int, float]:
    """The first choice of grid steps per period [-] and contact sub-step [s]: the grid
    samples the highest bending mode STEPS_PER_MODE_CYCLE times a cycle; the sub-step is
    the estimated contact duration over SUBSTEPS_PER_CONTACT."""
    steps, most = p["steps_per_period"], BEAM_PARAMETERS["steps_per_period"].high
    if steps is None:
        ratio = float(bs.modes.omega[-1]) / (2 * math.pi * p["frequency"])
        steps = max(MIN_STEPS, 2 ** math.ceil(math.log2(STEPS_PER_MODE_CYCLE * ratio)))
        if steps > most:  # (a beam of a micrometre: gigabytes and minutes, then a crash)
            raise TooStiffError(
                f"too stiff: the beam's mode {len(bs.modes.omega)}, at "
                f"{float(bs.modes.omega[-1]) / (2 * math.pi):.3g} Hz, asks {steps:.3g} grid "
                f"steps per forcing period at {p['frequency']:g} Hz, beyond the "
                f"{most:g} steps_per_period [-] allows: take fewer modes (n_modes) or a "
                "beam whose modes are slower")
    substep = p["contact_step"]
    if substep is None:
        substep = contact_duration(p, bs) / SUBSTEPS_PER_CONTACT
    if p["contact_step"] is not None and p["hertz_stiffness"] > 0:
        bound, what = contact_step_bound(p, bs)
        if substep > bound:
            warnings.warn(
                f"contact_step = {substep:.3g} s is beyond the estimated RK4 stability bound "
                f"{RK4_STABILITY}/rate = {bound:.3g} s of {what} (at the expected "
                "impact): the run may diverge or not settle: use <= "
                f"{bound:.3g} or leave contact_step unset", StabilityWarning, stacklevel=3)
    count = contact_steps(p, substep)
    if count > most:  # (a contact step of 1e-300 s: a run without end)
        what = (f"contact_step [s] = {substep:.3g}" if p["contact_step"] is not None else
                f"the contact, estimated to last {substep * SUBSTEPS_PER_CONTACT:.3g} s,")
        raise TooStiffError(
            f"too stiff: {what} asks {count:.3g} RK4 sub-steps per forcing period at "
            f"{p['frequency']:g} Hz in contact, beyond the {most:g} steps a period "
            "steps_per_period [-] allows: give a longer contact_step [s]")
    return int(steps), float(substep)


def contact_steps(p: dict, substep: float) -> float:
    """The RK4 sub-steps of ``substep`` [s] a forcing period of ``p`` holds: what a point in
    contact all period would take [-]."""
    return 1.0 / (p["frequency"] * substep)


def _expected_impact(p: dict, bs: BeamSystem) -> tuple[float, float, float]:
    """The impact a point's contact estimates expect (hertz_stiffness > 0): the contact
    point's apparent mass [kg] (1 / sum of the squared mode shapes there, the beam's and
    the rod's), its approach velocity [m/s] (of the linear response's amplitude there) and
    the undamped Hertz contact's largest penetration [m] at that velocity."""
    surface = bs.system.surfaces[0]
    mass = 1.0 / float(np.sum(surface ** 2))
    omega = 2 * math.pi * p["frequency"]
    reach = float(np.abs(surface @ bs.linear))
    velocity = max(omega * max(reach - p["gap"], reach * 1e-3), 1e-12)
    return mass, velocity, hertz.penetration(0.5 * mass * velocity ** 2, p["hertz_stiffness"])


def contact_duration(p: dict, bs: BeamSystem) -> float:
    """Estimated duration [s] of an impact (:func:`_expected_impact`); a forcing period where
    hertz_stiffness is 0 (no stop: the sub-step then serves no contact)."""
    if p["hertz_stiffness"] == 0:
        return 1.0 / p["frequency"]
    _, velocity, delta = _expected_impact(p, bs)
    # Hertz's impact of a mass: 2.94 delta_max / v
    return 2.94 * delta / velocity


def contact_step_bound(p: dict, bs: BeamSystem) -> tuple[float, str]:
    """The longest contact sub-step [s] inside RK4's stability bound at the expected impact
    (:func:`_expected_impact`; hertz_stiffness > 0), RK4_STABILITY over the faster of the
    contact's rates on the apparent mass: its stiffness's sqrt(1.5 k_h delta^0.5 / m) and
    its damping's k_h delta^1.5 c_h / m; and which rate it is. (The modes' own flow is exact
    in a sub-step: the contact alone is RK4's.)"""
    mass, _, delta = _expected_impact(p, bs)
    kh = p["hertz_stiffness"]
    rates = {"the contact's stiffness": math.sqrt(hertz.stiffness(kh, delta) / mass),
             "the contact's damping": hertz.static_force(kh, delta) * bs.contact_damping
             / mass}
    what = max(rates, key=rates.get)
    return RK4_STABILITY / rates[what], what


def pack_beam(p: dict, bs: BeamSystem, steps: int, substep: float) -> ModalPoint:
    """The rows of a beam point at ``steps`` grid steps per period and sub-step ``substep``
    [s]."""
    S = len(bs.system.surfaces)
    return pack(bs.system, p["frequency"], p["amplitude"], [p["hertz_stiffness"]] * S,
                [bs.contact_damping] * S, p["resistance"], steps, substep, p["max_periods"],
                p["settle_tolerance"], LIMIT, bs.scale)
