"""Two stops, one on each side of the beam, against independent references: SciPy's DOP853
on the same equations with every contact onset and separation located, the model's odd
symmetry, and a lower stop out of reach."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from harvester_sweep import run_scene
from tests.helpers import beam, lankarani_nikravesh_damping

# An asymmetric pair of stops (the lower one softer, more lossy and further away) on which
# the paper scene settles on an orbit of two forcing periods, striking each stop once a
# period.
ASYMMETRIC = dict(gap=1e-6, lower_gap=1.5e-6, lower_hertz_stiffness=3e8, lower_restitution=0.6,
                  frequency=175.0)


class TwoStops:
    """m x'' + c x' + k x + F_u - F_l - theta V = m A sin(w t), C_p V' + V/R + theta x' = 0,
    F_u = k_h (x - g)^1.5 (1 + c_h x') for x > g, F_l = k_l (-g_l - x)^1.5 (1 - c_l x') for
    x < -g_l (docs/model.md), integrated in pieces between the contact switches."""

    def __init__(self, p):
        self.p = p
        self.m, self.k, self.c, self.w = beam(p)
        self.upper = (p["gap"], p["hertz_stiffness"],
                      lankarani_nikravesh_damping(p["restitution"], p["impact_velocity"]))
        self.lower = (p["lower_gap"], p["lower_hertz_stiffness"],
                      lankarani_nikravesh_damping(p["lower_restitution"], p["impact_velocity"]))
        self.onsets = {"upper": 0, "lower": 0}

    def force(self, x, v):
        """Net contact force on the tip, positive upwards [N]."""
        g, kh, ch = self.upper
        gl, kl, cl = self.lower
        if x > g:
            return -kh * (x - g) ** 1.5 * max(1 + ch * v, 0.0)
        if x < -gl:
            return kl * (-gl - x) ** 1.5 * max(1 - cl * v, 0.0)
        return 0.0

    def rhs(self, t, y):
        p = self.p
        x, v, V = y[:3]
        a = (self.m * p["amplitude"] * math.sin(self.w * t) - self.c * v - self.k * x
             + p["coupling"] * V + self.force(x, v)) / self.m
        return [v, a, -(V / p["resistance"] + p["coupling"] * v) / p["capacitance"], V * V]

    def run(self, y0, t1, samples=20001):
        """State and int V^2 dt at t1 from y0 at 0, and x sampled densely."""
        g, gl = self.upper[0], self.lower[0]
        surfaces = [lambda t, y: y[0] - g, lambda t, y: y[0] + gl]
        for s in surfaces:
            s.terminal = True
        y, t, pieces = np.concatenate([np.asarray(y0, float)[:3], [0.0]]), 0.0, []
        atol = np.array([1e-16, 1e-14, 1e-14, 1e-24])
        while t < t1:
            sol = solve_ivp(self.rhs, (t, t1), y, method="DOP853", rtol=1e-12, atol=atol,
                            events=surfaces, dense_output=True)
            pieces.append(sol)
            if sol.status == 1:
                hit = 0 if sol.t_events[0].size else 1
                t, y = sol.t_events[hit][0], sol.y_events[hit][0].copy()
                if (hit == 0 and y[1] > 0) or (hit == 1 and y[1] < 0):
                    self.onsets["upper" if hit == 0 else "lower"] += 1
                y[0] = g if hit == 0 else -gl  # exactly on the surface: no event again
                y[0] += math.copysign(1e-18, y[1])
            else:
                t, y = t1, sol.y[:, -1]
        times = np.linspace(0.0, t1, samples)
        x = np.concatenate([sol.sol(times[(times >= sol.t[0]) & (times <= sol.t[-1])])[0]
                            for sol in pieces])
        return y, x


def test_an_asymmetric_period_two_orbit_is_scipys():
    """The engine's period-2 orbit closes under SciPy's flow over two periods, and its
    metrics are SciPy's over them: extremes, impacts on each stop, power."""
    result = run_scene("paper", steps_per_period=2048, settle_tolerance=1e-12, **ASYMMETRIC)
    m, p = result.metrics, result.parameters
    assert m["status"] == "settled" and m["orbit_period"] == 2
    reference = TwoStops(p)
    T = 2 / p["frequency"]
    end, x = reference.run(result.state, T)
    scale = np.array([1e-6, 2 * math.pi * p["frequency"] * 1e-6, m["v_peak"]])
    assert np.all(np.abs(end[:3] - result.state[:3]) / scale < 1e-7)
    assert reference.onsets == {"upper": 2, "lower": 2}
    assert m["impacts_per_period"] == m["impacts_per_period_lower"] == 1.0
    assert m["x_max"] == pytest.approx(x.max(), rel=1e-6)
    assert m["x_min"] == pytest.approx(x.min(), rel=1e-6)
    assert m["power"] == pytest.approx(end[3] / T / p["resistance"], rel=1e-6)
    assert m["x_min"] < -p["lower_gap"] and m["contact_force_max_lower"] > 0


def test_symmetric_stops_give_a_symmetric_orbit():
    """Equal stops at equal distances: the model is odd, so x_min = -x_max and each stop
    is struck alike."""
    m = run_scene("paper", gap=1e-6, lower_gap=1e-6, frequency=245.0).metrics
    assert m["impacts_per_period"] == m["impacts_per_period_lower"] == 1.0
    assert m["x_min"] == pytest.approx(-m["x_max"], rel=1e-9)
    assert m["contact_force_max_lower"] == pytest.approx(m["contact_force_max"], rel=1e-9)


def test_a_lone_lower_stop_is_the_upper_stop_mirrored():
    """With the upper stop out of reach, a lower stop at 1 um gives the orbit of an upper
    stop at 1 um mirrored (x -> -x half a period later): the same power, extremes swapped."""
    upper = run_scene("paper", gap=1e-6, frequency=245.0, steps_per_period=1024).metrics
    lower = run_scene("paper", gap=1.0, lower_gap=1e-6, frequency=245.0,
                      steps_per_period=1024).metrics
    assert lower["impacts_per_period"] == 0 and lower["impacts_per_period_lower"] == 1.0
    assert lower["x_max"] == pytest.approx(-upper["x_min"], rel=1e-9)
    assert lower["x_min"] == pytest.approx(-upper["x_max"], rel=1e-9)
    assert lower["power"] == pytest.approx(upper["power"], rel=1e-9)
    assert lower["contact_force_max_lower"] == pytest.approx(upper["contact_force_max"],
                                                             rel=1e-9)


def test_a_lower_stop_out_of_reach_changes_nothing_bit_for_bit():
    one = run_scene("paper", gap=1e-6, frequency=245.0)
    two = run_scene("paper", gap=1e-6, frequency=245.0, lower_gap=1.0)
    for name, value in one.metrics.items():
        if name != "run_time":
            assert two.metrics[name] == value, name
    for name in ("displacement", "voltage", "contact_force"):
        np.testing.assert_array_equal(one.series()[name].values, two.series()[name].values)
