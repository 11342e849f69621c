"""How long a run will take, said before it starts: the package's one run-time model.

A run's time is mostly not its RK4 steps: the periodic-orbit solver calls the engine once a
round, and each round costs its Python and the call besides the steps. A swept line runs
its points one after another (each starts from the last one's orbit), so a frequency
response of two lines is hundreds of rounds of a few points each, where the steps alone
take a tenth of the time (issue 44: "roughly 0.06 s" was said before 0.8-4 s). So the
model counts three things, each measured on this machine, on the grid's own points, just
before the run:

- **a sample of the grid solved for real** (:data:`SAMPLE_POINTS` points spread over it;
  under continuation :data:`SEGMENT` consecutive points of a line each, so that the points
  that start from their neighbour's orbit are counted as the run takes them): each point's
  RK4 steps and the rounds it ran in. A sample point gets at most :data:`SAMPLE_STEPS`
  steps of motion; one that does not settle within them is counted as running its whole
  budget (``max_periods``), as it will if it never settles;
- **the engine's rate**: the sample's orbits run again in one engine call, its lanes
  filled, timed (the best of :data:`RATE_RUNS`) [RK4 steps per second and thread];
- **the cost of a round**: the sample's wall time less its steps at that rate, shared out
  over its rounds and its points' rounds (a point in a round costs
  :data:`POINT_ROUND_SHARE` of a round's own cost).

A run of chunks (lines_per_chunk lines each, one after another) then takes, per chunk,
its rounds (the slowest point's from rest; a line's, its points' one after another) at a
round's cost, plus each point's rounds at their share and its steps at the engine's rate
on the threads its calls take. How near the runs came, on the examples and the benchmark
grids: benchmarks/estimate.py, benchmarks/results/estimate_44.md. The machine is measured
as it is when the run starts: a load that comes or goes later moves the run, not this.
The sample costs some rounds of its own (0.01 to 0.5 s; a sweep's sample is measured
once per process) and changes no result: the run solves every point afresh. The progress
bar's ETA, from the run's own rate, takes over once the sweep runs.
"""

from __future__ import annotations

import math
import sys
import time
import warnings
from dataclasses import dataclass

import numpy as np

from . import period_map, timescales
from ._engine import LANES, METRIC, PARAM, STATUS
from ._engine.scheduler import SHORT_CALL
from .orbits import compile_solver, solve_orbits
from .packing import pack_points
from .parameters import ParameterError

#: A run estimated to take longer than this [s] starts only when confirmed (``--yes``).
LONG_RUN_SECONDS = 3600.0
#: Points of the grid solved for the estimate, spread evenly over it [-].
SAMPLE_POINTS = 32
#: Under continuation, the sample's points come in runs of this many consecutive points of
#: a line, the first from rest [-].
SEGMENT = 8
#: RK4 steps of motion a sample point may run before it is counted as running its whole
#: budget: bounds the sample's cost (a point that settles within it costs what it did) [-].
SAMPLE_STEPS = 1_000_000
#: The same bound for a beam sample point, in forcing periods (the beam's solver counts
#: periods, each of its own many steps): the beam presets' budget, so that a point that
#: never settles is timed as it will run [-].
BEAM_SAMPLE_PERIODS = 2000
#: The cost of one point in a round, as a share of the round's own cost (its Python and the
#: engine call): a ratio of two Python costs, which a machine's speed changes alike; fitted
#: on the benchmark grids and the frequency response (benchmarks/results/estimate_44.md) [-].
POINT_ROUND_SHARE = 0.01
#: Timed runs of the engine's rate, the best taken [-].
RATE_RUNS = 3
#: RK4 steps of one timed run of the engine's rate (about 10 ms) [-].
RATE_STEPS = 1_000_000
#: A grid of fewer points than this is not sampled before it runs (:func:`sweep_estimate`):
#: the sample solves up to SAMPLE_POINTS of its points and times the engine, a good share
#: of such a run, and more than the run itself on a grid of a few points [-].
SAMPLED_GRID = 8 * SAMPLE_POINTS
#: The same for a beam sweep, whose sample solves a chunk's worth of points (seconds),
#: a tenth or less of a grid of this many [-].
BEAM_SAMPLED_GRID = 1024
#: A beam sample's points at the most [-].
BEAM_SAMPLE_POINTS = 64
#: The rate a small grid's budget is bounded at, a tenth of the nominal one: the solver's
#: copies, error estimates and re-solves besides the motion, and a slow or loaded machine,
#: fit in that margin [RK4 steps/s].
BOUND_RATE = timescales.STEPS_PER_SECOND / 10


@dataclass(frozen=True)
class Sample:
    """What the solver did on a sample of a grid's points, and this machine's costs.

    Attributes
    ----------
    head_steps, head_rounds : float
        RK4 steps and rounds of a point solved from rest (the mean over the sample).
    head_max_rounds : float
        The most rounds of a point from rest: a chunk of points from rest runs until its
        slowest is done.
    line_steps, line_rounds : float
        The same of a point that starts from its neighbour's orbit (NaN without
        continuation).
    line_max_rounds : float
        The most rounds of such a point over the sample's runs of a line (the mean along
        each): a chunk of lines runs until its slowest is done.
    steps_per_second : float
        The engine's rate on one thread, its lanes filled [RK4 steps/s].
    round_seconds : float
        The cost of a round besides its steps [s].
    setup_seconds : float
        The cost of a point before it is solved: its parameters resolved and packed [s].
    seconds : float
        What the sample and the rate's runs took [s].
    cut_short : str
        How many of the sample's points ran past the periods the sample gives a point and
        were counted at their whole budget, and those periods ("" for none).
    """

    head_steps: float
    head_rounds: float
    head_max_rounds: float
    line_steps: float
    line_rounds: float
    line_max_rounds: float
    steps_per_second: float
    round_seconds: float
    setup_seconds: float
    seconds: float
    cut_short: str = ""

    def point_seconds(self, steps: float, rounds: float, threads: int) -> float:
        """The time [s] a point of ``steps`` RK4 steps in ``rounds`` rounds adds to its
        round, its steps on ``threads`` threads."""
        return (self.setup_seconds + rounds * POINT_ROUND_SHARE * self.round_seconds
                + steps / (self.steps_per_second * threads))


@dataclass(frozen=True)
class RunEstimate:
    """The work of a run, and its time.

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
    seconds : float
        Expected wall time [s].
    starts : int
        Runs from a start of their own at each point (a basin map's samples), 1 for a sweep.
    cut_short : str
        How many sampled points were counted at their whole budget (Sample.cut_short).
    """

    points: int
    remaining: int
    steps: float
    threads: int
    seconds: float
    starts: int = 1
    cut_short: str = ""

    @property
    def long(self) -> bool:
        """True when the run is expected to take more than LONG_RUN_SECONDS."""
        return self.seconds > LONG_RUN_SECONDS

    def describe(self) -> str:
        """One line: size, steps and time (the size alone where no time was estimated)."""
        todo = "" if self.remaining == self.points else f" ({self.remaining:,} still to run)"
        starts = f" x {self.starts:,} starts" if self.starts > 1 else ""
        size = f"{self.points:,} point{'s' if self.points != 1 else ''}{starts}{todo}"
        if math.isnan(self.seconds):
            return size
        counted = f" ({self.cut_short})" if self.cut_short else ""
        steps = "" if math.isnan(self.steps) else f" about {self.steps:.2g} RK4 steps:"
        return (f"{size},{steps} roughly "
                f"{duration(self.seconds)} on {self.threads} thread"
                f"{'s' if self.threads > 1 else ''}{counted}")


def sweep_estimate(spec, remaining: int, threads: int) -> RunEstimate:
    """What a sweep ``spec`` (a SweepSpec) says of ``remaining`` points before it runs:
    :func:`estimate`; but a grid of fewer than SAMPLED_GRID points that cannot be long (its
    every point run for its whole budget at its first step would take less than
    LONG_RUN_SECONDS at BOUND_RATE on one thread) is not sampled, and says its size alone
    (``seconds`` and ``steps`` NaN)."""
    threads = max(1, threads)
    if remaining > 0 and spec.n_points < SAMPLED_GRID:
        points = [spec.point_parameters(spec.values_at(i)) for i in range(spec.n_points)]
        with warnings.catch_warnings():  # (a StabilityWarning is the run's to give, once)
            warnings.simplefilter("ignore")
            rows = pack_points(points).rows
        budget = float((rows[:, PARAM.max_periods] * rows[:, PARAM.steps]).sum())
        if budget / BOUND_RATE <= LONG_RUN_SECONDS:
            return RunEstimate(spec.n_points, remaining, math.nan, threads, math.nan)
    return estimate(spec, remaining, threads)


def estimate(spec, remaining: int, threads: int) -> RunEstimate:
    """The expected work and time of ``remaining`` points of ``spec`` (a SweepSpec) on
    ``threads`` threads (its chunks one after another; more threads than this process's
    numba threads: chunks side by side on Dask workers)."""
    threads = max(1, threads)
    if remaining <= 0:
        return RunEstimate(spec.n_points, 0, 0.0, threads, 0.0)
    sample = _sweep_sample(spec)
    length = spec.line_length
    lines = remaining / length
    per_chunk = min(spec.lines_per_chunk, math.ceil(lines))
    if spec.continuation:
        line_steps = sample.head_steps + (length - 1) * sample.line_steps
        line_rounds = sample.head_rounds + (length - 1) * sample.line_rounds
        chunk_rounds = sample.head_max_rounds + (length - 1) * (
            sample.line_max_rounds if per_chunk > 1 else sample.line_rounds)
    else:
        line_steps, line_rounds = sample.head_steps, sample.head_rounds
        chunk_rounds = sample.head_max_rounds
    return _timed(spec.n_points, remaining, lines, per_chunk, line_steps, line_rounds,
                  chunk_rounds, sample, threads)


def estimate_basins(spec, threads: int, starts_per_call: int) -> RunEstimate:
    """The expected work and time of a basin map ``spec`` (a basins.BasinSpec) on
    ``threads``, its starts solved ``starts_per_call`` at a time: every start counted as a
    point from rest (a start near an orbit settles sooner), and under a shock each point's
    run from rest too."""
    threads = max(1, threads)
    sample = _basin_sample(spec)
    runs = spec.samples + (1 if spec.shock is not None else 0)
    starts = spec.n_points * runs
    per_call = max(1, starts_per_call // spec.samples) * runs
    work = _timed(spec.n_points, spec.n_points, starts, min(per_call, starts),
                  sample.head_steps, sample.head_rounds, sample.head_max_rounds, sample,
                  threads)
    return RunEstimate(spec.n_points, spec.n_points, work.steps, threads, work.seconds,
                       spec.samples, sample.cut_short)


def beam_estimate(spec, remaining: int, threads: int, solve) -> RunEstimate:
    """The expected time of ``remaining`` points of a beam sweep ``spec`` (a SweepSpec of
    ``model = "beam"``) on ``threads`` threads (more than this process's numba threads:
    chunks side by side on Dask workers).

    The beam's solver lies in a layer above this module, so it comes as ``solve(points,
    starts)``: the validated parameters of some points and the states they start from
    (None: rest), returning each point's ``periods_run`` [-] and end state. A sample of
    the grid is solved with it as the sweep solves it (:func:`_sample_index`: points from
    rest, or runs of a line one frequency step at a time, each from the last one's orbit),
    as many points a call as a chunk's calls hold (up to BEAM_SAMPLE_POINTS), so that the
    solver's cost of a round is shared as in the run; each sample point's budget is cut to
    BEAM_SAMPLE_PERIODS, and a point cut short is counted at its whole budget, as it will
    run if it never settles. A point's expected time is the wall time of the sample's
    points of its kind (from rest, or from a neighbour) per point. A grid of fewer than
    BEAM_SAMPLED_GRID points is not sampled and says its size alone (``seconds`` NaN).
    ``steps`` is NaN: the beam's solver counts periods, not RK4 steps."""
    threads = max(1, threads)
    if remaining <= 0 or spec.n_points < BEAM_SAMPLED_GRID:
        return RunEstimate(spec.n_points, remaining, math.nan, threads,
                           0.0 if remaining <= 0 else math.nan)
    # (as many points a call as the chunks' calls hold: the solver's cost of a round,
    # shared by its points, is then shared as in the run)
    index, segment = _sample_index(spec, min(BEAM_SAMPLE_POINTS, spec.lines_per_chunk
                                             * min(SEGMENT, spec.line_length)))
    runs = index.reshape(-1, segment)  # (a run of a line per row)
    # (a first point solved outside the timing loads the compiled engine's functions)
    first = spec.point_parameters(spec.values_at(int(index[0])))
    solve([dict(first, max_periods=min(first["max_periods"], BEAM_SAMPLE_PERIODS))], None)
    ends, expected, cut, cap = None, np.zeros(2), 0, math.inf
    for k in range(segment):
        points = [spec.point_parameters(spec.values_at(int(i))) for i in runs[:, k]]
        budget = np.array([p["max_periods"] for p in points], dtype=float)
        given = np.minimum(budget, BEAM_SAMPLE_PERIODS)
        began = time.perf_counter()
        periods, ends = solve([dict(p, max_periods=int(g)) for p, g in zip(points, given)],
                              ends)
        took = time.perf_counter() - began
        periods = np.maximum(np.asarray(periods, dtype=float), 1.0)
        short = (periods >= given) & (budget > given)
        cut, cap = cut + int(short.sum()), min(cap, given.min())
        # the call's time, scaled to the periods its points are expected to run; the
        # runs' first points from rest, the others continued
        expected[min(k, 1)] += took * np.where(short, budget, periods).sum() / periods.sum()
    per_point = expected / np.array([len(runs), max(len(runs) * (segment - 1), 1)])
    length = spec.line_length
    lines = remaining / length
    side_by_side = _threads_here(threads)[1]
    chunks = math.ceil(lines / min(spec.lines_per_chunk, math.ceil(lines)))
    cut_short = (f"{cut} of {index.size} sampled points did not settle within the "
                 f"sample's {cap:.0f} periods and are counted at their whole budget "
                 "(max_periods)" if cut else "")
    total = lines * (per_point[0] + (length - 1) * per_point[1])
    return RunEstimate(spec.n_points, remaining, math.nan, threads,
                       total / min(side_by_side, chunks), cut_short=cut_short)


def _threads_here(threads: int) -> tuple[int, int]:
    """Of a run's ``threads``: this process's numba threads it takes, and the chunks it
    runs side by side (on Dask workers, when ``threads`` is more than this process has)."""
    import numba

    local = max(1, min(threads, numba.get_num_threads()))
    return local, max(1, threads // local)


def _timed(points, remaining, lines, per_chunk, line_steps, line_rounds, chunk_rounds,
           sample, threads) -> RunEstimate:
    """The time of ``lines`` lines (each ``line_steps`` steps in ``line_rounds`` point
    rounds) run ``per_chunk`` lines at a time, a chunk's rounds ``chunk_rounds``."""
    local, side_by_side = _threads_here(threads)
    chunks = math.ceil(lines / per_chunk)
    # A call's steps: its lines' share of a round; a short call (SHORT_CALL, the engine's
    # own line) takes one thread.
    call_steps = per_chunk * line_steps / max(line_rounds, 1.0)
    call_threads = 1 if call_steps < SHORT_CALL else min(local, math.ceil(per_chunk / LANES))
    seconds = (chunks * chunk_rounds * sample.round_seconds
               + lines * sample.point_seconds(line_steps, line_rounds, call_threads))
    return RunEstimate(points, remaining, lines * line_steps, threads,
                       seconds / min(side_by_side, chunks), cut_short=sample.cut_short)


def _sweep_sample(spec) -> Sample:
    """The Sample of a sweep (SweepSpec), measured once per process and sweep."""
    digest = spec.digest()
    if digest not in _SAMPLES:
        if len(_SAMPLES) >= 8:
            _SAMPLES.pop(next(iter(_SAMPLES)))
        _SAMPLES[digest] = _sample_of(spec)
    return _SAMPLES[digest]


_SAMPLES: dict = {}  # a sweep's digest -> its Sample, measured in this process


def _sample_of(spec) -> Sample:
    index, segment = _sample_index(spec)
    successors = np.where(np.arange(len(index)) % segment < segment - 1,
                          np.arange(len(index)) + 1, -1)
    packed, setup = _resolved(lambda i: spec.point_parameters(spec.values_at(i)), index,
                              spec.n_points)
    return _measure(packed, successors, spec.estimated(index), setup)


def _sample_index(spec, count: int = SAMPLE_POINTS) -> tuple[np.ndarray, int]:
    """The grid's points (flat indices) a sample solves, and the length of its runs: up to
    ``count`` points spread over the grid, each from rest (runs of 1); under continuation
    runs of SEGMENT consecutive points of a line in its direction, one after another in
    the array, the first of each from rest."""
    length = spec.line_length
    if not spec.continuation:
        return _spread(spec.n_points, count), 1
    segment = min(SEGMENT, length)
    lines = _spread(spec.n_lines, max(1, count // segment))
    firsts = _spread(length - segment + 1, len(lines))
    index = []
    for line, first in zip(lines, np.resize(firsts, len(lines))):
        position = np.arange(first, first + segment)
        if spec.directions[np.unravel_index(line, spec.line_shape)[0]] == "down":
            position = length - 1 - position  # (a down line runs from its top)
        index.extend(line * length + position)
    return np.asarray(index), segment


def _basin_sample(spec) -> Sample:
    """The Sample of a basin map (basins.BasinSpec): its points from rest."""
    index = _spread(spec.n_points, SAMPLE_POINTS)
    packed, setup = _resolved(spec.point, index, spec.n_points)
    return _measure(packed, np.full(len(index), -1), np.zeros(len(index), dtype=bool),
                    setup)


def _spread(n: int, count: int) -> np.ndarray:
    """Up to ``count`` indices spread evenly over 0 .. n - 1."""
    return np.unique(np.linspace(0, n - 1, min(count, n)).round().astype(np.int64))


def _resolved(point, index, n: int) -> tuple[object, float]:
    """The points ``index`` of a grid of ``n`` (``point(i)``: validated parameters)
    packed, and the time [s] a point takes to be resolved and packed: timed on their
    neighbours, as the first points resolved and packed in a process pay for its first
    calls."""
    with warnings.catch_warnings():  # (a StabilityWarning is the run's to give, once)
        warnings.simplefilter("ignore")
        packed = pack_points([point(int(i)) for i in index])
        began = time.perf_counter()
        pack_points([point(int(i)) for i in (index + 1) % n])
    return packed, (time.perf_counter() - began) / len(index)


def _measure(packed, successors, estimated, setup: float) -> Sample:
    """Solve ``packed`` points (``successors`` as the engine's, each line's first from
    rest) for real, and time the engine on their orbits; ``setup``: a point's time to be
    resolved and packed [s]."""
    rows = packed.rows.copy()
    budget = rows[:, PARAM.max_periods].copy()
    rows[:, PARAM.max_periods] = np.minimum(
        budget, np.maximum(np.floor(SAMPLE_STEPS / rows[:, PARAM.steps]), 1.0))
    compile_solver()  # (compiled or loaded outside the timing)
    began = time.perf_counter()
    orbits = solve_orbits(rows, packed.states, successors, estimated & ~packed.refused,
                          packed.accuracy, packed.max_steps)
    solving = time.perf_counter() - began
    steps = orbits.rk4_steps.astype(float)
    done = orbits.rounds.astype(float)  # the round each point was done in
    heads = np.ones(len(packed), dtype=bool)
    heads[successors[successors >= 0]] = False
    # A continued point's rounds: from its predecessor's end to its own (a successor
    # starts once its predecessor is on its orbit, so at least one).
    before = np.zeros(len(packed))
    linked = successors >= 0
    before[successors[linked]] = done[linked]
    rounds = np.where(heads, done, np.maximum(done - before, 1.0))
    # A point cut short by the sample's budget runs on to its own.
    run = orbits.metrics[:, METRIC.periods_run]
    short = (orbits.metrics[:, METRIC.status] != STATUS.settled) \
        & (run >= rows[:, PARAM.max_periods]) \
        & (budget > rows[:, PARAM.max_periods])
    more = np.where(short, budget / np.maximum(run, 1.0), 1.0)
    cut, given = int(short.sum()), rows[short, PARAM.max_periods]
    cut_short = (f"{cut} of {len(short)} sampled points did not settle within the "
                 f"sample's {given.min():.0f} period{'s' if given.min() > 1 else ''} and are "
                 "counted at their whole budget (max_periods)" if cut else "")
    rate, rating = _engine_rate(rows, orbits.finals, packed.refused)
    import numba

    threads = max(1, min(numba.get_num_threads(), math.ceil(len(packed) / LANES)))
    besides = solving - steps.sum() / (rate * threads)
    share = done.max() + POINT_ROUND_SHARE * rounds.sum()
    # (at least a third of the sample's time is its rounds': its steps at the best rate
    # seen take no less)
    round_seconds = max(besides, solving / 3) / max(share, 1.0)
    steps, rounds = steps * more, rounds * more
    runs = ~packed.refused

    def mean(values, where):
        where = where & runs
        return float(values[where].mean()) if where.any() else math.nan

    line = np.cumsum(heads) - 1  # each point's run of a line (the sample's points in order)
    spans = [mean(rounds, ~heads & (line == k)) for k in range(line[-1] + 1)]
    slowest = max((r for r in spans if not math.isnan(r)), default=math.nan)
    return Sample(mean(steps, heads), mean(rounds, heads),
                  float(rounds[heads & runs].max()) if (heads & runs).any() else 0.0,
                  mean(steps, ~heads), mean(rounds, ~heads), slowest, rate, round_seconds,
                  setup, solving + rating + 2 * setup * len(packed), cut_short)


def _engine_rate(rows, states, refused) -> tuple[float, float]:
    """RK4 steps per second and thread of the engine on ``rows`` from ``states`` (copies
    of the points enough to fill every thread's lanes), the best of RATE_RUNS timed calls;
    and the seconds the calls took."""
    import numba

    keep = ~refused
    if not keep.any():  # (nothing runs: the nominal rate, never used on a step)
        return timescales.STEPS_PER_SECOND, 0.0
    threads = numba.get_num_threads()
    copies = math.ceil(2 * LANES * threads / keep.sum())
    rows, states = np.repeat(rows[keep], copies, axis=0), np.repeat(states[keep], copies,
                                                                       axis=0)
    periods = max(1, round(RATE_STEPS / rows[:, PARAM.steps].sum()))
    best, began = math.inf, time.perf_counter()
    for _ in range(RATE_RUNS):
        batch = period_map.Batch(period_map.state_size(rows), 1)
        batch.add(rows, states, periods, book=True)
        start = time.perf_counter()
        (run,) = batch.run()
        best = min(best, time.perf_counter() - start)
    steps = float(run.work.sum())
    used = min(threads, math.ceil(len(rows) / LANES))
    return steps / (best * used), time.perf_counter() - began


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


def duration(seconds: float) -> str:
    """``seconds`` [s] in the unit a reader takes in at once: s, min, h, days or years."""
    for unit, size in (("years", 365.25 * 86400), ("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= 2 * size:
            return f"{_rounded(seconds / size)} {unit}"
    return f"{_rounded(seconds)} s"


def _rounded(value: float) -> str:
    """Two significant digits, without an exponent below 1e15."""
    return f"{value:.2g}" if value < 10 or value >= 1e15 else f"{float(f'{value:.2g}'):,.0f}"
