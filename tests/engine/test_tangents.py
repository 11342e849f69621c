"""The monodromy a lane carries along its run (_engine.tangents): the derivative of the
engine's own period map, checked against the closed form clear of the stops and against
central differences of the map where the motion strikes one stop or two."""

import numba
import numpy as np
import pytest
from scipy.linalg import expm

from harvester_sweep import _engine, packing, period_map, resolve_parameters
from harvester_sweep._engine import METRIC, PARAM, STATE
from harvester_sweep.models import tip_mass

SAMPLES = 130


def _runs(row, states, tangents):
    """The engine's runs of packed ``row`` from ``states`` (n, 3): end states (n, 3),
    metric rows, and the carried monodromies (n, 3, 3) where ``tangents``."""
    numba.get_num_threads()  # (starts numba's threads, as run_independent needs)
    n = len(states)
    rows = np.repeat(row[None], n, axis=0)
    rows[:, PARAM.tangents] = tangents
    y = np.zeros((n, len(STATE)))
    y[:, :3] = states
    metrics = np.empty((n, len(METRIC)))
    derivatives = np.full((n, 3, 3), np.nan)
    _engine.run_independent(rows, y, metrics, np.empty((n, SAMPLES, 3)), np.bool_(True), 1,
                            derivatives)
    return y[:, :3], metrics, derivatives


def _central(row, state, scale, move=1e-6):
    """The period map's derivative at ``state`` by central differences of the engine's
    runs, each component moved by ``move`` times its ``scale``."""
    moved = np.repeat(state[None], 6, axis=0)
    for c in range(3):
        moved[c, c] += move * scale[c]
        moved[3 + c, c] -= move * scale[c]
    ends = _runs(row, moved, 0.0)[0]
    return ((ends[:3] - ends[3:]) / (2 * move * scale[:, None])).T


def _scaled(jacobian, scale):
    return jacobian / scale[:, None] * scale[None, :]


def test_clear_of_the_stops_it_is_the_flow_of_the_linear_system():
    """With the stop out of reach the map is RK4's of the linear system: its monodromy is
    exp(M T) to RK4's error over a period (SciPy's matrix exponential)."""
    p = resolve_parameters("paper", gap=1.0, steps_per_period=1024)
    row = packing.pack_parameters(p)
    row[PARAM.max_periods] = 1
    _, metrics, carried = _runs(row, packing.initial_state(p)[None, :3], 1.0)
    assert metrics[0, METRIC.impacts_per_period] == 0
    m, _ = tip_mass.linear_system(**p)
    exact = expm(m / p["frequency"])
    assert np.allclose(carried[0], exact, rtol=0, atol=1e-9 * np.abs(exact).max())


@pytest.mark.parametrize("case", [
    dict(),  # the paper's point: an impact a period
    dict(gap=0.5e-6, frequency=150.0),  # an orbit of two periods
    dict(gap=2e-6, frequency=120.0),
    dict(gap=1e-6, lower_gap=1e-6, frequency=145.0),  # both stops, the lane mirrored
], ids=["paper", "period 2", "far gap", "two stops"])
def test_it_is_the_period_maps_derivative_across_impacts(case):
    """Across impacts (located touches, quarter and graded steps, separations, the mirror
    to a lower stop) the carried monodromy is the map's derivative: central differences
    of the map agree with it to 1e-7 of the scales (measured 1e-9 to 2e-8; with the
    pieces' rates in theta taken by differences of the pieces, the paper point's was 2e-7
    off); and the run that carries it takes the same motion, bit for bit."""
    p = resolve_parameters("paper", **case)
    row = packing.pack_parameters(p)
    row[PARAM.max_periods] = 30
    start = _runs(row, packing.initial_state(p)[None, :3], 0.0)[0][0]
    row[PARAM.max_periods] = 2
    plain, metrics, _ = _runs(row, start[None], 0.0)
    ends, _, carried = _runs(row, start[None], 1.0)
    assert metrics[0, METRIC.impacts_per_period] > 0
    if "lower_gap" in case:
        assert metrics[0, METRIC.impacts_per_period_lower] > 0
    amplitude = max(abs(metrics[0, METRIC.x_max]), abs(metrics[0, METRIC.x_min]))
    scale = period_map.orbit_scales(row, amplitude, metrics[0, METRIC.v_peak])
    np.testing.assert_array_equal(ends, plain)
    apart = np.abs(_scaled(carried[0], scale) - _scaled(_central(row, start, scale), scale))
    assert apart.max() < 1e-7, apart


def test_a_batch_request_carries_its_monodromy():
    """period_map.Batch's "carried" request (continuation's Jacobian): each point's
    monodromy is its map's spread differences to 1e-7 of the scales (measured 1e-8), run
    in one call with other requests (its rows found among theirs); its own run is the
    plain one, bit for bit. A row that cannot carry (a stop on a spring) is refused."""
    p = resolve_parameters("paper")
    row = packing.pack_parameters(p)
    row[PARAM.max_periods] = 30
    start = _runs(row, packing.initial_state(p)[None, :3], 0.0)[0][0]
    states = np.zeros((2, len(STATE)))
    states[:, :3] = start
    states[1, 0] *= 1.001
    scale = np.repeat(period_map.orbit_scales(row, abs(start[0]), 1e-6)[None], 2, axis=0)
    batch = period_map.Batch(period_map.D, 0)
    batch.add(row, states[:1], 1)
    spread = batch.add(np.repeat(row[None], 2, axis=0), states, 1, copies="spread",
                       scale=scale)
    carried = batch.add(np.repeat(row[None], 2, axis=0), states, 1, copies="carried")
    plain, by_copies, by_tangents = batch.run()
    assert by_tangents.ok.all() and (spread, carried) == (1, 2)
    np.testing.assert_array_equal(by_tangents.ends[:1], plain.ends)
    np.testing.assert_array_equal(by_tangents.metrics[:1], plain.metrics)
    for k in range(2):
        apart = np.abs(_scaled(by_tangents.jacobian[k], scale[k])
                       - _scaled(by_copies.jacobian[k], scale[k]))
        assert apart.max() < 1e-7, (k, apart)
    moving = packing.pack_parameters(resolve_parameters("paper", stop_mass=1e-3,
                                                        stop_support_stiffness=1e4))
    with pytest.raises(ValueError, match="carried"):
        period_map.Batch(period_map.D, 0).add(moving, states[:1], 1, copies="carried")
