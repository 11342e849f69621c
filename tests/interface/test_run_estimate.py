"""The run-time estimate said before a sweep (run_estimate): what it counts is what the
solver does, it grows with the work and shrinks with the threads, it gates long runs in
one line, and it changes no result. No assertion here is on a time: the estimate's
seconds are compared only with each other, on one measured sample."""

from __future__ import annotations

import numpy as np
import pytest

from harvester_sweep import run_estimate, run_sweep
from harvester_sweep.chunks import compute_chunk
from harvester_sweep.cli import main
from harvester_sweep.parameters import ParameterError
from harvester_sweep.run_estimate import RunEstimate, announce, estimate
from harvester_sweep.sweep_file import load_sweep

#: A grid of the paper scene, stop in reach and out of it, larger than the sample.
GRID = {"preset": "paper", "parameters": {"steps_per_period": 256, "max_periods": 2000},
        "grid": {"gap": {"start": 0.5e-6, "stop": 4e-6, "num": 12},
                 "frequency": {"start": 120.0, "stop": 260.0, "num": 12}},
        "sweep": {"outputs": ["power"], "error_estimate": "none"}}


def _line(directions, num=24):
    return {**GRID, "grid": {"gap": [1e-6], "frequency": {"start": 150.0, "stop": 280.0,
                                                           "num": num}},
            "sweep": {**GRID["sweep"], "directions": directions}}


def test_a_grid_within_the_sample_is_counted_as_the_solver_runs_it():
    # The sample is solved for real: on a grid it covers, the estimate's steps are the
    # sweep's own count (rk4_steps, from the solver), under continuation too.
    for sweep in ({**GRID, "grid": {"gap": [0.5e-6, 2e-6], "frequency": [140.0, 180.0]}},
                  _line(["up"], num=run_estimate.SEGMENT)):
        spec = load_sweep(sweep)
        work = estimate(spec, spec.n_points, 1)
        ds = run_sweep(spec, progress=False)
        assert work.steps == pytest.approx(float(ds["rk4_steps"].sum()), rel=1e-12)
        assert "did not settle" not in work.describe()


def test_the_estimate_grows_with_the_points_and_shrinks_with_the_threads():
    spec = load_sweep(GRID)
    half, whole = (estimate(spec, n, 1) for n in (spec.n_points // 2, spec.n_points))
    assert whole.steps == pytest.approx(2 * half.steps)
    assert half.seconds < whole.seconds < 2.2 * half.seconds
    # (the steps share the threads; the solver's rounds do not)
    one, two, eight = (estimate(spec, spec.n_points, t).seconds for t in (1, 2, 8))
    assert eight <= two <= one
    assert estimate(spec, 0, 1).seconds == 0.0


def test_a_continued_line_costs_its_points_one_after_another(monkeypatch):
    # A swept line's points wait for each other: a line twice as long takes longer, and
    # a second direction adds its line's steps. (The two lines' times on one measured
    # sample, the short line's: each sweep's own, measured apart, differ by this machine's
    # load, and under pytest-xdist by the other worker's.)
    short, long = (load_sweep(_line(["up"], num=n)) for n in (24, 48))
    sample = run_estimate._sweep_sample(short)
    with monkeypatch.context() as patched:
        patched.setattr(run_estimate, "_sweep_sample", lambda spec: sample)
        assert estimate(long, long.n_points, 2).seconds > estimate(short, short.n_points,
                                                                   2).seconds
    both = load_sweep(_line(["up", "down"], num=24))
    assert estimate(both, both.n_points, 2).steps > estimate(short, short.n_points, 2).steps


def test_the_sample_is_bounded_whatever_the_grid(monkeypatch):
    solved = []
    solve = run_estimate.solve_orbits

    def counting(rows, *args, **kwargs):
        solved.append(len(rows))
        assert (rows[:, run_estimate.PARAM.max_periods] * rows[:, run_estimate.PARAM.steps]
                <= max(run_estimate.SAMPLE_STEPS, rows[:, run_estimate.PARAM.steps].max())
                ).all()
        return solve(rows, *args, **kwargs)

    monkeypatch.setattr(run_estimate, "solve_orbits", counting)
    huge = {**GRID, "grid": {"frequency": {"start": 100, "stop": 300, "num": 100_000},
                             "gap": {"start": 1e-7, "stop": 1e-5, "num": 100_000}}}
    work = estimate(load_sweep(huge), 10**10, 2)
    assert solved == [run_estimate.SAMPLE_POINTS]
    assert work.long and work.points == 10**10


def test_a_long_run_is_refused_in_one_line_before_any_work(tmp_path, capsys):
    long = RunEstimate(10, 10, 1e12, 2, run_estimate.LONG_RUN_SECONDS * 1.5)
    with pytest.raises(ParameterError, match=r"^10 points, .* beyond 1 h: start it with --yes"):
        announce(long, yes=False, progress=True, smaller="make the grid coarser")
    announce(long, yes=True, progress=True, smaller="")
    assert capsys.readouterr().err.startswith("harvester-sweep: 10 points, about 1e+12")
    sweep = tmp_path / "long.toml"
    sweep.write_text('[grid]\nfrequency = { start = 100, stop = 300, num = 100000 }\n'
                     'gap = { start = 1e-7, stop = 1e-5, num = 10000 }\n')
    capsys.readouterr()
    assert main(["run", str(sweep), "--output", str(tmp_path / "long.nc")]) == 2
    # (the estimate solves a sample of the grid: on a cold cache the engine's compilation
    # note comes first)
    err = [line for line in capsys.readouterr().err.strip().splitlines()
           if "compiling" not in line]
    assert len(err) == 1 and "1,000,000,000 points" in err[0] and "--yes" in err[0], err
    assert not (tmp_path / "long.nc.partial").exists()


def test_a_small_grid_that_cannot_be_long_is_not_sampled(monkeypatch, capsys):
    # Below SAMPLED_GRID points the sample would be a good share of the run: the sweep
    # says its size alone and solves nothing first.
    def refused(spec):
        raise AssertionError("a small grid was sampled")

    monkeypatch.setattr(run_estimate, "_sample_of", refused)
    spec = load_sweep(_line(["up"], num=24))
    assert spec.n_points < run_estimate.SAMPLED_GRID
    ds = run_sweep(spec, progress=True)
    assert (ds["status"] == 0).all()
    err = [line for line in capsys.readouterr().err.splitlines() if "compiling" not in line]
    assert err[0] == "harvester-sweep: 24 points"


def test_a_small_grid_whose_budgets_could_be_long_is_sampled_and_refused(tmp_path, capsys):
    # Two points at 1e6 steps a period and a budget of 1e6 periods: the bound (2e12
    # steps at BOUND_RATE) is beyond an hour, so the sample decides, and it says long.
    sweep = tmp_path / "small_but_long.toml"
    sweep.write_text('[parameters]\nsteps_per_period = 1000000\nmax_periods = 1000000\n'
                     '[grid]\nfrequency = [100.0, 300.0]\n')
    assert main(["run", str(sweep), "--output", str(tmp_path / "out.nc")]) == 2
    err = [line for line in capsys.readouterr().err.strip().splitlines()
           if "compiling" not in line]
    assert len(err) == 1 and err[0].startswith("harvester-sweep: error: 2 points, about")
    assert "--yes" in err[0]
    # (and why: the sample gave each point one period, which did not settle it)
    assert ("(2 of 2 sampled points did not settle within the sample's 1 period and are "
            "counted at their whole budget (max_periods))") in err[0]


def test_the_estimate_changes_no_result():
    # A sweep run after its estimate (its sample solved, the engine timed) gives the
    # chunk's numbers bit for bit as the chunk computed alone, with no estimate.
    sweep = _line(["up", "down"], num=12)
    spec = load_sweep(sweep)
    run_estimate._SAMPLES.clear()
    estimate(spec, spec.n_points, 2)  # (a grid this small is not sampled by the sweep)
    ds = run_sweep(spec, progress=True)
    alone = compute_chunk(spec, 0)
    np.testing.assert_array_equal(ds["power"].values.ravel(), alone["metrics"][..., 0].ravel())
    np.testing.assert_array_equal(ds["rk4_steps"].values.ravel(), alone["rk4_steps"].ravel())
