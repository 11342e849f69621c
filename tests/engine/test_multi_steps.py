"""Multi-steps clear of the stops (lanes.resume): a lane takes PARAM.multi contact-free
steps at once, the composition of the RK4 step's map, and takes apart any multi-step a
contact, a mirror or a swing's top near the stop falls in. The motion is the single steps'
to rounding, and the metrics to int V^2 dt's quadrature over a multi-step."""

import numpy as np
import pytest

from harvester_sweep import _engine, packing
from harvester_sweep._engine import METRIC, PARAM
from harvester_sweep.parameters import resolve_parameters

STOPS = {"clear of the stop": dict(gap=1.0),
         "an impact a period": dict(gap=1e-6),
         "two stops": dict(gap=1e-6, lower_gap=1.5e-6),
         "a swing's top short of the stop": dict(gap=1.3e-6, frequency=130.0)}


def _run(p: dict, multi: float, periods: int):
    row = packing.pack_parameters(p)
    row[PARAM.max_periods], row[PARAM.multi] = periods, multi
    states = packing.initial_state(p)[None, :].copy()
    metrics = np.empty((1, len(METRIC)))
    _engine.run_points(row[None, :], states, metrics, np.empty((1, 0, 3)), settle=False)
    return states[0], metrics[0]


@pytest.mark.parametrize("stops", STOPS.values(), ids=STOPS.keys())
def test_multi_steps_follow_single_steps(stops):
    """20 periods from rest at 1024 steps a period, four steps at once against one: the
    same state to rounding (1e-11 of its scale), the same impacts of each stop, power,
    v_peak and the extrema within 1e-7 (int V^2 dt and the turns placed on the Hermite
    interpolant over four steps rather than one), the same near miss to 1e-7 of the gap."""
    p = resolve_parameters("paper", steps_per_period=1024, **{"frequency": 140.0, **stops})
    (y1, m1), (y4, m4) = _run(p, 1.0, 20), _run(p, 4.0, 20)
    scale = np.array([1e-6, 1e-2, 1e-5])
    np.testing.assert_allclose(y4[:3] / scale, y1[:3] / scale, rtol=0, atol=1e-11)
    for name in ("impacts_per_period", "impacts_per_period_lower"):
        assert m4[getattr(METRIC, name)] == m1[getattr(METRIC, name)]
    for name in ("power", "v_peak", "x_max", "x_min"):
        i = getattr(METRIC, name)
        assert m4[i] == pytest.approx(m1[i], rel=1e-7)
    if np.isfinite(m1[METRIC.near_miss]):
        assert m4[METRIC.near_miss] == pytest.approx(m1[METRIC.near_miss],
                                                    abs=1e-7 * p["gap"])
    else:
        assert np.isnan(m4[METRIC.near_miss])


def test_a_coarse_period_takes_single_steps():
    """Below MULTI_SPAN multi-steps a period a lane takes single steps, bit for bit: at 384
    steps a period four steps at once would book int V^2 dt on an interpolant over a 96th
    of the period."""
    p = resolve_parameters("paper", gap=1e-6, frequency=140.0, steps_per_period=384)
    (y1, m1), (y4, m4) = _run(p, 1.0, 10), _run(p, 4.0, 10)
    assert np.array_equal(y1, y4)
    assert np.array_equal(m1, m4, equal_nan=True)
