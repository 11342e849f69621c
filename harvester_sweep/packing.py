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
    wn = 2.0 * math.pi * p["natural_frequency"]
    m = p["mass"]
    row = np.zeros(len(PARAM))
    # (the tip's forcing mu_1 A; a moving stop shares it, hence mu_1 = 1 beside one)
    row[PARAM.amplitude] = amplitude = forcing_amplitude(p)
    row[PARAM.wn2] = wn * wn
    row[PARAM.cm] = 2.0 * p["damping_ratio"] * wn
    row[PARAM.thm] = p["coupling"] / m
    row[PARAM.mass] = m
    row[PARAM.gap], row[PARAM.khm], row[PARAM.ch], row[PARAM.latch] = _stop_row(p)
    row[PARAM.irc] = 1.0 / (p["resistance"] * p["capacitance"])
    row[PARAM.thc] = p["coupling"] / p["capacitance"]
    row[PARAM.resistance] = p["resistance"]
    row[PARAM.period] = 1.0 / p["frequency"]
    row[PARAM.steps] = p["steps_per_period"]
    row[PARAM.max_periods] = 0.0 if refusal(p) else p["max_periods"]
    row[PARAM.tolerance] = p["settle_tolerance"]
    static = amplitude / (wn * wn) / max(2.0 * p["damping_ratio"], 1e-4)
    row[PARAM.x_limit] = 1e3 * (abs(p["gap"]) + static + 1e-9)
    row[PARAM.locate] = 1.0 if p["locate_switches"] else 0.0
    w = 2.0 * math.pi * p["frequency"]
    row[PARAM.v_per_x] = w
    tau = p["resistance"] * p["capacitance"]
    row[PARAM.voltage_per_x] = p["coupling"] / p["capacitance"] * min(1.0, w * tau)
    row[PARAM.phase] = 0.0  # t = 0 at a zero of the forcing; basins start elsewhere too
    lower = lower_stop(p)
    row[PARAM.lower_gap] = NO_STOP
    if lower is not None:
        (row[PARAM.lower_gap], row[PARAM.lower_khm], row[PARAM.lower_ch],
         row[PARAM.lower_latch]) = _stop_row(lower)
    if p["stop_support_stiffness"] is not None:  # a stop on a spring
        ms = p["stop_mass"]
        row[PARAM.stop_wn2] = p["stop_support_stiffness"] / ms
        row[PARAM.stop_cm] = p["stop_support_damping"] / ms
        row[PARAM.stop_ratio] = m / ms
    row[PARAM.book] = 1.0  # (every metric)
    row[PARAM.multi] = MULTI
    return row


def _stop_row(stop: dict) -> tuple:
    """The (upper) stop of parameter set ``stop`` as the engine reads it: gap [m] (NO_STOP
    when hertz_stiffness is 0), k_h/m [N/(m^1.5 kg)], contact damping in fixed mode [s/m]
    and the latched law's factor c_h v_imp (0 in fixed mode) [-]."""
    latched = stop["contact_damping"] is None and stop["impact_velocity_mode"] == "latched"
    # (hertz_stiffness 0 is no stop: placed beyond any motion, so that no touch is counted)
    return (stop["gap"] if stop["hertz_stiffness"] > 0 else NO_STOP,
            stop["hertz_stiffness"] / stop["mass"],
            contact_damping_of(stop, stop["impact_velocity"]),
            damping_factor(stop["contact_law"], stop["restitution"]) if latched else 0.0)


def initial_state(p: dict) -> np.ndarray:
    """State at rest (layouts.STATE): ``(x_0 [m], 0, 0, 0, 0, impact_velocity [m/s])``
    (the stop at rest too, a moving stop preloaded or not).

    At rest the mass sits at its static equilibrium ``k x_0 + k_h (x_0 - g)^1.5 = 0``: 0
    unless the stop is preloaded (g < 0), then between g and 0 (found by bisection). A
    preloaded moving stop gives way too, to ``k_s x_s0 = k_h delta^1.5``.
    """
    x0 = xs0 = 0.0
    k = p["mass"] * (2.0 * math.pi * p["natural_frequency"]) ** 2
    kh, g, ks = p["hertz_stiffness"], p["gap"], p["stop_support_stiffness"]
    if g < 0.0 and kh > 0.0 and ks is not None:
        # the penetration delta in [0, -g]: delta + F (1/k + 1/k_s) = -g, F = k_h delta^1.5
        low, high = 0.0, -g
        for _ in range(200):
            delta = 0.5 * (low + high)
            if delta + hertz.static_force(kh, delta) * (1.0 / k + 1.0 / ks) + g > 0.0:
                high = delta
            else:
                low = delta
        x0, xs0 = -hertz.static_force(kh, delta) / k, hertz.static_force(kh, delta) / ks
    elif g < 0.0 and kh > 0.0:
        low, high = g, 0.0
        for _ in range(200):
            x0 = 0.5 * (low + high)
            if k * x0 + hertz.static_force(kh, x0 - g) > 0.0:
                high = x0
            else:
                low = x0
    state = np.zeros(len(STATE))
    state[STATE.x], state[STATE.approach_velocity] = x0, p["impact_velocity"]
    state[STATE.stop_x] = xs0
    return state


def refusal(p: dict) -> str | None:
    """Why point ``p`` is refused before integration (too stiff), or None."""
    steps = p["steps_per_period"]
    if steps <= p["max_steps_per_period"]:
        return None
    rate, what = timescales.time_scales(p).fastest()
    return (f"too stiff: {what} (rate {rate:.3g} 1/s) needs a step <= "
            f"{1 / (p['frequency'] * steps):.3g} s, {steps} steps per period, about "
            f"{timescales.run_time_estimate(steps):.0f} s per point; raise "
            f"max_steps_per_period [-] (now {p['max_steps_per_period']}) to run it anyway")


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
    rows = np.array([pack_parameters(p) for p in points]).reshape(-1, len(PARAM))
    states = np.array([initial_state(p) for p in points]).reshape(-1, len(STATE))
    accuracy = np.array([p["accuracy"] if automatic_step(p) else np.nan for p in points])
    max_steps = np.array([p["max_steps_per_period"] for p in points], dtype=float)
    return Packed(rows, states, rows[:, PARAM.max_periods] == 0.0, accuracy, max_steps)


def automatic_step(p: dict) -> bool:
    """Whether point ``p``'s step is the one chosen for its accuracy target."""
    return p["steps_per_period"] == timescales.auto_steps_per_period(p)
