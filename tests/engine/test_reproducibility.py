"""The same input gives the same bits, whatever the thread count or the other points."""

import numba
import numpy as np

from harvester_sweep import _engine, packing, resolve_parameters, run_scene, run_sweep
from harvester_sweep._engine import BOOKED_METRICS, METRIC, PARAM
from harvester_sweep.results import solve


def _strip(metrics):
    return {k: v for k, v in metrics.items() if k not in ("run_time", "converged")}


def test_same_scene_same_bits():
    assert _strip(run_scene("paper").metrics) == _strip(run_scene("paper").metrics)


def test_point_independent_of_threads_and_neighbours():
    """A scene and the same point solved among others (with and without contact, one
    continued from another), on one and two threads: the periodic-orbit solver gives the
    same bits, multipliers and error estimate included."""
    alone = run_scene("paper", gap=1.2e-6)
    points = [resolve_parameters("paper", gap=g) for g in (0.5e-6, 1.2e-6, 3e-6, 1.0)]
    packed = packing.pack_points(points)
    successors = np.array([-1, -1, 3, -1])  # (the gap of 1 m starts from the 3 um orbit)
    runs = []
    for threads in (1, 2):
        numba.set_num_threads(threads)
        runs.append(solve(packed, successors, np.ones(4, dtype=bool)))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    for name in ("metrics", "finals", "errors", "multipliers", "steps", "rk4_steps"):
        np.testing.assert_array_equal(getattr(runs[0], name), getattr(runs[1], name))
    assert _strip(runs[0].point(1)) == _strip({**alone.metrics, "converged": True})
    np.testing.assert_array_equal(runs[0].finals[1], alone.state)


def test_beam_point_independent_of_threads_and_neighbours():
    """Beam points of very different cost (one that does not settle in its budget, one on a
    period-2 orbit, others that settle in a few periods, one clear of the stop) solved
    together on one and two threads, and one of them alone: the same bits (the modal
    engine deals its points from a shared counter, in an order that depends on the
    threads' timing)."""
    from harvester_sweep.beam_parameters import resolve_beam_parameters
    from harvester_sweep.beam_runs import solve_beam

    points = [resolve_beam_parameters("bimorph_tip", n_modes=2, frequency=f, gap=g,
                                      max_periods=300)
              for f, g in ((180.0, 1e-6), (155.0, 1e-6), (150.0, 3e-6), (140.0, 1.0),
                           (128.0, 1e-6))]
    runs = []
    for threads in (1, 2):
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        runs.append(solve_beam(points))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    assert list(runs[0].values["status"][:2]) == [1, 0]  # (not settled; settled)
    assert runs[0].values["orbit_period"][1] == 2
    alone = solve_beam(points[1:2])
    for name, values in runs[0].values.items():
        np.testing.assert_array_equal(values, runs[1].values[name])
        np.testing.assert_array_equal(values[1], alone.values[name][0])
    np.testing.assert_array_equal(np.array(runs[0].ends), np.array(runs[1].ends))


def test_point_same_bits_in_every_lane():
    """The same point in four different vectors and lanes of a queue, among other points
    (some striking the stop, some not), on one and two threads: the same bits each time."""
    target = resolve_parameters("paper", gap=0.8e-6, frequency=138.0)
    others = [resolve_parameters("paper", gap=g, frequency=f)
              for g in (0.3e-6, 2e-6, 5e-6) for f in (120.0, 135.0, 150.0, 170.0, 200.0)]
    points = others[:]
    slots = (0, 6, 13, 18)
    for slot in slots:
        points.insert(slot, target)
    rows = np.array([packing.pack_parameters(p) for p in points])
    for threads in (1, 2):
        numba.set_num_threads(threads)
        states = np.array([packing.initial_state(p) for p in points])
        metrics = np.empty((len(points), len(METRIC)))
        _engine.run_points(rows, states, metrics, np.empty((len(points), 0, 3)))
        for slot in slots[1:]:
            np.testing.assert_array_equal(metrics[slot], metrics[slots[0]])
            np.testing.assert_array_equal(states[slot], states[slots[0]])
        assert metrics[slots[0], METRIC.impacts_per_period] > 0  # the contact code ran
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)


def test_order_of_points_changes_no_bits():
    """40 points run in two orders, on one and two threads: every lane, refill, move to the
    first lanes at the tail and skipped group sees other neighbours, the bits stay."""
    rng = np.random.default_rng(5)
    points = [resolve_parameters("paper", gap=float(g), frequency=float(f),
                                 steps_per_period=512)
              for g, f in zip(rng.uniform(0.2e-6, 3e-6, 40), rng.uniform(110.0, 200.0, 40))]
    rows = np.array([packing.pack_parameters(p) for p in points])
    rest = np.array([packing.initial_state(p) for p in points])
    runs = []
    for threads, order in ((1, np.arange(40)), (2, rng.permutation(40)), (1, rng.permutation(40))):
        numba.set_num_threads(threads)
        states, metrics = rest[order].copy(), np.empty((40, len(METRIC)))
        _engine.run_points(rows[order], states, metrics, np.empty((40, 0, 3)))
        back = np.argsort(order)
        runs.append((metrics[back], states[back]))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    assert len(np.unique(runs[0][0][:, METRIC.periods_run])) > 5  # points end at different times
    for metrics, states in runs[1:]:
        np.testing.assert_array_equal(metrics, runs[0][0])
        np.testing.assert_array_equal(states, runs[0][1])


def test_sweep_power_whatever_the_outputs_stored():
    """A sweep's power does not depend on which other outputs it stores: every run whose
    metrics are read books every metric (a run that books fewer rounds differently)."""
    grid = {"gap": [0.5e-6, 2e-6], "frequency": [130.0, 145.0, 160.0]}

    def sweep(outputs):
        return run_sweep({"preset": "paper", "grid": grid,
                          "sweep": {"outputs": outputs, "error_estimate": "all"}},
                         progress=False)

    alone = sweep(["power"])
    every = sweep(["power", "x_max", "contact_force_max", "contact_force_spread"])
    assert (every.contact_force_max > 0).any()  # (the stop is struck)
    for name in ("power", "error_estimate", "floquet_multipliers_real", "rk4_steps"):
        np.testing.assert_array_equal(alone[name].values, every[name].values)


def test_runs_without_booking_round_alike():
    """A run that books no extrema or force peaks (Newton's perturbed copies) follows the
    same motion to rounding, with the same impacts and power, and its extrema and force
    metrics NaN rather than wrong. (Its power to int V^2 dt's quadrature, not to rounding:
    a booked run goes back to multi-steps as soon as the turn it took one apart for is
    placed, an unbooked one a multi-step's span later, so that the two sum int V^2 dt over
    different spans: lanes.resume.)"""
    points = [resolve_parameters("paper", gap=g, frequency=f, max_periods=4,
                                 settle_tolerance=1e-300)
              for g in (0.5e-6, 2e-6, 1.0) for f in (130.0, 160.0, 200.0)]
    rows = np.array([packing.pack_parameters(p) for p in points])
    ends = {}
    for book in (1.0, 0.0):
        rows[:, PARAM.book] = book
        states = np.array([packing.initial_state(p) for p in points])
        metrics = np.empty((len(points), len(METRIC)))
        _engine.run_points(rows, states, metrics, np.empty((len(points), 0, 3)), settle=False)
        ends[book] = states, metrics
    (booked, m1), (plain, m0) = ends[1.0], ends[0.0]
    scale = np.abs(booked[:, :3]).max(axis=0)
    np.testing.assert_allclose(plain[:, :3] / scale, booked[:, :3] / scale, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m0[:, METRIC.power], m1[:, METRIC.power], rtol=1e-9)
    np.testing.assert_array_equal(m0[:, METRIC.impacts_per_period],
                                  m1[:, METRIC.impacts_per_period])
    assert (m1[:, METRIC.impacts_per_period] > 0).any()
    assert np.isnan(m0[:, list(BOOKED_METRICS)]).all()
    # (a near miss only where a swing's top stays short of the stop)
    assert np.isfinite(m1[:, [c for c in BOOKED_METRICS if c != METRIC.near_miss]]).all()
    assert np.isfinite(m1[:, METRIC.near_miss]).any()
