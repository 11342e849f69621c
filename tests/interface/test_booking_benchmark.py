"""benchmarks.booking's count of where a sweep's RK4 steps go follows the orbit solver: it
reads the solver's work by kind from every solve, and leaves the solver as it found it."""

from __future__ import annotations

import pytest

from benchmarks.booking import _shares
from harvester_sweep import results


def test_the_shares_of_a_small_sweep_add_up_and_the_solver_is_restored():
    solve = results.solve_orbits
    shares = _shares({"gap": [1e-6, 2e-6], "frequency": [140.0, 150.0]}, "all")
    assert results.solve_orbits is solve
    assert sum(shares.values()) == pytest.approx(1.0)
    # the stop is struck: Newton runs copies for the monodromy through the contact
    assert all(0.0 < share < 1.0 for share in shares.values()), shares
