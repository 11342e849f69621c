"""benchmarks.booking's count of where a sweep's RK4 steps go follows the orbit solver: it
reads the solver's work by kind from every solve, and leaves the solver as it found it."""

from __future__ import annotations

import pytest

from benchmarks.booking import _shares
from harvester_sweep import results


@pytest.mark.parametrize("mode", ["fixed", "latched"])
def test_the_shares_of_a_small_sweep_add_up_and_the_solver_is_restored(mode):
    solve = results.solve_orbits
    shares = _shares({"gap": [1e-6, 2e-6], "frequency": [140.0, 150.0]}, "all",
                     {"impact_velocity_mode": mode})
    assert results.solve_orbits is solve
    assert sum(shares.values()) == pytest.approx(1.0)
    assert 0.0 < shares["Newton iterates"] < 1.0 and 0.0 < shares["motion and estimates"] < 1.0
    # the stop is struck: Newton's monodromy through the contact is carried along its runs
    # with the fixed law, taken by copies with the latched one (whose law moves with the
    # state at each touch)
    assert (shares["perturbed copies"] > 0.0) == (mode == "latched"), shares
