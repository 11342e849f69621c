"""Speed of the sweep engine, end to end, against what a user would otherwise pick.

    python -m pytest benchmarks/test_speed.py [--million]

pytest-benchmark times each case (its own table); conftest.py prints the figures in one
table, every ratio taken within this run, and writes benchmarks/results/speed.md.

- a 64 x 64 gap x frequency sweep of the paper scene at 1024 steps per period, through
  ``run_sweep`` (steady-state detection, contact location, metrics, netCDF): RK4 steps per
  second and share of the CPU's double-precision peak; the same grid with the stop out of
  reach, to show what the contact points cost the others; a 32 x 64 one swept up and
  down in frequency (continuation);
- per point at matched error: the paper scene from rest to its steady state, for an
  ensemble of 64 copies (the periodic-orbit solver as a sweep runs it, a diffrax ``vmap``)
  and SciPy LSODA, at the engine's default accuracy (1e-7) and at 1e-5. The engine's error
  is its orbit's distance from the exact orbit (tests/helpers.py's DOP853 reference); an
  alternative, a transient integration from rest, is timed to the period from which it
  stays within that distance (at its best tolerance);
- each time the best of a few runs (the counts and why: cases.py);
- a new process running a one-point sweep with the on-disk cache warm;
- with ``--million``: the 1e6-point 4-D sweep of examples/million_points.toml, its wall
  time and peak memory.
"""

from __future__ import annotations

import resource
import subprocess
import sys
import time
from pathlib import Path

import numba
import numpy as np
import pytest

import harvester_sweep as hs
from benchmarks.alternatives import (
    RTOLS,
    diffrax_ensemble,
    lsoda,
    matched_time,
    paper_reference,
    state_error,
)
from benchmarks.cases import (
    ALTERNATIVE_ROUNDS,
    COLD_START_ROUNDS,
    ENGINE_ROUNDS,
    FREE,
    GRID,
    HALF,
    SWEEP_ROUNDS,
    sweep_spec,
)
from benchmarks.per_point import ENSEMBLE, solve_round
from harvester_sweep import _engine, packing
from harvester_sweep._engine import lanes
from harvester_sweep._engine.layouts import LANE, LANES
from harvester_sweep.jit import JIT

ROOT = Path(__file__).resolve().parents[1]


def _sweep(grid: dict, output: Path, directions=None):
    return hs.run_sweep(sweep_spec(grid, directions), output, progress=False)


def _rate(benchmark, grid, tmp_path, directions=None) -> tuple[float, float, int]:
    # Compile or load the cache; and write a file, as the first netCDF file a process
    # writes costs imports (xarray imports dask.distributed when installed: 0.27 s), which
    # the new-process figure counts.
    _sweep({"gap": [1e-6], "frequency": [140.0]}, tmp_path / "warm.nc")
    walls = []

    def run():
        start = time.perf_counter()
        ds = _sweep(grid, tmp_path / "sweep.nc", directions)
        walls.append(time.perf_counter() - start)
        return ds

    # Best of SWEEP_ROUNDS (see there).
    ds = benchmark.pedantic(run, rounds=SWEEP_ROUNDS, iterations=1)
    assert int((ds.status == 2).sum()) == 0
    steps = int(ds.rk4_steps.sum())  # (every step: motion, Newton's copies, estimates)
    return steps / min(walls), min(walls), steps


def test_sweep_64x64(benchmark, figures, tmp_path):
    rate, wall, steps = _rate(benchmark, GRID, tmp_path)
    figures.update(sweep_rate=rate, sweep_wall=wall, sweep_steps=steps)


def test_sweep_64x64_stop_out_of_reach(benchmark, figures, tmp_path):
    figures["free_rate"], figures["free_wall"], figures["free_steps"] = _rate(
        benchmark, FREE, tmp_path)


def test_sweep_swept_up_and_down(benchmark, figures, tmp_path):
    """Frequency continuation: 32 gaps x 64 frequencies, each point from the final state of
    the frequency before, up and down (64 lines, which the lanes walk)."""
    figures["continued_rate"] = _rate(benchmark, HALF, tmp_path, ["up", "down"])[0]


@numba.njit(**{**JIT, "cache": False})
def _lane_loop(L, steps):
    """``steps`` plain steps of the lane loop alone (no scalar finishing, no period ends)."""
    for j in range(LANES):
        L[LANE.k_end + j] = np.inf  # never at a stop
    for _ in range(steps):
        lanes.lane_steps(L, 0.0)


def test_lane_loop_alone(benchmark, figures):
    """What one core does in the vector loop alone: lanes of the paper scene kept off the
    stop (the contact-free code) and kept in contact (the full code)."""
    numba_threads = numba.get_num_threads()
    rates = {}
    for touching in (0.0, 1.0):
        L = lanes.new_table()
        for j in range(LANES):
            p = hs.resolve_parameters("paper", steps_per_period=1024, frequency=100.0 + 5 * j)
            lanes.load(L, j, packing.pack_parameters(p), packing.initial_state(p), 0.0)
            L[LANE.on + j] = touching
        _lane_loop(L, 10)
        steps = 200_000

        def run(L=L):
            start = time.perf_counter()
            _lane_loop(L, steps)
            rates.setdefault(touching, []).append(LANES * steps
                                                  / (time.perf_counter() - start))

        benchmark.pedantic(run, rounds=3, iterations=1) if touching else run()
    assert numba.get_num_threads() == numba_threads
    figures.update(loop_free=max(rates[0.0]), loop_contact=max(rates[1.0]))


ACCURACIES = (1e-7, 1e-5)  # the engine's default, and an engineering accuracy


@pytest.fixture(scope="module", params=ACCURACIES, ids=lambda a: f"accuracy={a:g}")
def paper(request):
    """The paper scene at an accuracy (alternatives.paper_reference)."""
    return paper_reference(request.param)


def test_engine_per_point(benchmark, figures, paper):
    """The periodic-orbit solver as a sweep point runs it (``results.solve``: Floquet
    multipliers, error estimate and accuracy target included), on all cores (its default)
    and on one (numba.set_num_threads(1)), as SciPy and XLA run these baselines on one."""
    p, exact, _ = paper
    packed = packing.pack_points([p] * ENSEMBLE)
    estimated = np.ones(ENSEMBLE, dtype=bool)
    threads = numba.get_num_threads()
    times, out = {}, {}

    def run():
        # (each thread count solved untimed first, and no pause between rounds: a core
        # left idle wakes up late on this virtual machine: after 0.2 s idle, a two-thread
        # run of 64 points at 1e-5 took 0.24 ms a point, median of 30 runs, against 0.14
        # back to back; a sweep pays that once, not per point)
        for n, solved in solve_round(packed, estimated, threads).items():
            times.setdefault(n, []).append(solved.run_time)
            assert np.all(solved.finals == solved.finals[0])  # every lane the same bits
            out[n] = solved

    benchmark.pedantic(run, rounds=ENGINE_ROUNDS, iterations=1)
    solved = out[1]
    assert np.array_equal(solved.finals, out[threads].finals)  # and on any thread count
    assert solved.metrics[0, _engine.METRIC.status] == _engine.STATUS.settled
    figures["ensemble"] = ENSEMBLE
    figures.setdefault("points", {})[p["accuracy"]] = {
        "engine": min(times[threads]) / ENSEMBLE, "engine_1": min(times[1]) / ENSEMBLE,
        "threads": threads, "error": state_error(solved.finals[0], exact),
        "periods": int(solved.metrics[0, _engine.METRIC.periods_run]),
        "rk4_steps": int(solved.rk4_steps[0]), "steps": int(solved.steps[0])}


def test_lsoda_per_point(benchmark, figures, paper):
    p, exact, periods = paper
    runs = []

    def run():
        for rtol in RTOLS["lsoda"]:
            seconds, states = lsoda(p, periods, rtol)
            runs.append((rtol, seconds, states))

    benchmark.pedantic(run, rounds=ALTERNATIVE_ROUNDS, iterations=1)
    row = figures["points"][p["accuracy"]]
    row["lsoda"], row["lsoda_how"] = matched_time(runs, exact, row["error"])


def test_diffrax_per_point(benchmark, figures, paper):
    p, exact, periods = paper
    try:
        diffrax_ensemble(p, periods, ENSEMBLE, 1e-6)  # compile
    except ImportError as missing:
        figures["diffrax_skipped"] = str(missing)
        pytest.skip(str(missing))
    runs = []

    def run():
        for rtol in RTOLS["diffrax"]:
            seconds, states = diffrax_ensemble(p, periods, ENSEMBLE, rtol)
            runs.append((rtol, seconds, states[ENSEMBLE // 2]))

    benchmark.pedantic(run, rounds=ALTERNATIVE_ROUNDS, iterations=1)
    row = figures["points"][p["accuracy"]]
    row["diffrax"], row["diffrax_how"] = matched_time(runs, exact, row["error"])


def _cli(args: list[str]) -> None:
    subprocess.run([sys.executable, "-m", "harvester_sweep.cli", *args], check=True)


def test_one_point_sweep_in_a_new_process(benchmark, figures, tmp_path):
    sweep = tmp_path / "one.toml"
    sweep.write_text('preset = "paper"\n[grid]\nfrequency = [140.0]\n')
    args = ["run", str(sweep), "--output", str(tmp_path / "one.nc"), "--quiet"]
    _cli(args)  # the on-disk cache warm
    times = []

    def run():
        start = time.perf_counter()
        _cli(args)
        times.append(time.perf_counter() - start)

    benchmark.pedantic(run, rounds=COLD_START_ROUNDS, iterations=1)
    figures["cold_start"] = min(times)


def test_million_points(benchmark, figures, tmp_path, request):
    if not request.config.getoption("--million"):
        pytest.skip("the 1e6-point sweep takes several minutes: pass --million")
    import xarray as xr

    output = tmp_path / "million.nc"

    def run():
        start = time.perf_counter()
        _cli(["run", str(ROOT / "examples" / "million_points.toml"), "--output", str(output),
              "--quiet"])
        figures["million_wall"] = time.perf_counter() - start

    benchmark.pedantic(run, rounds=1, iterations=1)
    figures["million_rss"] = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024
    with xr.open_dataset(output) as ds:
        assert ds.power.size == 1_000_000
        figures["million_settled"] = int((ds.status == 0).sum())
