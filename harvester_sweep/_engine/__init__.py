"""The engine: many points of the harvester integrated to steady state by a fixed-step
RK4 with located contact switches, in Numba.

Private, numba and numpy only: nothing here imports from the rest of harvester_sweep but
the layer below it, the models it runs (``harvester_sweep.models``: the tip-mass model's
state, right-hand side, contact and contact-free step) and the compile flags
(``harvester_sweep.jit``).
The layers above hand it float arrays laid out by :mod:`.layouts` (parameter rows from
``harvester_sweep.packing``, states) and read back metric rows, stroboscopic samples and
final states. One concept per module:

- ``layouts``: every row layout, from named fields (the state's from the model);
- ``hermite``: the cubic Hermite interpolant of a step (extrema, crossings, int V^2 dt);
- ``rk4``: RK4 over parts of a step and contact switches located inside it;
- ``steady``: orbit periods from the stroboscopic samples, metrics of the last orbit;
- ``booking``: what a step finished in scalar code books (touches, extrema, force peaks);
- ``stop_motion``: a stop on a spring, stepped in scalar code;
- ``monodromy``: the period map clear of the stops (its Jacobian, its reach), in closed form;
- ``tangents``: the period map's Jacobian carried along a run (the variational equations);
- ``lanes``: the lane table, its vector step loop and the scalar finish of marked steps;
- ``scheduler``: lines, the shared queue, threads and progress (:func:`run_points`);
- ``cache``: numba's on-disk cache kept in step with this source.
"""

import os

# numba's OpenMP threads spin while they wait for the next parallel call, by default: on a
# machine shared with other work that spinning takes the cores the working threads need,
# and the orbit solver makes many short calls (issue 44). They sleep instead, unless the
# user says otherwise (read when numba first starts its threads).
os.environ.setdefault("OMP_WAIT_POLICY", "passive")

from ..models import hertz, tip_mass
from . import (
    booking,
    cache,
    hermite,
    lanes,
    monodromy,
    rk4,
    scheduler,
    steady,
    stop_motion,
    tangents,
)
from .lanes import multi_steps
from .layouts import (
    BOOKED_METRICS,
    LANE,
    LANES,
    METRIC,
    N_RIGID,
    N_STROBE,
    NO_STOP,
    PARAM,
    SERIES,
    STATE,
    STATUS,
)
from .monodromy import free_extent, free_monodromy
from .scheduler import record_series, run_independent, run_points, warm_up
from .steady import MAX_ORBIT_PERIOD
from .tangents import carried as carries_tangents

cache.flush_if_changed(scheduler._run_threads, (booking, hermite, lanes, monodromy, rk4,
                                                 scheduler, steady, stop_motion, tangents,
                                                 hertz, tip_mass))


def cache_warm() -> bool:
    """Whether the engine is in numba's on-disk cache (else its first run compiles it)."""
    return cache.is_warm(scheduler._run_threads)


def compiled_or_cached() -> bool:
    """Whether this process has the engine's machine code, or numba's on-disk cache holds
    it (cache.holds)."""
    return bool(scheduler._run_threads.overloads) or cache.holds(scheduler._run_threads)


__all__ = [
    "BOOKED_METRICS",
    "LANE",
    "LANES",
    "MAX_ORBIT_PERIOD",
    "METRIC",
    "N_RIGID",
    "N_STROBE",
    "NO_STOP",
    "PARAM",
    "SERIES",
    "STATE",
    "STATUS",
    "cache_warm",
    "compiled_or_cached",
    "carries_tangents",
    "free_extent",
    "free_monodromy",
    "multi_steps",
    "record_series",
    "run_independent",
    "run_points",
    "warm_up",
]
