"""Packing: the only place where validated parameter dicts become the engine's rows.

A point's parameter row (layouts.PARAM) holds what the engine reads, in SI units, and
its initial state (layouts.STATE) is the state at rest. Packing also decides which points
are refused before integration: a point whose step would exceed ``max_steps_per_period``
is *too stiff*; its row is marked so (a budget of 0 periods) and the engine writes its
outputs as such without running it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import timescales
from ._engine import NO_STOP, PARAM, STATE
from .contact import contact_damping_of, damping_factor, lower_stop
from .models import hertz
from .parameters import TooStiffError, forcing_amplitude

#: Contact-free steps a lane takes at once (layouts.PARAM.multi, lanes.resume): their
#: composition, a map of the same cost as one step, where a period holds 1024 steps or more
#: (lanes.MULTI_SPAN). A multi-step that ends in contact or near the stop is taken again
#: one step at a time, so the gain is the share of a period clear of the stops [-].
MULTI = 4.0


def pack_parameters(p: dict) -> np.ndarray:
    """The engine's parameter row (layouts.PARAM) of a validated parameter dict [SI]."""
    return pack_rows([p])[0]


def pack_rows(points) -> np.ndarray:
    """The engine's parameter rows (n, len(layouts.PARAM)) of validated parameter dicts
    [SI], made column by column: a sweep's chunk packs thousands of points at once, and
    each column is the arithmetic a point's value takes, in the same order (the same bits
    as one point at a time)."""
    c = _columns(points, _NUMBERS)
    rows = np.zeros((len(points), len(PARAM)))
    wn = 2.0 * math.pi * c["natural_frequency"]
    m = c["mass"]
    # (the tip's forcing mu_1 A; a moving stop shares it, hence mu_1 = 1 beside one)
    rows[:, PARAM.amplitude] = amplitude = forcing_amplitude(c)
    rows[:, PARAM.wn2] = wn * wn
    rows[:, PARAM.cm] = 2.0 * c["damping_ratio"] * wn
    rows[:, PARAM.thm] = c["coupling"] / m
    rows[:, PARAM.mass] = m
    (rows[:, PARAM.gap], rows[:, PARAM.khm], rows[:, PARAM.ch],
     rows[:, PARAM.latch]) = _stop_columns(points, c)
    rows[:, PARAM.irc] = 1.0 / (c["resistance"] * c["capacitance"])
    rows[:, PARAM.thc] = c["coupling"] / c["capacitance"]
    rows[:, PARAM.resistance] = c["resistance"]
    rows[:, PARAM.period] = 1.0 / c["frequency"]
    rows[:, PARAM.steps] = c["steps_per_period"]
    rows[:, PARAM.max_periods] = np.where(
        _too_stiff(c["steps_per_period"], c["max_steps_per_period"]), 0.0, c["max_periods"])
    rows[:, PARAM.tolerance] = c["settle_tolerance"]
    static = amplitude / (wn * wn) / np.maximum(2.0 * c["damping_ratio"], 1e-4)
    rows[:, PARAM.x_limit] = 1e3 * (np.abs(c["gap"]) + static + 1e-9)
    rows[:, PARAM.locate] = [1.0 if p["locate_switches"] else 0.0 for p in points]
    w = 2.0 * math.pi * c["frequency"]
    rows[:, PARAM.v_per_x] = w
    tau = c["resistance"] * c["capacitance"]
    rows[:, PARAM.voltage_per_x] = c["coupling"] / c["capacitance"] * np.minimum(1.0, w * tau)
    rows[:, PARAM.phase] = 0.0  # t = 0 at a zero of the forcing; basins start elsewhere too
    rows[:, PARAM.lower_gap] = NO_STOP
    lowers = [(i, lower) for i, lower in enumerate(map(lower_stop, points))
              if lower is not None]
    if lowers:
        where = [i for i, _ in lowers]
        stops = [lower for _, lower in lowers]
        (rows[where, PARAM.lower_gap], rows[where, PARAM.lower_khm], rows[where, PARAM.lower_ch],
         rows[where, PARAM.lower_latch]) = _stop_columns(stops, _columns(stops, _STOP_NUMBERS))
    moving = [i for i, p in enumerate(points) if p["stop_support_stiffness"] is not None]
    if moving:  # stops on a spring
        s = _columns([points[i] for i in moving], _MOVING_NUMBERS)
        ms = s["stop_mass"]
        rows[moving, PARAM.stop_wn2] = s["stop_support_stiffness"] / ms
        rows[moving, PARAM.stop_cm] = s["stop_support_damping"] / ms
        rows[moving, PARAM.stop_ratio] = s["mass"] / ms
    rows[:, PARAM.book] = 1.0  # (every metric)
    rows[:, PARAM.multi] = MULTI
    return rows


#: The numbers packing reads from every point, a stop's and a moving stop's.
_STOP_NUMBERS = ("gap", "hertz_stiffness", "mass")
_NUMBERS = _STOP_NUMBERS + (
    "natural_frequency", "damping_ratio", "coupling", "capacitance", "resistance", "amplitude",
    "base_forcing_factor", "frequency", "steps_per_period", "max_steps_per_period",
    "max_periods", "settle_tolerance")
_MOVING_NUMBERS = ("stop_support_stiffness", "stop_support_damping", "stop_mass", "mass")


def _columns(points, names) -> dict:
    """Each of ``names``' values over ``points``, a float array each."""
    return {name: np.array([p[name] for p in points], dtype=float) for name in names}


def _stop_columns(stops, c) -> tuple:
    """The (upper) stop of each parameter set of ``stops`` (their numbers ``c``, as
    _columns gives them) as the engine reads it: gap [m] (NO_STOP where hertz_stiffness is
    0), k_h/m [N/(m^1.5 kg)], contact damping in fixed mode [s/m] and the latched law's
    factor c_h v_imp (0 in fixed mode) [-]."""
    ch, latch = np.array([_damping(stop) for stop in stops]).reshape(-1, 2).T
    # (hertz_stiffness 0 is no stop: placed beyond any motion, so that no touch is counted)
    kh = c["hertz_stiffness"]
    return np.where(kh > 0, c["gap"], NO_STOP), kh / c["mass"], ch, latch


def _damping(stop: dict) -> tuple:
    """A stop's contact damping in fixed mode [s/m] and the latched law's factor [-]."""
    latched = stop["contact_damping"] is None and stop["impact_velocity_mode"] == "latched"
    return (contact_damping_of(stop, stop["impact_velocity"]),
            damping_factor(stop["contact_law"], stop["restitution"]) if latched else 0.0)


def initial_state(p: dict) -> np.ndarray:
    """State at rest (layouts.STATE): ``(x_0 [m], 0, 0, 0, 0, impact_velocity [m/s])``
    (the stop at rest too, a moving stop preloaded or not).

    At rest the mass sits at its static equilibrium ``k x_0 + k_h (x_0 - g)^1.5 = 0``: 0
    unless the stop is preloaded (g < 0), then between g and 0 (found by bisection). A
    preloaded moving stop gives way too, to ``k_s x_s0 = k_h delta^1.5``.
    """
    return rest_states([p])[0]


def rest_states(points) -> np.ndarray:
    """:func:`initial_state` of each of ``points`` (n, len(layouts.STATE)): at 0 but where
    a stop is preloaded, each point's equilibrium found alone."""
    states = np.zeros((len(points), len(STATE)))
    states[:, STATE.approach_velocity] = [p["impact_velocity"] for p in points]
    for i, p in enumerate(points):
        if _preloaded(p):
            states[i, STATE.x], states[i, STATE.stop_x] = _preloaded_rest(p)
    return states


def _preloaded_rest(p: dict) -> tuple:
    """x_0 [m] and the stop's x_s0 [m] at rest of point ``p``, whose stop is preloaded
    (:func:`initial_state`)."""
    k = p["mass"] * (2.0 * math.pi * p["natural_frequency"]) ** 2
    kh, g, ks = p["hertz_stiffness"], p["gap"], p["stop_support_stiffness"]
    if ks is not None:
        # the penetration delta in [0, -g]: delta + F (1/k + 1/k_s) = -g, F = k_h delta^1.5
        low, high = 0.0, -g
        for _ in range(200):
            delta = 0.5 * (low + high)
            if delta + hertz.static_force(kh, delta) * (1.0 / k + 1.0 / ks) + g > 0.0:
                high = delta
            else:
                low = delta
        return -hertz.static_force(kh, delta) / k, hertz.static_force(kh, delta) / ks
    low, high = g, 0.0
    for _ in range(200):
        x0 = 0.5 * (low + high)
        if k * x0 + hertz.static_force(kh, x0 - g) > 0.0:
            high = x0
        else:
            low = x0
    return x0, 0.0


def _preloaded(p: dict) -> bool:
    """Whether the (upper) stop of point ``p`` is preloaded: a stop (k_h > 0) at a gap
    below 0."""
    return p["gap"] < 0.0 and p["hertz_stiffness"] > 0.0


def _too_stiff(steps, most):
    """Whether a point of ``steps`` steps per period is refused before integration, where
    ``most`` is its max_steps_per_period [-] (numbers or arrays)."""
    return steps > most


def refusal(p: dict) -> str | None:
    """Why point ``p`` is refused before integration (too stiff), or None."""
    steps, most = p["steps_per_period"], p["max_steps_per_period"]
    if not _too_stiff(steps, most):
        return None
    seconds = f"about {_readable(timescales.run_time_estimate(steps))} s per point"
    remedy = f"raise max_steps_per_period [-] (now {most}) to run it anyway"
    if not automatic_step(p):  # (the step was asked for, not chosen for the stiffness)
        return (f"too stiff: steps_per_period [-] asks {_readable(steps)} steps per period, "
                f"above max_steps_per_period, {seconds}; {remedy}")
    rate, what = timescales.time_scales(p).fastest()
    return (f"too stiff: {what}, at {rate:.3g} 1/s, needs a step <= "
            f"{1 / (p['frequency'] * steps):.3g} s, {_readable(steps)} steps per period, "
            f"{seconds}; {remedy}")


def _readable(value: float) -> str:
    """``value`` in a few digits: a whole number from 10 up, two significant figures below
    (a refused point's time can be a millisecond), an exponent from 1e12 (a count of 150
    digits is unreadable)."""
    if value >= 1e12:
        return f"{value:.3g}"
    return f"{value:.0f}" if value >= 10 else f"{value:.2g}"


def check_runnable(p: dict) -> None:
    """Raise TooStiffError (a ParameterError) for a point that would be refused."""
    reason = refusal(p)
    if reason is not None:
        raise TooStiffError(reason)


@dataclass
class Packed:
    """Points packed for the engine.

    Attributes
    ----------
    rows : numpy.ndarray
        float64 (n, len(layouts.PARAM)): the parameter rows.
    states : numpy.ndarray
        float64 (n, len(layouts.STATE)): initial states, at rest.
    refused : numpy.ndarray
        bool (n,): refused before integration (too stiff).
    accuracy : numpy.ndarray
        float64 (n,): the error target [-] of a point whose step was chosen automatically
        (``steps_per_period`` unset, or set to the step it would get), NaN where the step
        was given: the periodic-orbit solver refines the step of the former only.
    max_steps : numpy.ndarray
        float64 (n,): ``max_steps_per_period`` [-], the finest step a refinement may take.
    """

    rows: np.ndarray
    states: np.ndarray
    refused: np.ndarray
    accuracy: np.ndarray
    max_steps: np.ndarray

    def __len__(self) -> int:
        return len(self.rows)


def pack_points(points) -> Packed:
    """Pack a sequence of validated parameter dicts, each from rest."""
    rows = pack_rows(points)
    states = rest_states(points)
    accuracy = np.array([p["accuracy"] if automatic_step(p) else np.nan for p in points])
    max_steps = np.array([p["max_steps_per_period"] for p in points], dtype=float)
    return Packed(rows, states, rows[:, PARAM.max_periods] == 0.0, accuracy, max_steps)


def automatic_step(p: dict) -> bool:
    """Whether point ``p``'s step is the one chosen for its accuracy target."""
    return p["steps_per_period"] == timescales.auto_steps_per_period(p)
