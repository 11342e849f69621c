"""The periodic-orbit solver against independent references: the closed-form linear
response and its RK4 amplification, transient integration of the same RK4 to a tight
settle tolerance (hysteresis included), and the accuracy target on points that the
automatic step used to miss."""

import math

import numba
import numpy as np
import pytest

from benchmarks.cases import GRID
from harvester_sweep import (
    _engine,
    acceptance,
    orbits,
    packing,
    period_map,
    resolve_parameters,
    run_scene,
)
from harvester_sweep._engine import METRIC, PARAM, STATUS
from harvester_sweep.orbits import solve_orbits
from tests.helpers import phasor


def _system_matrix(p):
    """d(x, v, V)/dt = A (x, v, V) + forcing, from the model's equations (docs/model.md)."""
    m, wn = p["mass"], 2 * math.pi * p["natural_frequency"]
    c, theta, cp, r = 2 * p["damping_ratio"] * m * wn, p["coupling"], p["capacitance"], \
        p["resistance"]
    return np.array([[0.0, 1.0, 0.0],
                     [-wn * wn, -c / m, theta / m],
                     [0.0, -theta / cp, -1.0 / (r * cp)]])


@pytest.mark.parametrize("steps", [256, 512])
def test_linear_orbit_is_the_phasor_and_its_multipliers_are_closed_form(steps):
    """Out of the stop's reach the orbit is the closed-form phasor, to RK4's own error at
    the step (it shrinks 16-fold when the step halves), and the multipliers are the RK4
    amplification R(h lambda)^N of the system's eigenvalues, close to exp(lambda T)."""
    result = run_scene("paper", gap=1.0, frequency=140.0, steps_per_period=steps)
    p, m = result.parameters, result.metrics
    X, V = phasor(**p)
    w = 2 * math.pi * p["frequency"]
    exact = np.array([X.imag, w * X.real, V.imag])  # x = Im(X e^{jwt}) at t = 0
    scale = np.array([abs(X), w * abs(X), abs(V)])
    error = np.max(np.abs(result.state[:3] - exact) / scale)
    assert m["status"] == "settled" and m["orbit_period"] == 1
    assert error <= 3 * m["error_estimate"]  # (the estimate is of this error, within O(1))
    rk4_error = (2 * math.pi * p["natural_frequency"] / (p["frequency"] * steps)) ** 4
    assert 0.002 * rk4_error < error < rk4_error

    lam = np.linalg.eigvals(_system_matrix(p))
    z = lam / (p["frequency"] * steps)
    rk4 = (1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24) ** steps
    engine = np.array(m["floquet_multipliers_real"]) + 1j * np.array(m["floquet_multipliers_imag"])
    # (out of reach the monodromy is the RK4 step's own matrix to the power N: rounding
    # only, relative to the largest multiplier)
    for reference, rtol in ((rk4, 1e-11), (np.exp(lam / p["frequency"]), 5 * rk4_error)):
        for mu in reference:
            assert np.min(np.abs(engine - mu)) <= rtol * np.max(np.abs(reference))
    assert m["spectral_radius"] == pytest.approx(np.max(np.abs(rk4)), rel=1e-11)


def _run_periods(rows, states, periods):
    """The engine's metric rows of ``periods`` periods of each point, no steady-state test
    (``states`` end where the runs ended)."""
    rows = rows.copy()
    rows[:, PARAM.max_periods] = periods
    metrics = np.empty((len(rows), len(METRIC)))
    _engine.run_points(rows, states, metrics, np.empty((len(rows), orbits.SAMPLES, 3)),
                       settle=False)
    return metrics


def test_the_closed_form_monodromy_is_the_engines_rk4_period_map():
    """Clear of the stop the solver takes the monodromy in closed form, the contact-free
    RK4 step's matrix to the power N p (period_map.contact_free_monodromy); the engine's lanes, run
    from copies of a state moved along each component, give the same matrix (the map is
    affine there: the forward differences are exact to rounding)."""
    points = [resolve_parameters("paper", gap=1.0, frequency=f, resistance=r,
                                 steps_per_period=s)
              for f, r, s in ((140.0, 1e5, 256), (190.0, 1e9, 512), (120.0, 1e3, 320))]
    packed = packing.pack_points(points)
    periods = np.array([1, 2, 3])
    scale = np.array([[1e-6, 1e-3, 1.0]] * len(points))
    states = period_map.perturbed_copies(packed.states, scale)
    metrics = _run_periods(np.repeat(packed.rows, 4, axis=0), states, np.repeat(periods, 4))
    lanes = period_map.monodromy(states.reshape(len(points), 4, -1), scale)
    closed = period_map.contact_free_monodromy(packed.rows, packed.rows[:, PARAM.steps], periods)
    assert np.all(metrics[:, METRIC.impacts_per_period] == 0)
    # (relative to each column's scale: the differences' rounding, 1e-16 / 1e-6)
    error = np.abs(lanes - closed) * scale[:, None, :] / scale[:, :, None]
    assert np.max(error) < 1e-8
    assert not np.allclose(closed, np.eye(3))  # (a map that moves)


def test_spread_differences_step_over_a_jump_of_the_map():
    """The RK4 map with located switches jumps by about its own error where a switch
    crosses a step's end (docs/numerics.md). On a map with a known Jacobian, smooth but
    for a jump of 1e-6 of the scale just past the central copy along x, the spread copies'
    median slope gives the Jacobian to the order of the curvature (0.01 x 2e-7), where
    central differences, whose copy straddles the jump, are 5 off."""
    rng = np.random.default_rng(7)
    a = rng.normal(size=(3, 3))
    scale = np.array([[1e-6, 1e-3, 1.0]])
    y0 = np.array([[2e-7, -3e-4, 0.4, 0.0, 0.0, 0.0]])
    z0 = y0[0, :3] / scale[0]
    exact = a.copy()
    exact[:, 0] += 0.02 * z0[0]  # (the derivative of 0.01 x^2)

    def error(spread):
        """The monodromy's largest error, in scaled components."""
        states = period_map.perturbed_copies(y0, scale, "spread" if spread else "central")
        z = states[:, :3] / scale
        jump = (z[:, 0] > z0[0] + 0.5 * period_map.CENTRAL) * 1e-6
        states[:, :3] = (z @ a.T + 0.01 * z[:, :1] ** 2 + jump[:, None]) * scale
        m = period_map.monodromy(states.reshape(1, -1, len(y0[0])), scale)[0]
        return np.max(np.abs(m * scale[0][None, :] / scale[0][:, None] - exact))

    assert error(spread=True) < 1e-8
    assert error(spread=False) > 1


def test_the_spectral_radius_is_the_rate_at_which_the_motion_returns():
    """The power method on the engine's own period map: from 1e-6 of a period-4 orbit of
    issue 19's grid (gap 2.70 um, 138.1 Hz, 1024 steps per period), the motion's change
    from one map to the next shrinks by the largest multiplier's modulus, 0.865362 from
    maps 10 to 30. The orbit's monodromy by central differences says the same to 4e-7;
    forward differences, which near grazing see the map bend, said 0.8628."""
    p = resolve_parameters("paper", gap=2.6984126984126986e-06, frequency=138.0952380952381,
                           steps_per_period=1024)
    packed = packing.pack_points([p])
    result = solve_orbits(packed.rows, packed.states)
    m = result.metrics[0]
    assert m[METRIC.status] == STATUS.settled and m[METRIC.orbit_period] == 4
    scale = period_map.orbit_scales(packed.rows, m[None, METRIC.x_max], m[None, METRIC.v_peak])
    states = result.finals.copy()
    states[0, :3] += 1e-6 * scale[0]
    ends = [states[0, :3].copy()]
    for _ in range(31):
        _run_periods(packed.rows, states, 4)
        ends.append(states[0, :3].copy())
    steps = np.max(np.abs(np.diff(ends, axis=0)) / scale, axis=1)
    rate = (steps[30] / steps[10]) ** (1 / 20)
    assert abs(np.abs(result.multipliers[0, 0]) - rate) < 1e-5


def test_the_guess_of_a_first_period_in_contact_is_the_engines():
    """Whether the first period from rest reaches the stop (which decides how Newton's
    first run is taken) is guessed from the motion without the stop at 64 steps a period;
    the engine's own first period at 1024 steps agrees, except within 1 % of grazing."""
    points = [resolve_parameters("paper", gap=g, frequency=f, steps_per_period=1024)
              for g in np.linspace(0.0, 10e-6, 16) for f in np.linspace(100.0, 300.0, 16)]
    packed = packing.pack_points(points)
    extent = np.empty((len(points), 2))
    _engine.free_extent(packed.rows, packed.states, orbits.GUESS_STEPS, extent)
    metrics = _run_periods(packed.rows, packed.states.copy(), 1)
    gap = packed.rows[:, PARAM.gap]
    touched = (metrics[:, METRIC.impacts_per_period] > 0) | (metrics[:, METRIC.x_max] >= gap)
    grazing = np.abs(metrics[:, METRIC.x_max] - gap) <= 0.01 * gap
    assert 20 < touched.sum() < len(points) - 20
    assert np.all(((extent[:, 0] >= gap) == touched) | grazing)
    # (and the lowest x is the engine's, to the coarse step's error, where it stayed clear)
    clear = ~touched
    assert np.allclose(extent[clear, 1], metrics[clear, METRIC.x_min],
                       rtol=0.02, atol=0.02 * np.abs(metrics[clear, METRIC.x_min]).max())


@pytest.mark.parametrize("overrides", [
    {"damping_ratio": 0.002, "frequency": 150.0},  # a lightly damped resonance
    {"resistance": 1e9},  # 1 GOhm: the load circuit decays over ~1e5 periods
])
def test_accuracy_met_where_the_automatic_step_missed_it(overrides):
    """At the default accuracy (1e-7) the automatic step gave these points 64 steps a
    period and an error near 6e-5; the solver now re-solves them at the step the estimate
    asks for: the estimate meets the target and so does the error against the phasor.
    And no transient is integrated: one period of the motion, where a transient took
    1836 (the resonance) and 98,626 (1 GOhm) periods."""
    result = run_scene("paper", gap=1.0, **overrides)
    p, m = result.parameters, result.metrics
    assert p["steps_per_period"] == 64 < m["steps_per_period"]  # (was refined)
    X, V = phasor(**p)
    assert m["error_estimate"] <= p["accuracy"]
    assert m["power"] == pytest.approx(abs(V) ** 2 / (2 * p["resistance"]),
                                       rel=2 * p["accuracy"])
    assert m["x_max"] == pytest.approx(abs(X), rel=2 * p["accuracy"])
    assert m["periods_run"] == 1


@pytest.mark.parametrize("point", [
    dict(gap=3.6875e-06, frequency=143.67088607594937, resistance=215443.46900318822,
         restitution=0.5551020408163265),
    dict(gap=2.5e-07, frequency=128.48101265822785, resistance=21544.346900318822,
         restitution=0.7479591836734694),
])
def test_accuracy_met_where_the_map_jumps_near_newtons_floor(point):
    """Two points of examples/million_points.toml (automatic step) whose period map jumps
    at about 1e-8 of the scales, where Newton's iterates stall. The first's re-solve at a
    finer step ran four estimate runs, each halving the distance to the finer orbit, gave
    up, and the point kept the coarser solve's estimate (1.1e-6; error 4.4e-7); the
    second's re-solve stalled 1.9e-8 from its orbit and the point kept the coarser orbit
    (error 5.7e-7). Against the same RK4 at 16384 steps a period the errors are now 7.3e-8
    and 9.6e-8, and the estimates (6.1e-8, 9.2e-8) meet the target."""
    result = run_scene("paper", **point)
    fine = run_scene("paper", steps_per_period=16384, **point)
    m, f = result.metrics, fine.metrics
    assert m["status"] == f["status"] == "settled" and m["orbit_period"] == f["orbit_period"]
    assert m["error_estimate"] <= result.parameters["accuracy"]
    amplitude = max(abs(f["x_max"]), abs(f["x_min"]))
    error = max(abs(m["power"] / f["power"] - 1), abs(m["v_peak"] / f["v_peak"] - 1),
                abs(m["x_max"] - f["x_max"]) / amplitude,
                abs(m["x_min"] - f["x_min"]) / amplitude)
    assert error <= 2 * result.parameters["accuracy"]  # (the estimate is of it, to O(1))


def test_a_re_solve_finds_the_orbit_and_multipliers_of_its_step():
    """A point with contact whose automatic step missed the accuracy target is re-solved at
    a finer step from the orbit its estimate located, its copies run both ways at once:
    its orbit and Floquet multipliers are those a solve from rest finds with that step
    given (Newton's floor, and central differences taken within 1e-7 of the orbit)."""
    result = run_scene("strong_coupling", frequency=140.0, gap=0.5e-6)
    m = result.metrics
    assert result.parameters["steps_per_period"] < m["steps_per_period"]  # (was re-solved)
    assert m["impacts_per_period"] > 0
    given = run_scene("strong_coupling", frequency=140.0, gap=0.5e-6,
                      steps_per_period=m["steps_per_period"]).metrics
    assert m["orbit_period"] == given["orbit_period"]
    for name in ("power", "v_peak", "x_max"):
        assert m[name] == pytest.approx(given[name], rel=1e-9)
    assert np.allclose(m["floquet_multipliers_real"], given["floquet_multipliers_real"],
                       rtol=0, atol=1e-6)
    assert np.allclose(m["floquet_multipliers_imag"], given["floquet_multipliers_imag"],
                       rtol=0, atol=1e-6)


def _grid(direction=None, n=24):
    gaps, freqs = np.linspace(0.25e-6, 4e-6, n), np.linspace(150.0, 300.0, n)
    freqs = freqs[::-1] if direction == "down" else freqs
    points = [resolve_parameters("paper", gap=float(g), frequency=float(f),
                                 steps_per_period=512, settle_tolerance=1e-12)
              for g in gaps for f in freqs]
    successors = None
    if direction:
        successors = np.arange(1, n * n + 1).reshape(n, n)
        successors[:, -1] = -1
        successors = successors.ravel()
    return packing.pack_points(points), successors


def test_groups_of_lines_change_no_bits_and_report_every_point():
    """A solve deals its lines out to groups, one a thread, each solved in a thread of its
    own: lines of different lengths (frequency continuations up and down, points alone)
    give the same bits on one thread and two, with progress told or not; the progress
    told adds up to the points; an error told by the progress stops the solve."""
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one numba thread: a solve makes one group")
    packed, successors = _grid("up", n=6)
    down, down_successors = _grid("down", n=6)
    alone = packing.pack_points([resolve_parameters("paper", gap=g, frequency=f,
                                                    steps_per_period=512)
                                 for g, f in ((0.4e-6, 160.0), (1e-6, 240.0), (3e-6, 200.0))])
    cut = down_successors.copy()
    cut[5], cut[[8, 20]] = 6, -1  # lines of 3, 6 and 9 points
    rows = np.concatenate([packed.rows, down.rows, alone.rows])
    states = np.concatenate([packed.states, down.states, alone.states])
    successors = np.concatenate([successors, np.where(cut >= 0, cut + 36, -1), [-1] * 3])
    estimated = np.arange(len(rows)) % 3 == 0
    default = numba.get_num_threads()
    runs, reports = [], []
    try:
        for threads, on_points in ((1, None), (2, reports.append), (2, None)):
            numba.set_num_threads(threads)
            runs.append(solve_orbits(rows, states, successors, estimated,
                                     on_points=on_points))

        class Stop(Exception):
            pass

        def stop(count):
            raise Stop

        with pytest.raises(Stop):
            solve_orbits(rows, states, successors, estimated, on_points=stop)
    finally:
        numba.set_num_threads(default)
    assert sum(reports) == len(rows)
    assert (runs[0].metrics[:, METRIC.status] == STATUS.settled).sum() > 60
    for run in runs[1:]:
        for name in ("metrics", "finals", "multipliers", "errors", "steps", "rk4_steps"):
            np.testing.assert_array_equal(getattr(run, name), getattr(runs[0], name), name)


def _transient(rows, states):
    metrics = np.empty((len(rows), len(METRIC)))
    _engine.run_points(rows, states.copy(), metrics, np.empty((len(rows), 0, 3)))
    return metrics


@pytest.mark.parametrize("direction", [None, "up", "down"])
def test_same_attractors_as_the_transient(direction):
    """A 24 x 24 gap x frequency grid from rest, and continued up and down in frequency:
    each point's orbit is the attractor that transient integration of the same RK4 reaches
    from the same state (rest, or the orbit the point before settled on), to a settle
    tolerance of 1e-12: same status and orbit period, metrics within 1e-7."""
    packed, successors = _grid(direction)
    orbits = solve_orbits(packed.rows, packed.states, successors)
    starts = packed.states.copy()
    if direction:  # each from the state its predecessor left
        follows = successors >= 0
        starts[successors[follows]] = orbits.finals[follows]
    reference = _transient(packed.rows, starts)
    new = orbits.metrics
    settled = reference[:, METRIC.status] == STATUS.settled
    assert settled.sum() >= 560
    np.testing.assert_array_equal(new[settled, METRIC.status], STATUS.settled)
    np.testing.assert_array_equal(new[settled, METRIC.orbit_period],
                                  reference[settled, METRIC.orbit_period])
    amplitude = 0.5 * (reference[:, METRIC.x_max] - reference[:, METRIC.x_min])
    for name, scale in (("power", np.abs(reference[:, METRIC.power])),
                        ("v_peak", reference[:, METRIC.v_peak]), ("x_max", amplitude),
                        ("x_min", amplitude), ("impacts_per_period", 1.0)):
        column = getattr(METRIC, name)
        difference = np.abs(new[settled, column] - reference[settled, column])
        assert np.all(difference <= 1e-7 * np.broadcast_to(scale, settled.shape)[settled]), name
    # the points the transient could not settle within its budget: chaos here, or an orbit
    # with multipliers near 1; the solver does not force a chaotic motion onto an orbit
    unsettled = ~settled
    radius = np.abs(orbits.multipliers[unsettled, 0])
    taken = new[unsettled, METRIC.status] == STATUS.settled
    assert np.all(radius[taken] > 0.98)
    # the solver integrates a small part of the periods the transient did
    assert new[:, METRIC.periods_run].sum() < 0.2 * reference[:, METRIC.periods_run].sum()


def test_a_slowly_contracting_orbit_is_the_attractor_the_motion_reaches():
    """Near a period doubling of the paper scene (gap 2.7 um, 144.4 Hz; spectral radius
    0.996) the motion from rest needs about 10,000 periods to settle to 1e-12. The solver
    takes an orbit after a small part of them, in the linear regime of the orbit it
    converged on, and it is the orbit the transient reaches: same period, same power."""
    p = resolve_parameters("paper", gap=10e-6 * 17 / 63, frequency=100.0 + 200.0 * 14 / 63,
                           steps_per_period=1024, settle_tolerance=1e-12, max_periods=40_000)
    packed = packing.pack_points([p])
    orbits = solve_orbits(packed.rows, packed.states)
    reference = _transient(packed.rows, packed.states)[0]
    new = orbits.metrics[0]
    assert reference[METRIC.status] == STATUS.settled
    assert reference[METRIC.periods_run] > 5000
    assert np.abs(orbits.multipliers[0, 0]) > 0.99
    assert new[METRIC.status] == STATUS.settled
    assert new[METRIC.orbit_period] == reference[METRIC.orbit_period]
    assert new[METRIC.power] == pytest.approx(reference[METRIC.power], rel=1e-8)
    assert new[METRIC.periods_run] < 0.1 * reference[METRIC.periods_run]


def test_a_stable_orbit_the_motion_only_passes_is_not_taken():
    """At gap 0.25 um, 103.8 Hz, 21.5 kOhm, restitution 0.886 (a point of
    examples/million_points.toml, automatic step) a stable period-2 orbit (spectral radius
    0.49) lies within NEAR of the motion from rest after 90 periods, but the motion does
    not settle on it: the transient, run for 5000 periods, never settles. The attempt's
    monodromy at the motion's state expands (EXPANDING), so the orbit is not taken, and
    the point is reported not settled, as the transient says."""
    _not_settled_as_the_transient(gap=0.25e-6, frequency=103.79746835443038,
                                  resistance=21544.346900318822,
                                  restitution=0.8857142857142857)


def test_a_stable_orbit_that_nearly_grazes_is_not_taken_from_beyond_its_margin():
    """At gap 0.25 um, 103.8 Hz, 100 kOhm, restitution 0.886 (a point of
    examples/million_points.toml, automatic step) a stable period-2 orbit (spectral radius
    0.49) has a swing whose top stays 0.006 of the amplitude short of the stop. The motion
    from rest passes it again and again, never nearer than 0.012 (the transient, run for
    40,000 periods, does not settle): within NEAR, its next periods as the monodromy
    predicts, yet beyond that near miss, where the period map is not the orbit's. It was
    taken after 182 periods; the motion must now come within the margin (acceptance.reach),
    and the point is reported not settled, as the transient says."""
    _not_settled_as_the_transient(gap=0.25e-6, frequency=103.79746835443038,
                                  resistance=1e5, restitution=0.8857142857142857)


def test_an_orbit_reached_along_a_multiplier_near_minus_one_is_taken():
    """At gap 2.28 um, 141.8 Hz, 1 kOhm, restitution 0.904 (a point of
    examples/million_points.toml, automatic step) the motion nears a period-2 orbit with
    the multiplier -0.9999 and the near miss 0.045 of its amplitude: it is turned away at
    first, from 0.061 of it, and the motion's samples then repeat after 4 periods better
    than after 2. The solver tries period 2 again and takes the orbit within the budget of
    1000 periods; the motion from rest, run at the orbit's step, comes nearer it in each
    of three runs of 2000 periods."""
    point = dict(gap=2.28125e-06, frequency=141.77215189873417, resistance=1000.0,
                 restitution=0.9040816326530612)
    packed = packing.pack_points([resolve_parameters("paper", **point)])
    solved = solve_orbits(packed.rows, packed.states)
    m = solved.metrics[0]
    assert m[METRIC.status] == STATUS.settled and m[METRIC.orbit_period] == 2
    assert solved.multipliers[0, 0].real == pytest.approx(-0.9999, abs=1e-4)
    rows = packed.rows.copy()
    rows[:, PARAM.steps], rows[:, PARAM.max_periods], rows[:, PARAM.tolerance] = (
        solved.steps[0], 2000, 0.0)
    scale = period_map.orbit_scales(packed.rows[0], m[METRIC.x_max], m[METRIC.v_peak])
    state, distances = packed.states.copy(), []
    for _ in range(3):
        _engine.run_points(rows, state, np.empty((1, len(METRIC))), np.empty((1, 0, 3)))
        distances.append(np.max(np.abs(state[0, :3] - solved.finals[0, :3]) / scale))
    assert distances[2] < distances[1] < distances[0] < acceptance.NEAR, distances


def test_reach_is_the_margin_from_grazing():
    """acceptance.reach: NEAR for an orbit far from grazing or without a stop, else the near
    miss relative to the x scale, or the overshoot 0.5 (v_imp / (w x))^2 of the slowest
    impact, whichever is smaller."""
    m = np.full((4, len(METRIC)), np.nan)
    m[1, METRIC.near_miss] = 0.003
    m[2, METRIC.approach_velocity_min] = 0.1
    m[3, [METRIC.near_miss, METRIC.approach_velocity_min]] = 0.5, 2.0
    scale = np.array([[1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 2.0, 1.0]])
    np.testing.assert_allclose([acceptance.reach(m[k], scale[k]) for k in range(4)],
                               [acceptance.NEAR, 0.003, 0.5 * 0.05 ** 2, acceptance.NEAR])


def _not_settled_as_the_transient(**point):
    """The paper scene at ``point`` (a budget of 1000 periods) is not settled: neither in
    the transient run for 5000 periods, nor by the solver, which gives no multipliers."""
    packed = packing.pack_points([resolve_parameters("paper", max_periods=1000, **point)])
    rows = packed.rows.copy()
    rows[:, PARAM.max_periods] = 5000
    reference = _transient(rows, packed.states)[0]
    orbits = solve_orbits(packed.rows, packed.states)
    assert reference[METRIC.status] == STATUS.not_settled
    assert orbits.metrics[0, METRIC.status] == STATUS.not_settled
    assert np.isnan(orbits.multipliers[0]).all()


def test_an_orbit_forward_differences_called_stable_is_not_taken():
    """At gap 3.53 um, 139.9 Hz, 464 kOhm, restitution 0.53 (a point of
    examples/million_points.toml, automatic step) the motion comes within 6e-5 of a
    period-12 orbit after 856 periods, and the orbit's monodromy predicts its next period to
    9 % of the distance. Forward differences gave it the multiplier -0.9963: stable. It is
    not: central differences give -1.0036 at every step from 1e-5 to 1e-9 of the scales,
    and the motion started on it leaves it at that rate; the motion settles, after about
    1500 periods, on a period-24 orbit around it (2.5e-5 from it), which repeats to the
    last bit and is beyond the 16 periods the engine looks for. The transient, run for
    5000 periods, does not settle, and the point is reported not settled."""
    _not_settled_as_the_transient(gap=3.53125e-06, frequency=139.873417721519,
                                  resistance=464158.8833612772,
                                  restitution=0.5275510204081633)


def _on_its_way(m, e0, e1, maps=1):
    """acceptance.on_its_way for one motion at ``e0`` and, ``maps`` maps later, ``e1`` from a
    fixed point of monodromy ``m`` (unit scales, Newton's floor 1e-12)."""
    fixed = np.array([1.0, -2.0, 0.5])
    return bool(acceptance.on_its_way(fixed + e0, fixed + e1, maps, fixed, m, np.ones(3), 1e-12))


def test_on_its_way_follows_the_monodromys_prediction():
    """On an exactly linear period map y -> y* + M (y - y*) with M non-normal (spectral
    radius 0.9, but |M^k e| grows about 4-fold before it decays): a motion that moves away
    at first and whose prediction stays within NEAR is on its way; one whose prediction
    leaves NEAR, one that does not follow the prediction, and one beyond NEAR are not."""
    m = np.array([[0.9, 1.0, 0.0], [0.0, 0.9, 0.0], [0.0, 0.0, 0.3]])

    def judge(e0, maps=1, moved=np.zeros(3)):
        return _on_its_way(m, e0, np.linalg.matrix_power(m, maps) @ e0 + moved, maps)

    small = np.array([0.01, 0.02, 0.0])  # |M^k e| peaks near 0.081 (k = 9)
    assert np.linalg.norm(m @ small, np.inf) > 1.4 * np.linalg.norm(small, np.inf)
    assert judge(small) and judge(small, maps=2)
    assert not judge(2 * small)  # its prediction peaks near 0.16, beyond NEAR
    assert not judge(small, moved=np.array([0.0, 0.0, 0.005]))  # not the linear regime
    assert not judge(np.array([0.0, 0.0, 2 * acceptance.NEAR]))  # contracting, but beyond NEAR
    assert judge(np.array([0.0, 1e-13, 0.0]), moved=np.array([0.5, 0.0, 0.0]))  # on it


def test_hysteresis_up_and_down():
    """Swept up and down, some points of the grid settle on different orbits: the stop's
    hysteresis is kept (each point's orbit against the transient from the same state is
    test_same_attractors_as_the_transient's)."""
    powers = {}
    for direction in ("up", "down"):
        packed, successors = _grid(direction, n=12)
        orbits = solve_orbits(packed.rows, packed.states, successors)
        power = orbits.metrics[:, METRIC.power].reshape(12, 12)
        powers[direction] = power if direction == "up" else power[:, ::-1]
    differ = np.abs(powers["up"] - powers["down"]) > 1e-3 * np.abs(powers["down"])
    assert differ.sum() >= 3


def test_unstable_fixed_points_are_not_taken_and_chaos_stays_unsettled():
    """A point whose motion does not settle (here a tiny gap at low frequency, where the
    transient does not settle within 1000 periods) is reported not settled with NaN
    multipliers, never forced onto a fixed point."""
    p = resolve_parameters("paper", gap=0.25e-6, frequency=150.0, steps_per_period=512,
                           max_periods=1000)
    packed = packing.pack_points([p])
    reference = _transient(packed.rows, packed.states)
    orbits = solve_orbits(packed.rows, packed.states)
    assert reference[0, METRIC.status] == STATUS.not_settled
    assert orbits.metrics[0, METRIC.status] == STATUS.not_settled
    assert orbits.metrics[0, METRIC.periods_run] == packed.rows[0, PARAM.max_periods]
    assert np.isnan(orbits.multipliers[0]).all()


@pytest.mark.parametrize("gap_index, frequency_index", [(36, 3), (50, 4), (53, 9)])
def test_a_motion_that_does_not_settle_reports_its_last_periods(gap_index, frequency_index):
    """Points of the benchmark grid (benchmarks/cases.py) whose motion does not settle in
    its 1000 periods: the solver's metrics are those of the transient run from rest to the
    budget, over its last 16 periods (the run ends on the same state bit for bit), whatever
    attempts the solver made on the way. They were over the last piece of trajectory the
    solver ran, as short as 3 periods: their power moved by up to 0.12 of itself when the
    attempts' timing changed."""
    gap = np.linspace(**GRID["gap"])[gap_index]
    frequency = np.linspace(**GRID["frequency"])[frequency_index]
    packed = packing.pack_points([resolve_parameters("paper", gap=gap, frequency=frequency,
                                                     steps_per_period=1024)])
    reference = _transient(packed.rows, packed.states)[0]
    orbits = solve_orbits(packed.rows, packed.states)
    assert reference[METRIC.status] == orbits.metrics[0, METRIC.status] == STATUS.not_settled
    np.testing.assert_array_equal(orbits.metrics[0, :METRIC.orbit_period],
                                  reference[:METRIC.orbit_period])


def test_attempts_end_at_an_orbit_they_could_not_take():
    """Gap 2.54 um, 112.7 Hz: the motion never settles (the transient engine's own test at
    the same budget says so), and its contact comes and goes. From a first run without
    contact, Newton's iterates go through the contact-free map's fixed point to an orbit
    with contact beyond NEAR of the motion, which could not be taken: they end once near
    it (orbits.SETTLING), not converge to it at every attempt."""
    p = resolve_parameters("paper", gap=2.53968253968254e-06, frequency=112.6984126984127,
                           steps_per_period=1024)
    packed = packing.pack_points([p])
    reference = _transient(packed.rows, packed.states)
    assert reference[0, METRIC.status] == STATUS.not_settled
    rounds = {}
    for settling in (orbits.SETTLING, -1.0):  # (-1: every attempt converges)
        solved = solve_orbits(packed.rows, packed.states, settling=settling)
        assert solved.metrics[0, METRIC.status] == STATUS.not_settled
        assert solved.metrics[0, METRIC.periods_run] == packed.rows[0, PARAM.max_periods]
        rounds[settling] = solved.rounds[0]
    assert rounds[orbits.SETTLING] <= rounds[-1.0] - 8
