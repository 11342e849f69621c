"""The beam model's parameters: names, units, ranges, presets and validation.

The beam (a bimorph in ``n_modes`` bending modes striking a stop at ``contact_position``,
the stop rigid or a rod in ``rod_modes`` modes) shares the load, the forcing, the stop's
contact law and the run's numerics with the tip-mass model: those parameters are the
same objects as in :data:`harvester_sweep.parameters.PARAMETERS`, with the same names,
units and ranges. The presets come from :data:`harvester_sweep.bimorph.BEAM_PRESETS`.
"""

from __future__ import annotations

from types import MappingProxyType

from .bimorph import BEAM_PRESETS, CONNECTIONS, MAX_MODES, Bimorph
from .contact import CONTACT_LAWS
from .materials import MATERIALS, PIEZO_MATERIALS
from .parameters import PARAMETERS, Parameter, ParameterError, value_text
from .rod import MAX_MODES as MAX_ROD_MODES
from .rod import Rod


class _Ratios(Parameter):
    """A list of damping ratios in [0, 1), one per bending mode (text: comma-separated)."""

    def range_text(self) -> str:
        return "a list of numbers in [0, 1), one per bending mode"

    def check(self, value):
        if value is None:
            return None
        items = value.split(",") if isinstance(value, str) else value
        if not isinstance(items, (list, tuple)) or not items:
            raise ParameterError(f"{self.name} [-] = {value_text(value)}: must be "
                                 f"{self.range_text()}")
        element = Parameter(self.name, "1", self.description, low=0, high=1, high_open=True)
        out = []
        for item in items:
            if isinstance(item, str):
                try:
                    item = float(item)
                except ValueError:
                    raise ParameterError(f"{self.name} [-] = {value_text(value)}: must be "
                                         f"{self.range_text()}") from None
            out.append(element.check(item))
        return tuple(out)


_P = Parameter
_SHARED = ("damping_ratio", "resistance", "amplitude", "frequency", "gap", "lower_gap",
           "hertz_stiffness", "restitution", "impact_velocity", "contact_damping", "accuracy",
           "settle_tolerance")

#: Every parameter of the beam model, by name.
BEAM_PARAMETERS: dict[str, Parameter] = {
    p.name: p
    for p in [
        _P("length", "m", "beam length L from the clamp to the tip", low=0, low_open=True),
        _P("width", "m", "beam width b", low=0, low_open=True),
        _P("substrate_thickness", "m", "substrate thickness h_s", low=0, low_open=True),
        _P("piezo_thickness", "m", "thickness h_p of each piezo layer", low=0, low_open=True),
        _P("substrate", "1", "substrate material", kind="choice", choices=tuple(MATERIALS)),
        _P("piezo", "1", "piezoceramic material", kind="choice",
           choices=tuple(PIEZO_MATERIALS)),
        _P("tip_mass", "kg", "tip mass M_t", low=0),
        _P("tip_inertia", "kg m^2", "rotary inertia of the tip mass I_t", low=0),
        _P("connection", "1", "how the two piezo layers feed the load", kind="choice",
           choices=CONNECTIONS),
        _P("n_modes", "1", "bending modes of the beam", kind="int", low=1, high=MAX_MODES),
        _Ratios("mode_damping_ratios", "1", "damping ratio of each bending mode, one per "
                "mode (unset: damping_ratio for all)", kind="list", optional=True),
        _P("substrate_modulus", "Pa", "substrate's Young's modulus (unset: the material's)",
           low=0, low_open=True, optional=True),
        _P("substrate_density", "kg/m^3", "substrate's density (unset: the material's)",
           low=0, low_open=True, optional=True),
        _P("piezo_modulus", "Pa", "piezo layers' Young's modulus 1/s11^E (unset: the "
           "material's)", low=0, low_open=True, optional=True),
        _P("piezo_density", "kg/m^3", "piezo layers' density (unset: the material's)", low=0,
           low_open=True, optional=True),
        _P("d31", "m/V", "piezoelectric constant d31 (unset: the material's)",
           optional=True),
        _P("permittivity", "F/m", "piezo permittivity eps33^T at constant stress (unset: the "
           "material's)", low=0, low_open=True, optional=True),
        _P("contact_position", "m", "span position s_c of the contact from the clamp, at "
           "most the length (unset: the tip)", low=0, low_open=True, optional=True),
        _P("rod_modes", "1", "longitudinal modes of a rod stop (0: a rigid stop)", kind="int",
           low=0, high=MAX_ROD_MODES),
        _P("rod_length", "m", "length of the rod stop", low=0, low_open=True),
        _P("rod_area", "m^2", "cross-section of the rod stop", low=0, low_open=True),
        _P("rod_material", "1", "material of the rod stop", kind="choice",
           choices=tuple(MATERIALS)),
        _P("rod_damping_ratio", "1", "modal damping ratio of the rod stop", low=0, high=1,
           high_open=True),
        _P("stop_mass", "kg", "mass m_s of a stop on a spring (with stop_support_stiffness; "
           "unset: no such stop)", low=0, low_open=True, optional=True),
        _P("stop_support_stiffness", "N/m", "stiffness k_s of the spring a lumped stop is "
           "mounted on, on the shaking base (unset: a rigid or rod stop)", low=0,
           low_open=True, optional=True),
        _P("stop_support_damping", "N s/m", "damping c_s of a lumped stop's support", low=0),
        _P("rod_modulus", "Pa", "rod's Young's modulus (unset: the material's)", low=0,
           low_open=True, optional=True),
        _P("rod_density", "kg/m^3", "rod's density (unset: the material's)", low=0,
           low_open=True, optional=True),
        _P("steps_per_period", "1", "grid steps per forcing period that look for contact and "
           "sample the outputs (unset: chosen from the modes and `accuracy`)", kind="int",
           low=16, high=1e7, optional=True),
        _P("contact_step", "s", "RK4 sub-step in contact (unset: chosen from the contact's "
           "time scale and `accuracy`)", low=0, low_open=True, optional=True),
        _P("max_periods", "1", "budget of forcing periods to reach steady state", kind="int",
           low=1, high=1e7),
        *(PARAMETERS[name] for name in _SHARED),
        _P("contact_law", "1", "contact damping law", kind="choice",
           choices=tuple(CONTACT_LAWS)),
    ]
}

_TABLE_1_STOP = dict(damping_ratio=0.01, resistance=10e3, amplitude=1.0, frequency=140.0,
                     gap=1e-6, lower_gap=None, hertz_stiffness=9.03e8, restitution=0.85,
                     impact_velocity=1.76e-3, contact_damping=None,
                     contact_law="lankarani_nikravesh", accuracy=1e-7,
                     settle_tolerance=1e-10, steps_per_period=None, contact_step=None,
                     max_periods=2000, n_modes=5, mode_damping_ratios=None,
                     substrate_modulus=None, substrate_density=None, piezo_modulus=None,
                     piezo_density=None, d31=None, permittivity=None, rod_modulus=None,
                     rod_density=None, stop_mass=None, stop_support_stiffness=None,
                     stop_support_damping=0.0)


def _preset(name: str) -> MappingProxyType:
    beam, rod, position = BEAM_PRESETS[name]
    values = dict(_TABLE_1_STOP, length=beam.length, width=beam.width,
                  substrate_thickness=beam.substrate_thickness,
                  piezo_thickness=beam.piezo_thickness, substrate=beam.substrate,
                  piezo=beam.piezo, tip_mass=beam.tip_mass, tip_inertia=beam.tip_inertia,
                  connection=beam.connection,
                  contact_position=None if position == beam.length else position,
                  rod_modes=0 if rod is None else 5,
                  rod_length=40e-3 if rod is None else rod.length,
                  rod_area=2e-5 if rod is None else rod.area,
                  rod_material="steel" if rod is None else rod.material,
                  rod_damping_ratio=0.0 if rod is None else rod.damping_ratio)
    return MappingProxyType(values)


#: The beam's presets (read-only), from bimorph.BEAM_PRESETS with the paper's stop, load
#: and forcing (Table 1).
BEAM_PARAMETER_PRESETS = {name: _preset(name) for name in BEAM_PRESETS}
#: The preset a beam run starts from unless told otherwise.
DEFAULT_BEAM_PRESET = "bimorph_tip"
#: What each preset assumes, printed with every result.
BEAM_PRESET_NOTES = {
    "bimorph_tip": ["a PZT-5A bimorph on brass whose one-mode reduction has Table 1's 150 Hz "
                    "and 2.5 g, striking at its tip Table 1's stop (docs/model.md)"],
    "mak_rod": ["the bimorph_tip beam striking at 0.8 L a steel rod 40 mm long, 5 mm across, "
                "in 5 longitudinal modes (the arrangement of Mak et al. 2011)"],
}


def resolve_beam_parameters(preset: str | None = DEFAULT_BEAM_PRESET, **overrides) -> dict:
    """The full, validated beam parameter set: a preset updated with ``overrides`` (SI units
    of :data:`BEAM_PARAMETERS`). Raises ParameterError naming the parameter, its unit and
    its allowed range."""
    preset = DEFAULT_BEAM_PRESET if preset is None else preset
    if not isinstance(preset, str) or preset not in BEAM_PARAMETER_PRESETS:
        raise ParameterError(f"preset {value_text(preset)} is unknown for the beam: must be "
                             f"one of {', '.join(BEAM_PARAMETER_PRESETS)}")
    for name in overrides:
        if name not in BEAM_PARAMETERS:
            raise ParameterError(f"unknown beam parameter {value_text(name)}: known parameters "
                                 f"are {', '.join(BEAM_PARAMETERS)}")
    p = dict(BEAM_PARAMETER_PRESETS[preset])
    p.update(overrides)
    if isinstance(p["mode_damping_ratios"], list):  # (hashable, as every value here)
        p["mode_damping_ratios"] = tuple(p["mode_damping_ratios"])
    checked = {name: BEAM_PARAMETERS[name].check(p[name]) for name in BEAM_PARAMETERS}
    if checked["contact_position"] is not None \
            and checked["contact_position"] > checked["length"]:
        raise ParameterError(
            f"contact_position [m] = {value_text(checked['contact_position'])}: must be in "
            f"(0, length = {checked['length']:g} m]")
    ratios = checked["mode_damping_ratios"]
    if ratios is not None and len(ratios) != checked["n_modes"]:
        raise ParameterError(
            f"mode_damping_ratios [-] = {value_text(list(ratios))}: must be "
            f"{BEAM_PARAMETERS['mode_damping_ratios'].range_text()} (n_modes = "
            f"{checked['n_modes']})")
    lumped = checked["stop_support_stiffness"] is not None
    if lumped != (checked["stop_mass"] is not None):
        raise ParameterError(
            "a stop on a spring needs both stop_mass [kg] > 0 and stop_support_stiffness "
            "[N/m] > 0 (unset both: a rigid or rod stop)")
    if lumped and (checked["rod_modes"] > 0 or checked["lower_gap"] is not None):
        raise ParameterError(
            f"stop_support_stiffness [N/m] = {value_text(checked['stop_support_stiffness'])}: "
            "a stop on a spring is the upper stop, rigid otherwise: leave rod_modes 0 and "
            "lower_gap unset")
    if checked["rod_modes"] > 0 and checked["lower_gap"] is not None:
        raise ParameterError(
            f"lower_gap [m] = {value_text(checked['lower_gap'])}: a second stop below beside a "
            f"rod stop is not modelled: leave lower_gap unset or rod_modes 0")
    try:
        bimorph(checked)
        rod(checked)
    except ValueError as error:
        raise ParameterError(str(error)) from None
    return checked


def moving_stop(p: dict) -> bool:
    """Whether the stop of a validated parameter set moves (a rod, or a stop on a spring):
    its face's displacement is then an output."""
    return p["rod_modes"] > 0 or p["stop_support_stiffness"] is not None


def contact_position(p: dict) -> float:
    """The contact's span position s_c [m] of a validated parameter set (unset: the
    tip)."""
    return p["length"] if p["contact_position"] is None else p["contact_position"]


def bimorph(p: dict) -> Bimorph:
    """The beam of a validated parameter set."""
    return Bimorph(length=p["length"], width=p["width"],
                   substrate_thickness=p["substrate_thickness"],
                   piezo_thickness=p["piezo_thickness"], substrate=p["substrate"],
                   piezo=p["piezo"], tip_mass=p["tip_mass"], tip_inertia=p["tip_inertia"],
                   connection=p["connection"], substrate_modulus=p["substrate_modulus"],
                   substrate_density=p["substrate_density"], piezo_modulus=p["piezo_modulus"],
                   piezo_density=p["piezo_density"], d31=p["d31"],
                   permittivity=p["permittivity"])


def rod(p: dict) -> Rod | None:
    """The rod stop of a validated parameter set, None for a rigid stop."""
    if p["rod_modes"] == 0:
        return None
    return Rod(length=p["rod_length"], area=p["rod_area"], material=p["rod_material"],
               modulus=p["rod_modulus"], density=p["rod_density"],
               damping_ratio=p["rod_damping_ratio"])
