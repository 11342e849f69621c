"""Model parameters: names, SI units, allowed ranges, presets and validation.

Every parameter the engine takes is listed once in :data:`PARAMETERS`; the
command line, the Python API, the datasets and the docs all use these names.
"""

from __future__ import annotations

import functools
import math
import numbers
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from . import timescales
from .contact import CONTACT_LAWS, IMPACT_VELOCITY_MODES
from .materials import MATERIALS, hertz_stiffness_from_bodies


class ParameterError(ValueError):
    """A parameter is unknown, of the wrong type or out of its allowed range."""


class TooStiffError(ParameterError):
    """A point's step would exceed max_steps_per_period: refused before integration (raised
    by harvester_sweep.packing for a scene; a sweep flags the point ``too stiff`` and goes
    on)."""


@dataclass(frozen=True)
class Parameter:
    """One model or run parameter.

    ``low``/``high`` bound the value (``None`` for unbounded); ``low_open`` and
    ``high_open`` make a bound exclusive. ``kind`` is ``"float"``, ``"int"``, ``"bool"`` or
    ``"choice"`` (then ``choices`` lists the allowed strings). ``optional``: ``None`` means
    unset.
    """

    name: str
    unit: str
    description: str
    kind: str = "float"
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    choices: tuple[str, ...] = ()
    optional: bool = False

    def range_text(self) -> str:
        if self.kind == "choice":
            return "one of " + ", ".join(self.choices)
        if self.kind == "bool":
            return "true or false"
        if self.low is None and self.high is None:
            return "any finite number"
        lo = "-inf" if self.low is None else f"{self.low:g}"
        hi = "inf" if self.high is None else f"{self.high:g}"
        left = "(" if self.low is None or self.low_open else "["
        right = ")" if self.high is None or self.high_open else "]"
        what = "an integer" if self.kind == "int" else "a finite number"
        return f"{what} in {left}{lo}, {hi}{right}"

    def check(self, value):
        """Return ``value`` converted to this parameter's type, or raise ParameterError.

        A numeric parameter takes a real number (Python's or numpy's) in its unit, never a
        bool, a string, a date or a container: TOML's ``mass = true`` is not 1 kg, and text
        from the command line is converted by :func:`parse_assignment` first. A bool
        parameter takes a boolean or the command line's words (true/false, yes/no, 1/0), not
        a number. A choice parameter takes one of its strings.
        """
        if self.optional and value is None:
            return None
        unit = f" [{'-' if self.unit == '1' else self.unit}]"
        if self.kind == "bool":
            if isinstance(value, (bool, np.bool_)):
                return bool(value)
            text = value.strip().lower() if isinstance(value, str) else None
            if text in ("true", "1", "yes", "1.0"):
                return True
            if text in ("false", "0", "no", "0.0"):
                return False
            raise ParameterError(f"{self.name}{unit} = {value_text(value)}: must be true or false")
        if self.kind == "choice":
            # (a string first: a list or table is refused without being hashed or compared)
            if not isinstance(value, str) or value not in self.choices:
                raise ParameterError(
                    f"{self.name}{unit} = {value_text(value)}: must be {self.range_text()}")
            return str(value)
        if not is_number(value):
            raise ParameterError(f"{self.name}{unit} = {value_text(value)} is not a number: "
                                 f"must be {self.range_text()}")
        try:
            number = float(value)
        except OverflowError:  # an integer beyond a double's range (tomllib reads any size)
            number = math.inf
        bad = not math.isfinite(number)
        if self.low is not None:
            bad |= number < self.low or (self.low_open and number == self.low)
        if self.high is not None:
            bad |= number > self.high or (self.high_open and number == self.high)
        if self.kind == "int":
            bad |= not number.is_integer()
        if bad:
            raise ParameterError(
                f"{self.name}{unit} = {value_text(value)}: must be {self.range_text()}")
        return int(number) if self.kind == "int" else number


def is_number(value) -> bool:
    """A real number (Python's or numpy's), not a bool: bool is an int to Python
    (float(True) == 1.0), and TOML's ``true`` is not 1."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


#: The largest seed of a basin map's draws: a netCDF attribute holds it as a 64-bit integer.
MAX_SEED = 2**63 - 1


def whole_number(name: str, value, low: int, high: int | None = None) -> int:
    """``value`` as an int where it is a whole number in ``low`` .. ``high`` (no upper
    bound: None), or ParameterError in one line naming ``name`` [-]. It takes what the
    parameter table takes for an integer: Python's or numpy's integers, and a float of
    whole value (TOML reads ``1e3`` as 1000.0); never a bool."""
    number = None
    if is_number(value):
        if isinstance(value, numbers.Integral):
            number = int(value)
        else:
            number = float(value)
            number = int(number) if math.isfinite(number) and number.is_integer() else None
    if number is None or number < low or (high is not None and number > high):
        bounds = f">= {low}" if high is None else f"in {low} .. {high:,}"
        raise ParameterError(f"{name} [-] = {value_text(value)}: must be an integer {bounds}")
    return number


def check_seed(seed) -> int:
    """A seed of numpy's default generator, checked (ParameterError in one line)."""
    return whole_number("seed", seed, 0, MAX_SEED)


def value_text(value) -> str:
    """repr(value) for a message, or a description where Python refuses to print it."""
    try:
        return repr(value)
    except ValueError:  # an integer of over 4300 digits (sys.get_int_max_str_digits)
        return "an integer too long to print"


_P = Parameter
PARAMETERS: dict[str, Parameter] = {
    p.name: p
    for p in [
        _P("mass", "kg", "effective tip mass m", low=0, low_open=True),
        _P("natural_frequency", "Hz", "short-circuit natural frequency f_n", low=0, low_open=True),
        _P("damping_ratio", "1", "mechanical damping ratio zeta", low=0, high=10),
        _P("coupling", "N/V", "electromechanical coupling theta (k d33 in the paper)", low=0),
        _P("capacitance", "F", "piezo capacitance C_p", low=0, low_open=True),
        _P("resistance", "Ohm", "load resistance R", low=0, low_open=True),
        _P("amplitude", "m/s^2", "base acceleration amplitude A (the paper's Y)", low=0),
        _P("base_forcing_factor", "1", "base-forcing correction mu_1: the tip is forced by "
           "m mu_1 A sin(w t); the one-mode reduction of a beam has m_eq mu_1 A as its "
           "forcing; 1: the paper's model", low=0, high=10, low_open=True),
        _P("frequency", "Hz", "excitation frequency f", low=0, low_open=True),
        _P("gap", "m", "distance from rest to the stop g (<= 0: preloaded stop)"),
        _P("hertz_stiffness", "N/m^1.5", "Hertz contact stiffness k_h (0: no stop)", low=0),
        _P("restitution", "1", "coefficient of restitution e", low=0, high=1, low_open=True),
        _P("lower_gap", "m", "distance from rest to a second stop below the beam, at "
           "x = -lower_gap (unset: none); same contact law as the upper stop", low=0,
           low_open=True, optional=True),
        _P("lower_hertz_stiffness", "N/m^1.5", "Hertz contact stiffness of the lower stop "
           "(unset: hertz_stiffness)", low=0, optional=True),
        _P("lower_restitution", "1", "coefficient of restitution of the lower stop (unset: "
           "restitution)", low=0, high=1, low_open=True, optional=True),
        _P(
            "impact_velocity",
            "m/s",
            "approach velocity v_imp in the contact damping law (fixed mode; "
            "latched mode: used until the first impact)",
            low=0,
            low_open=True,
        ),
        _P(
            "contact_damping",
            "s/m",
            "contact damping c_h; when given it overrides the value from the contact law",
            low=0,
            optional=True,
        ),
        _P("contact_law", "1", "contact damping law", kind="choice", choices=tuple(CONTACT_LAWS)),
        _P(
            "impact_velocity_mode",
            "1",
            "'fixed': v_imp = impact_velocity (the paper); "
            "'latched': each impact's own approach velocity, latched at first touch",
            kind="choice",
            choices=IMPACT_VELOCITY_MODES,
        ),
        _P(
            "stop_mass",
            "kg",
            "mass of the stop m_s; when given, hertz_stiffness is computed from the tip and "
            "stop materials and masses (Goldsmith, equivalent spheres) unless it is given "
            "too beside stop_support_stiffness; the moving stop's mass",
            low=0,
            low_open=True,
            optional=True,
        ),
        _P("stop_support_stiffness", "N/m", "stiffness k_s of the spring the (upper) stop is "
           "mounted on, a stop that moves (unset: a rigid stop); needs stop_mass", low=0,
           low_open=True, optional=True),
        _P("stop_support_damping", "N s/m", "damping c_s of the moving stop's support",
           low=0),
        _P("tip_material", "1", "tip mass material", kind="choice", choices=tuple(MATERIALS)),
        _P("stop_material", "1", "stop material", kind="choice", choices=tuple(MATERIALS)),
        _P(
            "locate_switches",
            "1",
            "locate contact onset, separation and the no-tension switch inside the step and "
            "integrate the pieces separately (False: plain fixed steps across the switch)",
            kind="bool",
        ),
        _P("steps_per_period", "1", "RK4 steps per forcing period (unset: chosen per point "
           "from the time scales and `accuracy`)", kind="int", low=16, high=1e9, optional=True),
        _P("accuracy", "1", "target relative error of the metrics, used to choose "
           "steps_per_period when it is not given", low=1e-13, high=1e-2),
        _P("max_steps_per_period", "1", "most steps per period the automatic choice may take; "
           "a point that needs more is refused as too stiff", kind="int", low=16, high=1e9),
        _P("max_periods", "1", "budget of forcing periods to reach steady state (unset: from "
           "the slowest decay rate and settle_tolerance)", kind="int", low=1, high=1e8,
           optional=True),
        _P(
            "settle_tolerance",
            "1",
            "steady state when |y(nT) - y((n-p)T)| <= settle_tolerance * amplitude, per component",
            low=0,
            high=1e-3,
            low_open=True,
        ),
    ]
}

#: Parameters every preset starts from (the paper's Table 1 with the corrections of docs/model.md).
_TABLE_1 = dict(
    mass=2.5e-3,
    natural_frequency=150.0,
    damping_ratio=0.01,
    capacitance=100e-9,
    resistance=10e3,
    amplitude=1.0,
    base_forcing_factor=1.0,
    frequency=140.0,
    gap=1e-6,
    hertz_stiffness=9.03e8,
    restitution=0.85,
    lower_gap=None,
    lower_hertz_stiffness=None,
    lower_restitution=None,
    impact_velocity=1.76e-3,
    contact_damping=None,
    contact_law="lankarani_nikravesh",
    impact_velocity_mode="fixed",
    stop_mass=None,
    stop_support_stiffness=None,
    stop_support_damping=0.0,
    tip_material="copper",
    stop_material="steel",
    steps_per_period=None,
    accuracy=1e-7,
    max_steps_per_period=2_000_000,
    max_periods=None,
    settle_tolerance=1e-10,
    locate_switches=True,
)
_D33 = 190e-12  # m/V, Table 1
_K_TABLE_1 = _TABLE_1["mass"] * (2 * math.pi * _TABLE_1["natural_frequency"]) ** 2

#: The preset a scene, sweep, branch or basin map starts from when none is named (and the
#: one ``preset=None`` means): the paper's Table 1.
DEFAULT_PRESET = "paper"

PRESETS: dict[str, Mapping] = {  # (read-only: a preset's checked values are kept)
    "paper": MappingProxyType(dict(_TABLE_1, coupling=_K_TABLE_1 * _D33)),
    "strong_coupling": MappingProxyType(dict(_TABLE_1, coupling=3e-3)),
}

#: What each preset assumes beyond its source, printed with every result.
PRESET_NOTES: dict[str, list[str]] = {
    "paper": [
        "Mereles et al., Table 1; coupling = k d33 = 4.2e-7 N/V (Eq. 8)",
        "capacitance 100 nF is assumed: Table 1 gives none",
        "contact damping from Lankarani-Nikravesh c_h = 3(1-e^2)/(4 v_imp) = 118 s/m "
        "(the printed 1.07e11 counts k_h twice, see docs/model.md)",
    ],
    "strong_coupling": [
        "the paper scene with coupling 3e-3 N/V, a device-like coupling giving ~0.1 V",
        "capacitance 100 nF is assumed",
    ],
}


def resolve_parameters(preset: str | None = DEFAULT_PRESET, **overrides) -> dict:
    """Return the full, validated parameter set: a preset updated with ``overrides``.

    Parameters
    ----------
    preset : str or None
        Name of a preset in :data:`PRESETS`; ``None`` is :data:`DEFAULT_PRESET`.
    **overrides
        Parameter values by name, in the SI units of :data:`PARAMETERS`.

    Raises
    ------
    ParameterError
        For an unknown preset or parameter name, a value of the wrong type or out of its
        range, or values whose time scales overflow a double.
    """
    # (a string first: `in` would hash a list or table from a sweep file, a TypeError)
    if preset is not None and (not isinstance(preset, str) or preset not in PRESETS):
        raise ParameterError(
            f"preset {value_text(preset)} is unknown: must be one of {', '.join(PRESETS)}")
    check_names(overrides)
    checked = dict(_checked_preset(preset or DEFAULT_PRESET))
    for name, value in overrides.items():
        checked[name] = _check(name, value)
    moving = checked["stop_support_stiffness"] is not None
    if moving and checked["stop_mass"] is None:
        raise ParameterError(
            f"stop_support_stiffness [N/m] = {value_text(checked['stop_support_stiffness'])}: a "
            f"stop on a spring needs its mass: give stop_mass [kg] > 0")
    if moving and checked["lower_gap"] is not None:
        raise ParameterError(
            f"lower_gap [m] = {value_text(checked['lower_gap'])}: a second stop beside a moving "
            f"one (stop_support_stiffness) is not modelled: leave lower_gap unset")
    if moving and checked["base_forcing_factor"] != 1.0:
        # (the engine forces tip and moving stop with one acceleration, and the stop, a
        # lumped body on the base, takes A, not mu_1 A)
        raise ParameterError(
            f"base_forcing_factor [-] = {value_text(checked['base_forcing_factor'])}: beside a "
            f"moving stop (stop_support_stiffness), a body on the base forced by A while the tip "
            f"is forced by mu_1 A, only 1 is modelled: leave base_forcing_factor at 1")
    explicit = overrides.get("hertz_stiffness") is not None
    if overrides.get("stop_mass") is not None and explicit and not moving:
        raise ParameterError(
            "give hertz_stiffness [N/m^1.5] or stop_mass [kg], not both: "
            "stop_mass computes hertz_stiffness from the materials (both only with a moving "
            "stop, stop_support_stiffness)"
        )
    if checked["lower_gap"] is not None and checked["gap"] < 0:
        raise ParameterError(
            f"lower_gap [m] = {value_text(checked['lower_gap'])}: a stop on each side needs "
            f"gap [m] >= 0 (no preloaded upper stop), not {value_text(checked['gap'])}")
    try:
        if checked["stop_mass"] is not None and not (moving and explicit):
            checked["hertz_stiffness"] = hertz_stiffness_from_bodies(
                checked["mass"], checked["tip_material"], checked["stop_mass"],
                checked["stop_material"])
        _check_step(checked)
    except ParameterError:
        raise
    except (ArithmeticError, ValueError) as error:
        # Values each in range can still overflow together (resistance 1e300 Ohm squares
        # to inf in the time scales; R C_p underflows to 0): float arithmetic raises.
        given = ", ".join(f"{name} = {value_text(value)}" for name, value in overrides.items())
        raise ParameterError(
            f"the time scales of {given or f'preset {preset}'} are beyond double precision "
            f"({type(error).__name__}): give values of physical magnitude in SI units"
        ) from None
    return checked


def forcing_amplitude(p: dict) -> float:
    """The amplitude of the tip's forcing acceleration mu_1 A [m/s^2] of a validated
    parameter set: base_forcing_factor [-] times amplitude [m/s^2] (a moving stop is
    forced by A alone, and only mu_1 = 1 is taken beside one)."""
    return p["base_forcing_factor"] * p["amplitude"]


def check_names(names) -> None:
    """Raise ParameterError for the first of ``names`` that is not in :data:`PARAMETERS`."""
    for name in names:
        if name not in PARAMETERS:
            raise ParameterError(
                f"unknown parameter {value_text(name)}: known parameters are "
                + ", ".join(PARAMETERS)
            )


def _checked_preset(preset: str) -> dict:
    """The values of preset ``preset``, checked once for all the points of a sweep (again
    if PRESETS[preset] is replaced); the caller copies it."""
    source = PRESETS[preset]
    known = _CHECKED_PRESETS.get(preset)
    if known is None or known[0] is not source:
        known = source, {name: PARAMETERS[name].check(source[name]) for name in PARAMETERS}
        _CHECKED_PRESETS[preset] = known
    return known[1]


_CHECKED_PRESETS: dict = {}


def _check(name: str, value):
    """PARAMETERS[name].check(value), remembered: a sweep checks the same values again at
    every point of its grid."""
    try:
        return _check_remembered(name, type(value), value)
    except TypeError:  # an unhashable value
        return PARAMETERS[name].check(value)


@functools.lru_cache(maxsize=4096)
def _check_remembered(name: str, kind: type, value):
    """PARAMETERS[name].check(value); ``kind`` is type(value), part of the key only, so that
    1, 1.0, True and numpy's 1 (equal as keys) are checked each as itself: mass = True is
    refused after mass = 1 was taken, locate_switches = 1 after locate_switches = True."""
    return PARAMETERS[name].check(value)


class StabilityWarning(UserWarning):
    """An explicit step is beyond the estimated RK4 stability bound of the contact."""


def _check_step(p: dict) -> None:
    """Choose steps_per_period and max_periods when unset; check an explicit step.

    An explicit step must resolve the forcing and natural oscillations (16 steps per cycle)
    and keep the load circuit's exact decay rate 1/(R C_p) inside RK4's stability bound
    (errors); beyond the estimated contact bound it only warns, as that bound is an estimate.
    """
    if p["max_periods"] is None:
        p["max_periods"] = timescales.auto_max_periods(p)
    if p["steps_per_period"] is None:
        # (a step beyond max_steps_per_period is kept: packing refuses the point)
        p["steps_per_period"] = timescales.auto_steps_per_period(p)
        return
    fastest = max(p["frequency"], p["natural_frequency"])
    step = 1.0 / (p["frequency"] * p["steps_per_period"])
    needed = math.ceil(16 * fastest / p["frequency"])
    if p["steps_per_period"] < needed:
        raise ParameterError(
            f"steps_per_period [-] = {p['steps_per_period']}: the step {step:.3g} s does not "
            f"resolve the {fastest:g} Hz oscillation (16 steps per cycle): must be an integer "
            f">= {needed}"
        )
    tau = p["resistance"] * p["capacitance"]
    bound = timescales.RK4_STABILITY
    needed = math.ceil(1.0 / (p["frequency"] * bound * tau))
    if p["steps_per_period"] < needed:
        raise ParameterError(
            f"steps_per_period [-] = {p['steps_per_period']}: the step {step:.3g} s exceeds "
            f"RK4's stability bound {bound} R C_p = {bound * tau:.3g} s of the load circuit "
            f"(resistance {p['resistance']:g} Ohm, capacitance {p['capacitance']:g} F): must be "
            f"an integer >= {needed}"
        )
    needed, what = timescales.stability_steps(p)
    if p["steps_per_period"] < needed:
        limit = 1.0 / (p["frequency"] * needed)
        warnings.warn(
            f"steps_per_period = {p['steps_per_period']}: the step {step:.3g} s is beyond the "
            f"estimated RK4 stability bound {bound}/rate = {limit:.3g} s of {what}; the run "
            f"may diverge: use >= {needed} or leave steps_per_period unset",
            StabilityWarning,
            stacklevel=4,
        )


def parse_assignment(text: str) -> tuple[str, object]:
    """Parse ``NAME=VALUE`` from the command line into a typed pair."""
    name, sep, raw = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise ParameterError(f"--set {text!r}: expected NAME=VALUE, e.g. --set gap=2e-6")
    check_names([name])
    raw = raw.strip()
    spec = PARAMETERS[name]
    if spec.kind in ("choice", "bool"):
        return name, raw
    if spec.optional and raw.lower() in ("", "none"):
        return name, None
    try:
        number = float(raw)
    except ValueError:
        unit = f" [{'-' if spec.unit == '1' else spec.unit}]"
        raise ParameterError(
            f"{name}{unit} = {raw!r} is not a number: must be {spec.range_text()}"
        ) from None
    return name, int(number) if spec.kind == "int" and number.is_integer() else number
