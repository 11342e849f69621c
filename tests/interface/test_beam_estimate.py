"""The beam sweep's run-time estimate (run_estimate.beam_estimate): what it extrapolates
is the sample's own work, a long run is refused before any work and runs with --yes, a
small grid says its size alone, and the sample changes no result. No assertion is on a
measured time: the extrapolation is checked on a clock that the fake solver moves."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from harvester_sweep import run_estimate
from harvester_sweep.beam_cluster import run_beam_file
from harvester_sweep.beam_runs import beam_sweep
from harvester_sweep.cli import main
from harvester_sweep.sweep_file import load_sweep

#: Seconds the fake solver's clock moves per period a point runs [s].
PER_PERIOD = 1e-3


def _grid(directions=None, gaps=40, frequencies=30, **parameters) -> dict:
    sweep = {"model": "beam", "preset": "bimorph_tip",
             "parameters": {"n_modes": 1, **parameters},
             "grid": {"gap": {"start": 1e-6, "stop": 3e-6, "num": gaps},
                      "frequency": {"start": 120.0, "stop": 160.0, "num": frequencies}}}
    if directions:
        sweep["sweep"] = {"directions": directions}
    return sweep


def _fake(monkeypatch, periods_of):
    """A solver that runs no point: each point runs periods_of(point, continued) periods
    (at most its budget), and the estimate's clock moves PER_PERIOD a period."""
    clock = SimpleNamespace(now=0.0)
    monkeypatch.setattr(run_estimate, "time", SimpleNamespace(perf_counter=lambda: clock.now))

    def solve(points, starts):
        periods = np.array([min(periods_of(p, starts is not None), p["max_periods"])
                            for p in points], dtype=float)
        clock.now += PER_PERIOD * periods.sum()
        return periods, [np.zeros(2)] * len(points)

    return solve


def test_a_grid_of_like_points_is_its_points_times_a_points_time(monkeypatch):
    # Every point from rest runs 50 periods: the grid takes its points times 50 periods.
    spec = load_sweep(_grid(), model="beam")
    assert spec.n_points >= run_estimate.BEAM_SAMPLED_GRID
    work = run_estimate.beam_estimate(spec, spec.n_points, 1, _fake(monkeypatch,
                                                                    lambda p, c: 50))
    assert work.seconds == pytest.approx(spec.n_points * 50 * PER_PERIOD, rel=1e-12)
    # a resumed run: only what is left
    work = run_estimate.beam_estimate(spec, 100, 1, _fake(monkeypatch, lambda p, c: 50))
    assert work.seconds == pytest.approx(100 * 50 * PER_PERIOD, rel=1e-12)


def test_a_swept_line_costs_its_first_point_from_rest_and_the_rest_from_their_neighbour(
        monkeypatch):
    # From rest 80 periods, from the last frequency's orbit 10: a line of L points takes
    # 80 + 10 (L - 1) periods, whatever the sample's runs of SEGMENT points.
    spec = load_sweep(_grid(["up", "down"], gaps=16, frequencies=40), model="beam")
    assert spec.n_points >= run_estimate.BEAM_SAMPLED_GRID
    work = run_estimate.beam_estimate(
        spec, spec.n_points, 1, _fake(monkeypatch, lambda p, continued: 10 if continued
                                      else 80))
    lines = spec.n_points / 40
    assert work.seconds == pytest.approx(lines * (80 + 10 * 39) * PER_PERIOD, rel=1e-12)


def test_a_point_that_does_not_settle_in_the_sample_is_counted_at_its_whole_budget(
        monkeypatch):
    # Every point runs its budget (5000 periods), the sample gives it BEAM_SAMPLE_PERIODS.
    spec = load_sweep(_grid(max_periods=5000), model="beam")
    work = run_estimate.beam_estimate(spec, spec.n_points, 1,
                                      _fake(monkeypatch, lambda p, c: 10**9))
    assert work.seconds == pytest.approx(spec.n_points * 5000 * PER_PERIOD, rel=1e-12)
    sampled = min(run_estimate.BEAM_SAMPLE_POINTS, spec.lines_per_chunk)
    assert (f"{sampled} of {sampled} sampled points did not settle within the sample's "
            f"{run_estimate.BEAM_SAMPLE_PERIODS} periods") in work.describe()


def test_a_long_beam_sweep_is_refused_before_any_work_and_runs_with_yes(
        tmp_path, monkeypatch, capsys):
    sweep = tmp_path / "beam.toml"
    sweep.write_text('model = "beam"\npreset = "bimorph_tip"\n[parameters]\nn_modes = 1\n'
                     '[grid]\nfrequency = [130.0, 150.0]\n')
    out = tmp_path / "beam.nc"
    # a grid this small says its size alone
    assert main(["beam-sweep", str(sweep), "--output", str(out)]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if "compiling" not in line]
    assert err[0] == "harvester-sweep: 2 points"
    out.unlink()
    monkeypatch.setattr(run_estimate, "BEAM_SAMPLED_GRID", 1)
    monkeypatch.setattr(run_estimate, "LONG_RUN_SECONDS", 1e-9)
    for command in ("beam-sweep", "run"):
        assert main([command, str(sweep), "--output", str(out)]) == 2
        err = [line for line in capsys.readouterr().err.strip().splitlines()
               if "compiling" not in line]
        assert len(err) == 1 and err[0].startswith("harvester-sweep: error: 2 points, "
                                                   "roughly"), err
        assert "--yes" in err[0]
        assert not out.exists() and not (tmp_path / "beam.nc.partial").exists()
    assert main(["beam-sweep", str(sweep), "--output", str(out), "--yes"]) == 0
    assert out.exists()


def test_the_beam_estimate_changes_no_result(monkeypatch):
    # A sweep whose sample was solved first gives beam_sweep's numbers bit for bit.
    monkeypatch.setattr(run_estimate, "BEAM_SAMPLED_GRID", 1)
    axes = {"gap": [1e-6, 2e-6], "frequency": [130.0, 140.0, 150.0]}
    sweep = {"model": "beam", "preset": "bimorph_tip", "parameters": {"n_modes": 2},
             "grid": axes, "sweep": {"directions": ["up"]}}
    sampled = run_beam_file(sweep, announce=True)
    alone = beam_sweep(axes, "bimorph_tip", directions="up", n_modes=2)
    for name in ("power", "x_max", "status", "periods_run", "error_estimate"):
        np.testing.assert_array_equal(sampled[name].values, alone[name].values)
