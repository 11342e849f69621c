"""Time scales of a point, RK4 stability bounds and the default steps per period.

The fastest motion is usually the contact: linearised about the expected penetration delta,
the Hertz spring has the angular frequency ``w_c = sqrt(1.5 k_h sqrt(delta) / m)`` and the
contact damping the rate ``k_h delta^1.5 c_h / m``. The penetration is estimated from the
impact energy, ``1/2 m v^2 = 2/5 k_h delta^2.5`` (elastic), or, when the damping stops the
mass first, from ``1/2 m v^2 = 2/5 k_h c_h v delta^2.5`` (plastic), whichever is smaller,
with ``v`` the larger linear-response velocity amplitude at the forcing and at the natural
frequency (impacts are strongest near resonance, and the stop makes the response hardening).
A stop beyond twice the corresponding displacement is taken as out of reach. A stop on a
spring adds its support's frequency ``sqrt(k_s / m_s)`` and damping rate ``c_s / m_s``, and
its contact acts on the reduced mass ``m m_s / (m + m_s)`` of tip and stop. Clear of the
stop, the fastest mode is the largest |eigenvalue| of the model's linear system: with a
strong coupling the load stiffens the mode far beyond the natural frequency.
"""

from __future__ import annotations

import functools
import itertools
import math
import operator
from typing import NamedTuple

import numpy as np

from .contact import contact_damping_of, lower_stop
from .linear import linear_response
from .models import hertz, tip_mass

#: |h lambda| that RK4 keeps stable (2.78 on the negative real axis, 2.83 on the imaginary).
RK4_STABILITY = 2.5
#: Measured on the paper scene (benchmarks/convergence.py): relative error of the metrics
#: ~ ERROR_CONSTANT (h w_fast)^4 with contact switches located.
ERROR_CONSTANT = 2e-4
#: The lane engine's nominal rate, a thread's RK4 steps per second with its lanes filled
#: [steps/s]: what a message about a point that is not run divides by (a refused point's
#: time, run_time_estimate). A run's estimate does not assume it: run_estimate measures
#: the rate and what the solver does besides its steps on the run's own points (the steps
#: alone were 15 to 70 times off the examples' times, issue 44). The benchmark grids run
#: at 1e8-2.5e8 a thread on AMD Zen 3 (benchmarks/results/).
STEPS_PER_SECOND = 1e8
#: Periods a run typically needs to settle, for run-time estimates in messages.
TYPICAL_PERIODS = 150


class TimeScales(NamedTuple):
    """Rates of one point. [rad/s] for oscillations, [1/s] for decays. (A tuple of numbers,
    which Python's garbage collector stops tracking: a sweep remembers tens of thousands.)"""

    forcing: float
    natural: float
    circuit: float
    contact: float
    contact_damping: float
    impact_velocity: float  # estimate [m/s]
    penetration: float  # estimate [m]
    support: float = 0.0  # a moving stop's support sqrt(k_s/m_s) [rad/s], 0 when rigid
    support_damping: float = 0.0  # ... and c_s/m_s [1/s]
    # the fastest mode of the stop-free system, coupled: its largest |eigenvalue| [rad/s]
    coupled: float = 0.0

    def fastest(self) -> tuple[float, str]:
        """Largest rate and what it is, for stability."""
        rates = (self.natural, self.forcing, self.circuit, self.coupled, self.support,
                 self.support_damping, self.contact, self.contact_damping)
        rate = max(rates)
        what = rates.index(rate)  # (the first of equals; described only once chosen)
        if what < 6:
            return rate, ("the natural frequency", "the forcing",
                          "the load circuit 1/(R C_p)",
                          "the coupled electromechanical mode (largest |eigenvalue| of the "
                          "stop-free system)",
                          "the stop's support sqrt(k_s/m_s)",
                          "the stop's support damping c_s/m_s")[what]
        what -= 3
        if what == 3:
            return rate, (f"the contact stiffness (linearised contact frequency "
                          f"{self.contact / 2 / math.pi:.3g} Hz at the expected penetration "
                          f"{self.penetration:.2g} m)")
        return rate, (f"the contact damping (rate k_h delta^1.5 c_h / m at the expected "
                      f"penetration {self.penetration:.2g} m)")


#: Parameters chosen from the time scales, which they do not depend on: left out of the
#: key under which what is derived from them is remembered.
CHOSEN = frozenset({"steps_per_period", "max_periods"})
#: Left out of that key too: the gap, which enters what is derived here only as a preload
#: (below 0) or as whether the stop is in reach (_contact): the points of a grid that
#: differ in their gap alone share the derivations where it does the same to them.
_KEYLESS = CHOSEN | {"gap"}
#: The most keys each derivation remembers: more than the combinations of a grid's axes
#: other than the gap usually number (examples/million_points.toml has 80 x 10 x 50), so
#: that each is derived once, not once per gap.
REMEMBERED = 65536
_READERS: dict = {}  # a parameter set's names -> (their number, what reads the key's values)
# (numbers that never repeat, taken atomically: a sweep resolves its next chunk in a
# thread while other threads may resolve too)
_NUMBERS = itertools.count()


def _key(p: dict) -> tuple:
    """The key under which what is derived from parameter set ``p`` is remembered: the
    number of its set of names, and its values but the gap and those CHOSEN (a number, not
    the names themselves: a tuple's hash is not kept, and each lookup would hash them)."""
    names = tuple(p)
    known = _READERS.get(names)
    if known is None:
        known = _READERS[names] = (
            next(_NUMBERS), operator.itemgetter(*(n for n in names if n not in _KEYLESS)))
    return known[0], known[1](p)


def _remembered(derive):
    """``derive(p)`` remembered under _key(p) and what the gap does: below 0 the gap
    itself, else whether the stop is within the motion's reach, a distance that the key
    fixes (_reach). A point is resolved (its step chosen), then packed (its step checked
    against that choice), each asking, and a sweep's points that differ in their gap
    alone ask the same. Derived afresh where a value is unhashable. At most REMEMBERED
    keys (then forgotten all at once: what is derived does not depend on what is
    remembered)."""
    reaches: dict = {}  # key -> (the stop's reach [m], the key's number in `known`)
    known: dict = {}  # (the key's number, what the gap does) -> what is derived

    @functools.wraps(derive)
    def remembered(p):
        try:
            key = _key(p)
            reach = reaches.get(key)
        except TypeError:  # an unhashable value
            return derive(p)
        if reach is None:
            if len(reaches) >= REMEMBERED:
                reaches.clear()
                known.clear()
            reach = reaches[key] = (_reach(_velocity(p), _slower(p)), next(_NUMBERS))
        gap = p["gap"]
        which = reach[1], gap if gap < 0 else gap < reach[0]
        found = known.get(which)
        if found is None:
            found = known[which] = derive(p)
        return found

    return remembered


@_remembered
def time_scales(p: dict) -> TimeScales:
    """Time scales of a validated parameter set (SI units)."""
    wn = 2 * math.pi * p["natural_frequency"]
    w = 2 * math.pi * p["frequency"]
    v, omega = _velocity(p), _slower(p)
    contact = damping = delta = 0.0
    for stop in (p, lower_stop(p)):  # the faster of the stops in reach
        if stop is not None:
            c, d, dl = _contact(stop, v, omega)
            contact, damping, delta = max(contact, c), max(damping, d), max(delta, dl)
    support = support_damping = 0.0
    if p["stop_support_stiffness"] is not None:
        support = math.sqrt(p["stop_support_stiffness"] / p["stop_mass"])
        support_damping = p["stop_support_damping"] / p["stop_mass"]
    return TimeScales(w, wn, 1 / (p["resistance"] * p["capacitance"]), contact, damping, v,
                      delta, support, support_damping, _coupled_rate(*(p[n] for n in _LINEAR[:6])))


#: The parameters the stop-free velocity estimate reads.
_LINEAR = ("mass", "natural_frequency", "damping_ratio", "coupling", "capacitance",
           "resistance", "amplitude", "frequency", "base_forcing_factor")


_LINEAR_OF = operator.itemgetter(*_LINEAR)


def _velocity(p: dict) -> float:
    """The stop-free velocity estimate [m/s] of parameter set ``p`` (_free_velocity)."""
    return _free_velocity(*_LINEAR_OF(p))


def _slower(p: dict) -> float:
    """The lower of the forcing's and the natural angular frequency [rad/s]: the one the
    estimated velocity reaches the farthest at."""
    return min(2 * math.pi * p["frequency"], 2 * math.pi * p["natural_frequency"])


def _reach(v: float, omega: float) -> float:
    """The distance [m] within which a stop is in reach of a motion of velocity amplitude
    ``v`` [m/s] at ``omega`` [rad/s]: twice the displacement v / omega."""
    return 2.0 * v / omega


@functools.lru_cache(maxsize=65536)  # (a grid's other axes repeat these: the gap's, say)
def _free_velocity(mass, natural_frequency, damping_ratio, coupling, capacitance, resistance,
                   amplitude, frequency, base_forcing_factor) -> float:
    """The larger velocity amplitude [m/s] of the stop-free response at the forcing and at
    the natural frequency (SI parameters as in parameters.PARAMETERS)."""
    # At least 0.1 % damping in the estimate: an undamped resonance has no finite amplitude.
    X, _ = linear_response(amplitude, np.array([frequency, natural_frequency]),
                           base_forcing_factor=base_forcing_factor, mass=mass,
                           natural_frequency=natural_frequency,
                           damping_ratio=max(damping_ratio, 1e-3), coupling=coupling,
                           capacitance=capacitance, resistance=resistance)
    return max(float(np.max(np.abs(X) * 2 * math.pi * np.array([frequency,
                                                               natural_frequency]))), 1e-12)


@functools.lru_cache(maxsize=65536)
def _coupled_rate(mass, natural_frequency, damping_ratio, coupling, capacitance,
                  resistance) -> float:
    """The largest |eigenvalue| [rad/s] of the stop-free linear system (the model's
    ``linear_system``): with a strong coupling the electrical load stiffens the mode far
    beyond the natural frequency, which neither the mechanical nor the circuit's rate
    shows."""
    m, _ = tip_mass.linear_system(mass, natural_frequency, damping_ratio, coupling,
                                  capacitance, resistance)
    return float(np.max(np.abs(np.linalg.eigvals(m))))


def _contact(p: dict, v: float, omega: float) -> tuple[float, float, float]:
    """The contact's rates [1/s] and penetration [m] of the (upper) stop of ``p`` at the
    expected velocity ``v`` [m/s], zeros when it is out of reach."""
    kh = p["hertz_stiffness"]
    m = p["mass"]
    if p["stop_support_stiffness"] is not None:  # tip and stop pushed apart: reduced mass
        m = m * p["stop_mass"] / (m + p["stop_mass"])
    # The stop only takes energy out: the motion stays within the linear resonance amplitude.
    if not (kh > 0 and p["gap"] < _reach(v, omega)):
        return 0.0, 0.0, 0.0
    ch = contact_damping_of(p, v)
    energy = 0.5 * m * v * v
    delta = hertz.penetration(energy, kh)
    if ch > 0:  # (the damping force k_h c_h v delta^1.5 as the spring)
        spring = kh * ch * v
        delta = min(delta, hertz.penetration(energy, spring) if math.isfinite(spring)
                    # (taken apart where the product overflows: a c_h of 1e300 s/m)
                    else hertz.penetration(energy, kh) * ch ** -0.4 * v ** -0.4)
    delta += max(-p["gap"], 0.0)  # a preloaded stop is already pressed in
    rates = (math.sqrt(hertz.stiffness(kh, delta) / m), hertz.static_force(kh, delta) * ch / m)
    if not all(map(math.isfinite, rates)):  # (a c_h of inf: 0 inf is NaN, which max drops)
        raise OverflowError("the contact's rates are not finite numbers")
    return (*rates, delta)


@_remembered
def auto_steps_per_period(p: dict) -> int:
    """Steps per forcing period for the accuracy target ``p["accuracy"]``, within stability.

    The step resolves the fastest oscillation (forcing, natural, contact) so that
    ERROR_CONSTANT (h w)^4 <= accuracy, and keeps every rate at half RK4's stability bound.
    At least 64 steps, rounded up to a multiple of 16.
    """
    s = time_scales(p)
    oscillation = max(s.forcing, s.natural, s.coupled, s.support, s.contact)
    h_accuracy = (p["accuracy"] / ERROR_CONSTANT) ** 0.25 / oscillation
    h_stable = 0.5 * RK4_STABILITY / s.fastest()[0]
    steps = math.ceil(1.0 / (p["frequency"] * min(h_accuracy, h_stable)))
    return max(64, 16 * math.ceil(steps / 16))


@_remembered
def stability_steps(p: dict) -> tuple[int, str]:
    """Fewest steps per period inside RK4's stability bound, and the rate that sets it."""
    rate, what = time_scales(p).fastest()
    return math.ceil(rate / (p["frequency"] * RK4_STABILITY)), what


def run_time_estimate(steps_per_period: int) -> float:
    """Rough run time [s] of one point at ``steps_per_period`` among a sweep's, on one
    thread: TYPICAL_PERIODS periods at STEPS_PER_SECOND."""
    return steps_per_period * TYPICAL_PERIODS / STEPS_PER_SECOND


def slowest_decay(p: dict) -> tuple[float, str]:
    """Slowest decay rate of a transient without the stop [1/s], and what it is.

    The mechanical mode decays at zeta w_n plus what the load takes, c_e / (2 m) with
    c_e = theta^2 R / (1 + (w_n R C_p)^2); the load circuit at 1 / (R C_p). The stop only
    adds damping, so this bounds the settling time from above.
    """
    m = p["mass"]
    wn = 2 * math.pi * p["natural_frequency"]
    tau = p["resistance"] * p["capacitance"]
    electrical = p["coupling"] ** 2 * p["resistance"] / (1 + (wn * tau) ** 2) / (2 * m)
    rates = {"the mechanical damping": p["damping_ratio"] * wn + electrical,
             f"the load circuit (R C_p = {tau:.3g} s)": 1 / tau}
    if p["stop_support_stiffness"] is not None:  # the moving stop's own ringing
        rates["the stop's support damping"] = p["stop_support_damping"] / (2 * p["stop_mass"])
    what = min(rates, key=rates.get)
    return rates[what], what


@_remembered
def auto_max_periods(p: dict) -> int:
    """Budget of forcing periods: the slowest transient decays by the settle tolerance, with
    a margin; at least 1000 and at most 1e6."""
    rate, _ = slowest_decay(p)
    if rate <= 0:
        return 1_000_000
    needed = 1.5 * math.log(1 / p["settle_tolerance"]) * p["frequency"] / rate + 100
    return int(min(max(needed, 1000), 1_000_000))
