"""benchmarks.booking's count of where a sweep's RK4 steps go follows the orbit solver: it
counts at period_map's engine call, and leaves the engine as it found it."""

from __future__ import annotations

import pytest

from benchmarks.booking import _shares
from harvester_sweep import _engine, orbits


def test_the_shares_of_a_small_sweep_add_up_and_the_engine_is_restored():
    run, solve_round = _engine.run_points, orbits._Points.round
    shares = _shares({"gap": [1e-6, 2e-6], "frequency": [140.0, 150.0]}, "all")
    assert _engine.run_points is run and orbits._Points.round is solve_round
    assert sum(shares.values()) == pytest.approx(1.0)
    # the stop is struck: Newton runs copies for the monodromy through the contact
    assert all(0.0 < share < 1.0 for share in shares.values()), shares
