"""Packing: a point's engine row and rest state, packed among others as alone, and the
values the engine reads from them against their formulas (docs/model.md)."""

from __future__ import annotations

import math
import warnings

import numpy as np

from harvester_sweep import resolve_parameters
from harvester_sweep._engine import NO_STOP, PARAM, STATE
from harvester_sweep.contact import CONTACT_LAWS
from harvester_sweep.packing import pack_points

# Points that take every branch of packing: a lower stop (its own stiffness and
# restitution or the upper's), a stop on a spring, the latched law, no stop, a given
# contact damping, a preloaded stop, a point refused as too stiff.
VARIED = [{}, {"lower_gap": 2e-6}, {"lower_gap": 1e-6, "lower_hertz_stiffness": 2e9,
                                    "lower_restitution": 0.6},
          {"stop_support_stiffness": 1e4, "stop_mass": 1e-3, "stop_support_damping": 0.01},
          {"impact_velocity_mode": "latched", "contact_law": "hunt_crossley"},
          {"hertz_stiffness": 0.0}, {"contact_damping": 50.0}, {"gap": -0.5e-6},
          {"locate_switches": False}, {"max_steps_per_period": 64, "accuracy": 1e-9},
          {"contact_law": "flores", "restitution": 0.3, "frequency": 120.0}]


def _points():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (the step of a refused point)
        return [resolve_parameters("paper", **v) for v in VARIED]


def test_a_point_packed_among_others_is_packed_as_alone():
    """The rows are made column by column over all the points at once (a sweep's chunk);
    each point's row, rest state and error target are those it gets alone, to the bit,
    in either order."""
    points = _points()
    for order in (points, points[::-1]):
        packed = pack_points(order)
        for i, p in enumerate(order):
            alone = pack_points([p])
            assert packed.rows[i].tobytes() == alone.rows[0].tobytes(), VARIED[i]
            assert packed.states[i].tobytes() == alone.states[0].tobytes(), VARIED[i]
            assert packed.refused[i] == alone.refused[0]
            assert np.array_equal(packed.accuracy[i], alone.accuracy[0], equal_nan=True)


def test_the_rows_hold_the_models_coefficients():
    """The values the engine reads, each against its formula from the parameters."""
    points = _points()
    packed = pack_points(points)
    for v, p, row, state in zip(VARIED, points, packed.rows, packed.states):
        wn = 2 * math.pi * p["natural_frequency"]
        assert math.isclose(row[PARAM.wn2], wn**2, rel_tol=1e-15)
        assert math.isclose(row[PARAM.cm], 2 * p["damping_ratio"] * wn, rel_tol=1e-15)
        assert math.isclose(row[PARAM.irc], 1 / (p["resistance"] * p["capacitance"]),
                            rel_tol=1e-15)
        assert row[PARAM.period] == 1 / p["frequency"]
        kh = p["hertz_stiffness"]
        assert row[PARAM.gap] == (p["gap"] if kh > 0 else NO_STOP)
        assert math.isclose(row[PARAM.khm], kh / p["mass"], rel_tol=1e-15)
        factor = CONTACT_LAWS[p["contact_law"]](p["restitution"])
        given = p["contact_damping"]
        assert math.isclose(row[PARAM.ch], factor / p["impact_velocity"] if given is None
                            else given, rel_tol=1e-15)
        latched = given is None and p["impact_velocity_mode"] == "latched"
        assert row[PARAM.latch] == (factor if latched else 0.0)
        assert row[PARAM.locate] == (1.0 if p["locate_switches"] else 0.0)
        refused = p["steps_per_period"] > p["max_steps_per_period"]
        assert row[PARAM.max_periods] == (0 if refused else p["max_periods"]), v
        if p["lower_gap"] is None:
            assert row[PARAM.lower_gap] == NO_STOP
        else:
            lower_kh = p["lower_hertz_stiffness"] or kh
            lower_e = p["lower_restitution"] or p["restitution"]
            assert row[PARAM.lower_gap] == p["lower_gap"]
            assert math.isclose(row[PARAM.lower_khm], lower_kh / p["mass"], rel_tol=1e-15)
            assert math.isclose(row[PARAM.lower_ch], CONTACT_LAWS[p["contact_law"]](lower_e)
                                / p["impact_velocity"], rel_tol=1e-15)
        if p["stop_support_stiffness"] is None:
            assert row[PARAM.stop_ratio] == 0.0
        else:
            assert math.isclose(row[PARAM.stop_wn2],
                                p["stop_support_stiffness"] / p["stop_mass"], rel_tol=1e-15)
            assert math.isclose(row[PARAM.stop_ratio], p["mass"] / p["stop_mass"],
                                rel_tol=1e-15)
        # at rest: at 0, or where a preloaded stop's Hertz force balances the spring
        assert state[STATE.approach_velocity] == p["impact_velocity"]
        x0 = state[STATE.x]
        if p["gap"] >= 0 or kh == 0:
            assert x0 == 0.0
        else:
            k = p["mass"] * wn**2
            assert p["gap"] < x0 < 0
            assert math.isclose(k * x0 + kh * (x0 - p["gap"]) ** 1.5, 0.0,
                                abs_tol=1e-12 * k * abs(p["gap"]))
