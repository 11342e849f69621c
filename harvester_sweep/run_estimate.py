"""How much work a sweep is, said before it starts: points, RK4 steps and a rough run time.

The steps come from the model, not from a trial run: each of a sample of points spread over
the grid takes the step of its parameters (``steps_per_period``, chosen from its time scales
when unset) for the periodic-orbit solver's runs (:data:`FREE_PERIODS` where the linear
response from rest provably stays clear of the stop, twice its amplitude below the gap;
else :data:`CONTACT_PERIODS`) and, with contact, for the periods the slowest transient
needs to come within ``acceptance.NEAR`` of the orbit (at most ``max_periods``). Contact only
adds damping, and a point continued from its neighbour starts closer to its orbit, so this
is rather an upper estimate. The run time divides by a typical rate of the lane engine
(:data:`harvester_sweep.timescales.STEPS_PER_SECOND`, the package's one run-time rate); the
progress bar's ETA, from the measured rate, takes over once the sweep runs.
"""

from __future__ import annotations

import math
import sys
import warnings
from dataclasses import dataclass

import numpy as np

from . import timescales
from .acceptance import NEAR
from .linear import linear_response
from .parameters import ParameterError
from .period_map import D

#: A sweep estimated to take longer than this [s] starts only when confirmed (``--yes``).
LONG_RUN_SECONDS = 3600.0
#: Periods of a point's own step the solver runs besides the motion, in Newton's iterates
#: with their copies (D + 1 lanes), chord steps (one lane) and the error estimate (two runs
#: at twice the steps): an orbit clear of the stop takes the motion's one period (a chord
#: step with the contact-free map's monodromy) and a second chord step; one with contact
#: the attempt from rest and about three iterates after its motion, the last with its
#: copies both ways (2 D + 1 lanes: the monodromy by central differences).
FREE_PERIODS = 1 + 1 + 2 * 2
CONTACT_PERIODS = (D + 1) + 2 * (D + 1) + (2 * D + 1) + 2 * 2
#: Points whose parameters are resolved for the estimate, spread evenly over the grid.
SAMPLE_POINTS = 64


@dataclass(frozen=True)
class RunEstimate:
    """The work of a sweep.

    Attributes
    ----------
    points : int
        Points of the grid.
    remaining : int
        Points still to run (fewer when resuming).
    steps : float
        RK4 steps the remaining points are expected to take.
    threads : int
        Threads that share the work.
    starts : int
        Runs from a start of their own at each point (a basin map's samples), 1 for a sweep.
    """

    points: int
    remaining: int
    steps: float
    threads: int
    starts: int = 1

    @property
    def seconds(self) -> float:
        """Expected wall time [s] on ``threads`` threads."""
        return self.steps / (timescales.STEPS_PER_SECOND * self.threads)

    @property
    def long(self) -> bool:
        """True when the run is expected to take more than LONG_RUN_SECONDS."""
        return self.seconds > LONG_RUN_SECONDS

    def describe(self) -> str:
        """One line: size, steps and time."""
        todo = "" if self.remaining == self.points else f" ({self.remaining:,} still to run)"
        starts = f" x {self.starts:,} starts" if self.starts > 1 else ""
        return (f"{self.points:,} point{'s' if self.points != 1 else ''}{starts}{todo}, "
                f"about {self.steps:.2g} RK4 steps: roughly "
                f"{duration(self.seconds)} on {self.threads} thread"
                f"{'s' if self.threads > 1 else ''}")


def estimate(spec, remaining: int, threads: int) -> RunEstimate:
    """The expected work of ``remaining`` points of ``spec`` (a SweepSpec) on ``threads``."""
    per_point = _mean_steps(spec.n_points,
                            lambda i: spec.point_parameters(spec.values_at(i)))
    return RunEstimate(spec.n_points, remaining, per_point * remaining, max(1, threads))


def estimate_basins(spec, threads: int) -> RunEstimate:
    """The expected work of a basin map ``spec`` (a basins.BasinSpec) on ``threads``: every
    start run like a point from rest, and under a shock each point's run from rest too."""
    runs = spec.samples + (1 if spec.shock is not None else 0)
    per_point = _mean_steps(spec.n_points, spec.point) * runs
    return RunEstimate(spec.n_points, spec.n_points, per_point * spec.n_points,
                       max(1, threads), spec.samples)


def _mean_steps(n_points: int, point) -> float:
    """The mean of point_steps over SAMPLE_POINTS points spread evenly over ``n_points``,
    ``point(i)`` giving the validated parameters of point ``i``."""
    picks = np.unique(np.linspace(0, n_points - 1, min(SAMPLE_POINTS, n_points))
                      .round().astype(np.int64))
    with warnings.catch_warnings():  # (a StabilityWarning is the run's to give, once)
        warnings.simplefilter("ignore")
        return float(np.mean([point_steps(point(int(i))) for i in picks]))


def announce(work: RunEstimate, yes: bool, progress: bool, smaller: str) -> None:
    """Refuse a run ``work`` longer than LONG_RUN_SECONDS unless ``yes`` (ParameterError,
    one line that says how to make it ``smaller``), else say its size on stderr when
    ``progress``."""
    if work.long and not yes:
        raise ParameterError(
            f"{work.describe()}, beyond {LONG_RUN_SECONDS / 3600:g} h: start it with --yes "
            f"(yes=True in Python), or {smaller}")
    if progress:
        print(f"harvester-sweep: {work.describe()}", file=sys.stderr, flush=True)


def point_steps(p: dict) -> float:
    """RK4 steps point ``p`` (validated parameters) is expected to take from rest; 0 for a
    point refused as too stiff."""
    if p["steps_per_period"] > p["max_steps_per_period"]:
        return 0.0
    if not (p["hertz_stiffness"] > 0 and 2 * abs(linear_response(**p)[0]) >= p["gap"]):
        return p["steps_per_period"] * FREE_PERIODS
    rate, _ = timescales.slowest_decay(p)
    motion = math.log(1.0 / NEAR) * p["frequency"] / rate if rate > 0 else math.inf
    return p["steps_per_period"] * (min(p["max_periods"], motion) + CONTACT_PERIODS)


def duration(seconds: float) -> str:
    """``seconds`` [s] in the unit a reader takes in at once: s, min, h, days or years."""
    for unit, size in (("years", 365.25 * 86400), ("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= 2 * size:
            return f"{_rounded(seconds / size)} {unit}"
    return f"{_rounded(seconds)} s"


def _rounded(value: float) -> str:
    """Two significant digits, without an exponent below 1e15."""
    return f"{value:.2g}" if value < 10 or value >= 1e15 else f"{float(f'{value:.2g}'):,.0f}"
