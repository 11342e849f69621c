"""Lines of points walked by the kernel (_engine.run_points with successors), against the
same points run one call at a time, each from the final state of the one before."""

import warnings

import numba
import numpy as np
import pytest

from harvester_sweep import _engine, packing, resolve_parameters
from harvester_sweep._engine import METRIC, PARAM, STATE, STATUS, atomic, scheduler

FREQUENCIES = np.linspace(120.0, 300.0, 12)  # [Hz] through the impacting band and out


def _line(gap, steps=256, diverge_at=None):
    """Rows of one up line at ``gap`` [m]; the point ``diverge_at`` with a stop so stiff
    that RK4 diverges at this step."""
    rows = []
    for k, f in enumerate(FREQUENCIES):
        extra = {"hertz_stiffness": 1e13} if k == diverge_at else {}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the stability warning of the stiff stop
            p = resolve_parameters("paper", gap=gap, frequency=float(f),
                                   steps_per_period=steps, max_periods=400, **extra)
        rows.append(packing.pack_parameters(p))
    return np.array(rows), packing.initial_state(p)


def _one_call_per_point(rows, rest):
    """The reference: each point in a call of its own, from the final state of the point
    before (from rest after a diverged one, nothing run for a row of no period)."""
    n = len(rows)
    metrics, finals = np.full((n, len(METRIC)), -1.0), np.empty((n, len(STATE)))
    state = rest.copy()
    for i in range(n):
        if rows[i, PARAM.max_periods] == 0:  # refused: no values, status too stiff
            finals[i] = state
            metrics[i, :] = np.nan
            metrics[i, [METRIC.orbit_period, METRIC.periods_run]] = 0.0
            metrics[i, METRIC.status] = STATUS.too_stiff
            continue
        s = state[None, :].copy()
        _engine.run_points(rows[i:i + 1], s, metrics[i:i + 1], np.empty((1, 0, 3)))
        finals[i] = s[0]
        state = rest.copy() if metrics[i, METRIC.status] == STATUS.diverged else s[0]
    return metrics, finals


def _walked(lines, threads):
    """All lines in one call, the lanes walking them."""
    rows = np.concatenate([r for r, _ in lines])
    states = np.concatenate([np.repeat(rest[None, :], len(r), axis=0) for r, rest in lines])
    successors = np.arange(1, len(rows) + 1)
    ends = np.cumsum([len(r) for r, _ in lines]) - 1
    successors[ends] = -1
    metrics = np.full((len(rows), len(METRIC)), -1.0)
    numba.set_num_threads(threads)
    try:
        _engine.run_points(rows, states, metrics, np.empty((len(rows), 0, 3)), successors)
    finally:
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    return metrics, states


def test_walked_lines_give_the_bits_of_one_call_per_point():
    """20 lines (more than the lanes of a thread), one with a diverging point and one with a
    point of no period in the middle: the same bits as one point per call, on 1 and 2
    threads."""
    gaps = np.linspace(0.3e-6, 4e-6, 20)
    lines = [_line(g, diverge_at=5 if i == 3 else None) for i, g in enumerate(gaps)]
    lines[7][0][4, PARAM.max_periods] = 0  # refused before integration: not run
    expected = [_one_call_per_point(r, rest) for r, rest in lines]
    statuses = np.concatenate([m[:, METRIC.status] for m, _ in expected])
    assert (statuses == STATUS.diverged).sum() == 1 and (statuses == STATUS.settled).sum() > 100
    impacts = np.concatenate([m[:, METRIC.impacts_per_period] for m, _ in expected])
    assert (impacts > 0).sum() > 20 and (impacts == 0).sum() > 20  # both branches
    want_m = np.concatenate([m for m, _ in expected])
    want_s = np.concatenate([s for _, s in expected])
    for threads in (1, 2):
        metrics, states = _walked(lines, threads)
        np.testing.assert_array_equal(metrics, want_m)
        np.testing.assert_array_equal(states, want_s)
    skipped = 7 * len(FREQUENCIES) + 4
    assert metrics[skipped, METRIC.status] == STATUS.too_stiff  # written by the engine
    np.testing.assert_array_equal(states[skipped], states[skipped - 1])  # its state passes on


def test_progress_is_reported_as_points_finish_and_an_error_stops_the_run(monkeypatch):
    monkeypatch.setattr(scheduler, "_POLL", 0.01)
    rows, rest = _line(1e-6, steps=1024)
    rows = np.repeat(rows[1:2], 2000, axis=0)  # 2000 lines of one point, alike
    n = len(rows)
    reports = []
    metrics = np.full((n, len(METRIC)), -1.0)
    _engine.run_points(rows, np.repeat(rest[None, :], n, axis=0), metrics,
                     np.empty((n, 0, 3)), on_points=reports.append)
    assert sum(reports) == n and len(reports) > 1
    assert (metrics[:, METRIC.periods_run] == metrics[0, METRIC.periods_run]).all()
    few = []
    _engine.run_points(rows[:1], rest[None, :].copy(), metrics[:1], np.empty((1, 0, 3)),
                     on_points=few.append)
    assert few == [1]  # reported however fast the kernel ends

    class Stop(Exception):
        pass

    def stop(count):
        raise Stop

    metrics[:] = -1.0
    with pytest.raises(Stop):
        _engine.run_points(rows, np.repeat(rest[None, :], n, axis=0), metrics,
                         np.empty((n, 0, 3)), on_points=stop)
    run = (metrics[:, METRIC.periods_run] >= 0).sum()
    assert 0 < run < n // 2  # the points under way were finished, no other was taken


@numba.njit(parallel=True)
def _take_all(counts, n):
    """Two threads take n values each from counts[1] with atomic.fetch_add."""
    taken = np.empty(2 * n, dtype=np.int64)
    for thread in numba.prange(2):
        for i in range(n):
            taken[thread * n + i] = atomic.fetch_add(counts, 1)
    return taken


def test_threads_taking_from_one_counter_get_each_value_once():
    # The threads take lines from one queue by this counter (scheduler._next_point): a take
    # that was not atomic would hand a line to two lanes, or lose one.
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    try:
        counts = np.zeros(3, dtype=np.int64)
        taken = _take_all(counts, 200_000)
    finally:
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    assert counts[1] == 400_000 and counts[0] == counts[2] == 0
    np.testing.assert_array_equal(np.sort(taken), np.arange(400_000))


@pytest.mark.parametrize("successors", [[1, 1, -1], [1, 3, -1], [1, -2, -1], [1, -1],
                                        [-1, 2, 1], [-1, 1, -1]])
def test_bad_successors_are_refused(successors):
    rows, rest = _line(1e-6)
    with pytest.raises(ValueError, match="successors"):
        _engine.run_points(rows[:3], np.repeat(rest[None, :], 3, axis=0),
                         np.empty((3, len(METRIC))), np.empty((3, 0, 3)), successors)
