"""The quarter steps next to a contact switch, which the lane loop runs in vector code on
packed lanes (lanes._quarter_steps), against the kernel's scalar RK4 sub-steps."""

import math

import numpy as np
import pytest

from harvester_sweep import kernel, lanes, resolve_parameters

QUARTERS = np.full(4, 0.25)


def _points(rng):
    """LANES points in contact, each with its own parameters, state and forcing phase."""
    points = []
    for j in range(lanes.LANES):
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
    L = lanes._table()
    for j, (p, y, phase) in enumerate(points):
        lanes._load(L, j, kernel.pack_parameters(p), y, 0.0)
        L[lanes._S + j], L[lanes._C + j] = math.sin(phase), math.cos(phase)
        L[lanes._ON + j], L[lanes._FINE + j] = 1.0, 3.0
        L[lanes._NEED + j] = 1.0 if j in marked else 0.0
        L[lanes._XN + j] = L[lanes._VN + j] = L[lanes._EN + j] = np.nan
    lanes._quarter_steps(L, lanes.LANES)
    return np.array([[L[row + j] for row in (lanes._XN, lanes._VN, lanes._EN)]
                     for j in range(lanes.LANES)])


def test_quarter_steps_match_the_scalar_sub_steps():
    rng = np.random.default_rng(11)
    points = _points(rng)
    trial = _run(points, set(range(lanes.LANES)))
    for j, (p, y, phase) in enumerate(points):
        r = kernel.pack_parameters(p)
        n_steps = r[kernel.P_N]
        x, v, e, _ = kernel._rk4_pieces(
            y[0], y[1], y[2], 0.0, 1.0, QUARTERS, False, math.sin(phase), math.cos(phase),
            n_steps, r[kernel.P_T] / n_steps, r[kernel.P_A], r[kernel.P_WN2], r[kernel.P_CM],
            r[kernel.P_THM], r[kernel.P_KHM], r[kernel.P_G], r[kernel.P_CH], r[kernel.P_IRC],
            r[kernel.P_THC])
        # the same sub-steps; the forcing by rotation here, by Taylor series there
        np.testing.assert_allclose(trial[j], [x, v, e], rtol=1e-12,
                                   atol=1e-13 * np.abs([x, v, e]).max())
        assert abs(trial[j, 0] - y[0]) > 1e-6 * abs(y[0] - p["gap"])  # it moved


@pytest.mark.parametrize("marked", [{0}, {5}, {3, 9, 15}, set(range(1, 16, 2))])
def test_quarter_steps_same_bits_wherever_packed(marked):
    """A lane gets the same bits alone in a block, or packed at another place in one."""
    points = _points(np.random.default_rng(12))
    every = _run(points, set(range(lanes.LANES)))
    some = _run(points, marked)
    for j in range(lanes.LANES):
        if j in marked:
            np.testing.assert_array_equal(some[j], every[j])
        else:  # not marked: left alone
            assert np.all(np.isnan(some[j]))
