"""The quarter steps next to a contact switch, which the lane loop runs in vector code on
packed lanes (lanes.quarter_steps), against the kernel's scalar RK4 sub-steps."""

import math

import numpy as np
import pytest

from harvester_sweep import packing, resolve_parameters
from harvester_sweep._engine import LANE, LANES, PARAM, lanes, rk4
from harvester_sweep.models.tip_mass import Coefficients

QUARTERS = np.full(4, 0.25)


def _points(rng):
    """LANES points in contact, each with its own parameters, state and forcing phase."""
    points = []
    for j in range(LANES):
        p = resolve_parameters("paper", gap=float(rng.uniform(0.5e-6, 2e-6)),
                               frequency=float(rng.uniform(100.0, 200.0)),
                               resistance=float(rng.uniform(1e4, 1e6)),
                               restitution=float(rng.uniform(0.3, 0.9)),
                               steps_per_period=int(rng.choice([512, 1024])))
        y = np.array([p["gap"] + rng.uniform(1e-9, 1e-7), rng.uniform(-2e-3, 2e-3),
                      rng.uniform(-1e-5, 1e-5), p["impact_velocity"]])
        points.append((p, y, rng.uniform(0.0, 2.0 * math.pi)))
    return points


def _run(points, marked):
    """The trial rows (x, v, V) after _quarter_steps with the lanes ``marked``."""
    L = lanes.new_table()
    for j, (p, y, phase) in enumerate(points):
        lanes.load(L, j, packing.pack_parameters(p), y, 0.0)
        L[LANE.sin + j], L[LANE.cos + j] = math.sin(phase), math.cos(phase)
        L[LANE.on + j], L[LANE.fine + j] = 1.0, 3.0
        L[LANE.need + j] = 1.0 if j in marked else 0.0
        L[LANE.x_trial + j] = L[LANE.v_trial + j] = L[LANE.voltage_trial + j] = np.nan
    lanes.quarter_steps(L, LANES)
    return np.array([[L[row + j] for row in (LANE.x_trial, LANE.v_trial, LANE.voltage_trial)]
                     for j in range(LANES)])


def test_quarter_steps_match_the_scalar_sub_steps():
    rng = np.random.default_rng(11)
    points = _points(rng)
    trial = _run(points, set(range(LANES)))
    for j, (p, y, phase) in enumerate(points):
        r = packing.pack_parameters(p)
        n_steps = r[PARAM.steps]
        x, v, e, _ = rk4.pieces(
            y[0], y[1], y[2], 0.0, 1.0, QUARTERS, math.sin(phase), math.cos(phase),
            n_steps, r[PARAM.period] / n_steps, r[PARAM.amplitude],
            Coefficients(r[PARAM.wn2], r[PARAM.cm], r[PARAM.thm], r[PARAM.khm], r[PARAM.gap],
                         r[PARAM.ch], r[PARAM.irc], r[PARAM.thc]))
        # the same sub-steps; the forcing by rotation here, by Taylor series there
        np.testing.assert_allclose(trial[j], [x, v, e], rtol=1e-12,
                                   atol=1e-13 * np.abs([x, v, e]).max())
        assert abs(trial[j, 0] - y[0]) > 1e-6 * abs(y[0] - p["gap"])  # it moved


@pytest.mark.parametrize("marked", [{0}, {5}, {3, 9, 15}, set(range(1, 16, 2))])
def test_quarter_steps_same_bits_wherever_packed(marked):
    """A lane gets the same bits alone in a block, or packed at another place in one."""
    points = _points(np.random.default_rng(12))
    every = _run(points, set(range(LANES)))
    some = _run(points, marked)
    for j in range(LANES):
        if j in marked:
            np.testing.assert_array_equal(some[j], every[j])
        else:  # not marked: left alone
            assert np.all(np.isnan(some[j]))
