"""Which point each lane steps: lines of points, one shared queue, threads and progress.

A *line* is a run of points each of which starts from the final state of the one before
(the frequencies of a continuation); a point run from rest is a line of one. Each thread
steps LANES points at once (:mod:`.lanes`); a lane whose point is done takes the next
point of its line, or else the first point of the next line of a queue every thread
takes from (an atomic counter), so that slow points do not hold a group back, no lane
waits for other lines and the threads end together. Once the queue is empty the points
left move to the first lanes and an empty group is skipped.

A point's result does not depend on its lane, its thread or the thread count
(tests/engine/test_reproducibility.py).
"""

from __future__ import annotations

import concurrent.futures
import os
import threading

import numba
import numpy as np
from numba import prange

from ..jit import JIT, njit
from . import lanes, tangents
from .atomic import fetch_add
from .layouts import (
    ACC,
    GROUP,
    LANE,
    LANES,
    METRIC,
    N_RIGID,
    N_STROBE,
    PARAM,
    SERIES,
    STATE,
    STATUS,
)
from .monodromy import free_extent, free_monodromy
from .steady import GAP_HISTORY, MAX_ORBIT_PERIOD


@njit(**JIT)
def _run_queue(params, states, metrics, strobes, series, settle, queue, successors, control, b,
               derivatives):
    """Run lines that start at the points ``queue`` (indices) to their ends, LANES at a
    time, as thread ``b``, writing the monodromy of each point that carries tangents into
    ``derivatives`` (see run_independent): a lane whose point is done takes the point
    ``successors`` names next on its line (-1: none), from the state it left, or else the
    next line not yet taken from the queue (by any thread), so that no lane waits for the
    slowest point.
    ``control[b]`` counts the points done; ``control[-1]`` set to nonzero stops taking
    points (see _next_point)."""
    n_lanes = min(LANES, len(queue))
    n_strobe = strobes.shape[1]
    ring_len = max(MAX_ORBIT_PERIOD + 1, n_strobe)
    L = lanes.new_table()
    ring = np.empty((n_lanes, ring_len, N_STROBE))
    acc = np.zeros((n_lanes, MAX_ORBIT_PERIOD, len(ACC)))
    gaps = np.empty((n_lanes, GAP_HISTORY, MAX_ORBIT_PERIOD + 1))
    point = np.full(n_lanes, -1)
    n_series = series.shape[0]
    for j in range(LANES):
        lanes.idle(L, j)
    active = 0
    # the lanes in contact that carry tangents (lanes.carriers), listed again whenever a
    # lane may have joined or left them
    carriers = np.empty(LANES, dtype=np.int64)
    n_carriers, relist = 0, True
    for j in range(n_lanes):  # the lanes that get no point are the last ones
        # (none done yet, as typed values: the same compile of _next_point as the call below)
        pt = _next_point(params, states, metrics, strobes, successors, queue, np.int64(-1),
                         np.bool_(False), control, b)
        if pt < 0:
            break
        lanes.take(L, j, params, states, pt, ring, acc, gaps, 0.0)
        point[j] = pt
        active += 1
    groups = (active + GROUP - 1) // GROUP
    it = -1.0  # the iteration of the lane loop
    while active > 0:
        it += 1.0
        if n_series > 0:  # one point recorded at every step boundary
            _record(series, L, int(L[LANE.periods] * L[LANE.steps] + it - L[LANE.k0]))
        if relist:
            n_carriers, relist = lanes.carriers(L, n_lanes, carriers), False
        if n_carriers > 0:
            lanes.keep_starts(L, carriers, n_carriers)
        marked, quarters = (lanes.lane_steps(L, it) if groups > 1
                            else lanes.first_group_steps(L, it))
        if n_carriers > 0:
            lanes.carry_tangents(L, carriers, n_carriers, it)
        if marked == 0:
            continue
        if quarters > 0:
            lanes.quarter_steps(L, n_lanes)
        finished = False
        for j in range(n_lanes):
            if L[LANE.need + j] == 0.0 or point[j] < 0:
                continue
            on = L[LANE.on + j]
            ended = lanes.finish_step(L, j, it)
            relist = relist or (L[LANE.tangents + j] != 0.0 and L[LANE.on + j] != on)
            if not ended:
                continue
            pt = point[j]
            status, orbit = lanes.end_period(L, j, params[pt], ring[j], acc[j], gaps[j],
                                             ring_len, n_strobe, settle, it)
            if status < 0:
                continue
            if n_series > 0:
                _record(series, L, int(L[LANE.periods] * L[LANE.steps]))
            lanes.output(L, j, params[pt], states[pt], metrics[pt], strobes[pt], ring[j], acc[j],
                         ring_len, status, orbit)
            if L[LANE.tangents + j] != 0.0 and pt < derivatives.shape[0]:
                tangents.write(L, j, it + 1.0, derivatives[pt])
            relist = True
            control[b] += 1
            pt = _next_point(params, states, metrics, strobes, successors, queue, pt,
                             status == STATUS.diverged, control, b)
            if pt >= 0:
                lanes.take(L, j, params, states, pt, ring, acc, gaps, it + 1.0)
                point[j] = pt
            else:
                point[j] = -1
                lanes.idle(L, j)
                active -= 1
                finished = True
        if finished:  # the queue is empty: move the points left to the first lanes
            active, relist = 0, True
            for j in range(n_lanes):
                if point[j] >= 0:
                    if j != active:
                        lanes.move(L, j, active, ring, acc, gaps)
                        point[active], point[j] = point[j], -1
                    active += 1
            groups = (active + GROUP - 1) // GROUP


@njit(**JIT)
def _next_point(params, states, metrics, strobes, successors, queue, done, diverged, control,
                b):
    """The next point to run after point ``done`` (-1: none yet): ``done``'s successor,
    which starts from ``done``'s final state (from its own initial state, the state at
    rest, when ``done`` ``diverged``), or else the next line of ``queue``, which every
    thread takes from (``control[-2]``, the next to take, is shared); -1 when none is left
    or ``control[-1]`` asks to stop.

    A point whose budget of periods (PARAM.max_periods) is 0 was refused before
    integration (too stiff): it is not run, its outputs say so (lanes.refuse), and its
    state passes on to its successor.
    """
    pt = -1
    if done >= 0:
        pt = successors[done]
        if pt >= 0 and not diverged:
            states[pt, :] = states[done, :]
    while control[len(control) - 1] == 0:
        if pt < 0:
            taken = fetch_add(control, len(control) - 2)
            if taken >= len(queue):
                return -1
            pt = queue[taken]
        if params[pt, PARAM.max_periods] > 0.0:
            return pt
        lanes.refuse(metrics[pt], strobes[pt])
        control[b] += 1
        following = successors[pt]
        if following >= 0:
            states[following, :] = states[pt, :]
        pt = following
    return -1


@njit(inline="always", **JIT)
def _record(series, L, i):
    """Row ``i`` of a recorded series (layouts.SERIES) from the point of lane 0."""
    if i < series.shape[0]:
        s = L[LANE.sign]  # (the lane's state may be mirrored: lanes.mirror)
        series[i, SERIES.x], series[i, SERIES.v] = s * L[LANE.x], s * L[LANE.v]
        series[i, SERIES.voltage], series[i, SERIES.contact_force] = (
            s * L[LANE.voltage], s * L[LANE.fc])
        series[i, SERIES.stop_displacement] = L[LANE.stop_x]
        series[i, SERIES.stop_velocity] = L[LANE.stop_v]


def run_points(params, states, metrics, strobes, successors=None, on_points=None,
               settle=True) -> None:
    """Run every point to steady state, on all numba threads.

    ``params[i]`` is a parameter row (``harvester_sweep.packing``), ``states[i]`` the state
    (updated in place), ``metrics[i]`` and ``strobes[i]`` the outputs (layouts.METRIC;
    the last S stroboscopic samples). Points are independent and each is computed by the
    same instructions whichever lane or thread takes it, so a point's result does not
    depend on the thread count or on the other points.

    ``successors[i]``, when given, is the point that starts from point i's final state
    (-1: none), one frequency on of a continuation line (it starts from its own
    ``states`` when point i diverges); a point is named at most once and lines do not
    close on themselves (else ValueError). A lane walks a line to its end, with no wait for
    other lines. A point whose row has PARAM.max_periods = 0 is not run: its state passes on and its
    outputs are left unwritten. ``on_points(n)``, when given, is called in this thread as
    points finish (n: how many since the last call); the kernel then runs in another
    thread, and stops taking points when ``on_points`` raises (or on KeyboardInterrupt).
    ``settle=False`` runs every point for exactly its budget of periods (PARAM.max_periods),
    with no steady-state test: one evaluation of the period map (period_map.Batch);
    its metrics are those of the periods run (at most MAX_ORBIT_PERIOD).
    """
    n = params.shape[0]
    successors = (np.full(n, -1, dtype=np.int64) if successors is None
                  else np.ascontiguousarray(successors, dtype=np.int64))
    heads = _line_heads(successors, n)
    heads = _taking_order(params, heads)
    threads = call_threads(params, len(heads))
    control = np.zeros(threads + 2, dtype=np.int64)  # points done per thread; next line; stop
    args = (params, states, metrics, strobes, successors, heads, control, settle,
            _NO_DERIVATIVES)
    if on_points is None:
        _run_threads(*args)
        return

    def run():
        numba.set_num_threads(threads)  # (numba's thread count is per calling thread)
        _run_threads(*args)

    def stop():
        control[-1] = 1  # (a no-op once the kernel is done; else it stops taking points)

    run_watched([run], lambda: int(control[:threads].sum()), stop, on_points)


def run_watched(tasks, done, stop, on_points=None) -> None:
    """Run each of ``tasks`` (callables that call compiled code without the GIL) in a
    thread of its own and wait for them all, in a way an interrupt reaches.

    ``on_points(n)``, when given, is called in this thread as ``done()`` (points done so
    far) grows, every _POLL seconds and once at the end; ``stop()`` asks the tasks to take
    no more work: it is called when a task fails, when ``on_points`` raises or at a
    KeyboardInterrupt, and on the way out (a no-op by then). What a task or ``on_points``
    raises is raised again here, once every task has returned.
    """
    failure = []

    def run(task):
        try:
            task()
        except BaseException as error:  # raised again in the calling thread
            failure.append(error)
            stop()

    running = [_workers().submit(run, task) for task in tasks]
    reported = 0
    try:
        while running:
            running = list(concurrent.futures.wait(running, _POLL).not_done)
            now = done()
            if on_points is not None and now > reported:
                on_points(now - reported)
                reported = now
    finally:
        stop()
        concurrent.futures.wait(running)
    if failure:
        raise failure[0]


_pool, _pool_pid = None, None
_pool_lock = threading.Lock()


def _workers() -> concurrent.futures.ThreadPoolExecutor:
    """The threads that run :func:`run_watched`'s tasks, as many as numba may have:
    started once in a process (and again in a forked child, which has none of its
    parent's threads), as threads started for each call made the orbit solver's short
    solves slower (benchmarks/results/groups_47.md)."""
    global _pool, _pool_pid
    with _pool_lock:
        if _pool is None or _pool_pid != os.getpid():
            _pool = concurrent.futures.ThreadPoolExecutor(
                max_workers=numba.config.NUMBA_NUM_THREADS,
                thread_name_prefix="harvester_sweep kernel")
            _pool_pid = os.getpid()
        return _pool


#: The monodromies of a run that keeps none (run_points, record_series): no row's is written.
_NO_DERIVATIVES = np.empty((0, N_RIGID, N_RIGID))
_POLL = 0.2  # seconds between looks at the progress of a kernel run in another thread

#: A call whose budget (periods x steps, summed over its points) is below this many RK4
#: steps runs on one thread: on a quiet machine a second thread saves such a call little
#: (a call on two threads takes half its time on one plus a fixed share:
#: benchmarks/results/period_costs.md), and on a shared machine every thread of a call
#: waits for the slowest, one that is descheduled most of all (issue 44) [steps].
SHORT_CALL = 200_000


def call_threads(params: np.ndarray, lines: int) -> int:
    """The threads a call of :func:`run_points` takes: one for a short call
    (SHORT_CALL), else one for every LANES lines (a thread steps LANES points at once, so
    a thread more gains nothing below that), at most numba's thread count."""
    return _threads(params, lines, numba.get_num_threads())


@njit(**JIT)
def _threads(params, lines, most):
    """call_threads with ``most`` threads at most (numba's count, read by the caller:
    reading it in compiled code keeps the code out of numba's cache)."""
    budget = 0.0
    for i in range(params.shape[0]):
        # (a run that carries its monodromy counts as the N_RIGID + 1 lanes of the copies
        # it stands for: its tangents cost it a few times the state's work in contact)
        lanes_of = N_RIGID + 1.0 if params[i, PARAM.tangents] != 0.0 else 1.0
        budget += params[i, PARAM.max_periods] * params[i, PARAM.steps] * lanes_of
    if budget < SHORT_CALL:
        return 1
    return max(1, min(most, -(-lines // LANES)))


@njit(**JIT)
def _taking_order(params, heads):
    """``heads`` in the order lanes take them: largest budget (periods x steps of their
    first point) first, so that the long runs of a round of the orbit solver (1 to
    orbits.SLICE periods) do not start last and leave the other lanes idle; then by
    forcing period (stable: in the callers' order within one): the lanes of a group then
    hold points whose contacts come at about the same step of the period, so that fewer
    steps of a group run the contact stages."""
    period = np.empty(len(heads))
    work = np.empty(len(heads))
    for k in range(len(heads)):
        period[k] = -params[heads[k], PARAM.period]
        work[k] = -(params[heads[k], PARAM.max_periods] * params[heads[k], PARAM.steps])
    by_period = np.argsort(period, kind="mergesort")
    by_work = np.argsort(work[by_period], kind="mergesort")
    return heads[by_period[by_work]]


@njit(**JIT)
def run_independent(params, states, metrics, strobes, settle, most, derivatives):
    """:func:`run_points` for points that are each a line of their own (no successors),
    callable from compiled code, on at most ``most`` threads (numba's count, read by the
    Python caller): the orbit solver's rounds. A point whose row asks for tangents
    (PARAM.tangents) and can carry them (tangents.carried) gets its run's monodromy
    dy(end)/dy(start) of the rigid model's state in ``derivatives[i]`` (n, 3, 3); the
    others' are left unwritten. numba's threads must have been started
    (numba.get_num_threads, or a parallel function called from Python, starts them): a
    parallel loop reached from compiled code does not start them, and crashes."""
    n = params.shape[0]
    heads = _taking_order(params, np.arange(n))
    threads = _threads(params, n, most)
    control = np.zeros(threads + 2, dtype=np.int64)
    successors = np.full(n, -1, dtype=np.int64)
    if threads == 1:
        # (no parallel region: the orbit solver's groups of points each call from a thread
        # of their own at once, and numba's workqueue threading layer, the one it falls
        # back to, takes one parallel call at a time)
        _run_queue(params, states, metrics, strobes, np.empty((0, len(SERIES))), settle,
                   heads, successors, control, np.int64(0), derivatives)
    else:
        _run_threads(params, states, metrics, strobes, successors, heads, control, settle,
                     derivatives)


def _line_heads(successors: np.ndarray, n: int) -> np.ndarray:
    """The first point of every line of ``successors`` (see run_points); ValueError where
    they do not make lines."""
    linked = successors[successors >= 0]
    if successors.shape != (n,) or (successors < -1).any() or (linked >= n).any() \
            or len(np.unique(linked)) != len(linked):
        raise ValueError("successors: must hold, for each point, the index of another point "
                         "or -1, no point named twice")
    continued = np.zeros(n, dtype=bool)
    continued[linked] = True
    heads = np.flatnonzero(~continued)
    walked, ahead = len(heads), heads
    while ahead.size:  # one point further along every line per pass
        ahead = successors[ahead]
        ahead = ahead[ahead >= 0]
        walked += ahead.size
    if walked != n:  # the points left over close on themselves
        raise ValueError("successors: a cycle of points (a line must have a first point)")
    return heads


@njit(parallel=True, nogil=True, **JIT)
def _run_threads(params, states, metrics, strobes, successors, heads, control, settle,
                 derivatives):
    """Every thread takes lines from ``heads`` as its lanes need them (see _next_point),
    so that the threads end together whatever the lines cost."""
    no_series = np.empty((0, len(SERIES)))
    for b in prange(len(control) - 2):
        # (b as int64, the type record_series calls with: numba compiled the queue for the
        # prange index both as int64 and as uint64)
        _run_queue(params, states, metrics, strobes, no_series, settle, heads, successors,
                   control, np.int64(b), derivatives)


def warm_up() -> None:
    """Compile :func:`run_points` and the closed-form period map (or load them from numba's
    on-disk cache) without running."""
    free_monodromy(np.zeros((0, len(PARAM))), np.zeros(0), np.zeros(0, dtype=np.int64),
                   np.zeros((0, N_RIGID, N_RIGID)))
    free_extent(np.zeros((0, len(PARAM))), np.zeros((0, len(STATE))), 64, np.zeros((0, 2)))
    run_points(np.zeros((0, len(PARAM))), np.zeros((0, len(STATE))), np.zeros((0, len(METRIC))),
               np.zeros((0, 0, N_STROBE)))


def record_series(row: np.ndarray, state: np.ndarray, periods: int) -> np.ndarray:
    """The point of parameter row ``row`` at every step over ``periods`` forcing periods
    from ``state``, not modified.

    Returns a float64 array of shape ``(periods * steps_per_period + 1, len(SERIES))``,
    columns as layouts.SERIES.
    """
    row = row.copy()
    row[PARAM.max_periods] = periods
    row[PARAM.multi] = 1.0  # (every step recorded)
    n_steps = int(row[PARAM.steps])
    series = np.empty((periods * n_steps + 1, len(SERIES)))
    _run_queue(row[None, :], state.copy()[None, :], np.empty((1, len(METRIC))),
               np.empty((1, 0, N_STROBE)), series, False, np.zeros(1, dtype=np.int64),
               np.full(1, -1, dtype=np.int64), np.zeros(3, dtype=np.int64), 0,
               _NO_DERIVATIVES)
    return series
