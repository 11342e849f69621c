"""Speed of the sweep engine, end to end, against what a user would otherwise pick.

    python -m pytest benchmarks/test_speed.py [--million]

pytest-benchmark times each case (its own table); conftest.py prints the figures in one
table, every ratio taken within this run, and writes benchmarks/results/speed.md.

- a 64 x 64 gap x frequency sweep of the paper scene at 1024 steps per period, through
  ``run_sweep`` (steady-state detection, contact location, metrics, netCDF): RK4 steps per
  second and share of the CPU's double-precision peak; the same grid with the stop out of
  reach, to show what the contact points cost the others; a 32 x 64 one swept up and
  down in frequency (continuation);
- per point at matched error: the paper scene from rest to steady state for an ensemble of
  64 copies (the engine's lanes, a diffrax ``vmap``) against SciPy LSODA, at the engine's
  default accuracy (1e-7) and at 1e-5; the final state is compared with
  tests/helpers.py, and each alternative's time is interpolated (log-log, between the
  two tolerances that bracket it) to the engine's error;
- each time the best of a few runs (the counts and why: cases.py);
- a new process running a one-point sweep with the on-disk cache warm;
- with ``--million``: the 1e6-point 4-D sweep of examples/million_points.toml, its wall
  time and peak memory.
"""

from __future__ import annotations

import math
import resource
import subprocess
import sys
import time
from pathlib import Path

import numba
import numpy as np
import pytest

import harvester_sweep as hs
from benchmarks.alternatives import ATOL_SCALE, diffrax_ensemble, lsoda
from benchmarks.cases import (
    ALTERNATIVE_ROUNDS,
    COLD_START_ROUNDS,
    ENGINE_ROUNDS,
    FREE,
    GRID,
    HALF,
    STEPS_PER_PERIOD,
    SWEEP_ROUNDS,
    sweep_spec,
)
from harvester_sweep import _engine, packing
from harvester_sweep._engine import GROUP, LANE, LANES, lanes
from harvester_sweep._engine.flags import JIT
from tests.helpers import Reference

ROOT = Path(__file__).resolve().parents[1]
ENSEMBLE = 64


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
    steps = int(ds.periods_run.sum()) * STEPS_PER_PERIOD
    return steps / min(walls), min(walls), steps


def test_sweep_64x64(benchmark, figures, tmp_path):
    rate, wall, steps = _rate(benchmark, GRID, tmp_path)
    figures.update(sweep_rate=rate, sweep_wall=wall, sweep_steps=steps)


def test_sweep_64x64_stop_out_of_reach(benchmark, figures, tmp_path):
    figures["free_rate"] = _rate(benchmark, FREE, tmp_path)[0]


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
        lanes.lane_steps(L, LANES // GROUP, 0.0)


def test_lane_loop_alone(benchmark, figures):
    """What one core does in the vector loop alone: lanes of the paper scene kept off the
    stop (the contact-free code) and kept in contact (the full code)."""
    numba_threads = numba.get_num_threads()
    rates = {}
    for touching in (0.0, 1.0):
        L = lanes.table()
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
    """The paper scene at an accuracy, the periods the engine takes to settle from rest and
    the reference state after them."""
    scene = hs.run_scene("paper", accuracy=request.param)
    p, periods = scene.parameters, scene.metrics["periods_run"]
    exact = Reference(p).integrate(np.zeros(3), 0.0, periods / p["frequency"])[0][:3]
    return p, periods, exact


def _error(state, exact) -> float:
    """max over (x, v, V) of |state - reference| / (1e-6 m, 1e-2 m/s, 1e-5 V)."""
    return float(np.max(np.abs(np.asarray(state)[:3] - exact) / ATOL_SCALE))


def test_engine_per_point(benchmark, figures, paper):
    """The engine on all cores (its default) and on one (numba.set_num_threads(1)), as
    SciPy and XLA run these baselines on one core."""
    p, periods, exact = paper
    rows = np.repeat(packing.pack_parameters(p)[None, :], ENSEMBLE, axis=0)
    rest = np.repeat(packing.initial_state(p)[None, :], ENSEMBLE, axis=0)
    metrics = np.empty((ENSEMBLE, len(_engine.METRIC)))
    strobes = np.empty((ENSEMBLE, 0, 3))
    _engine.warm_up()
    threads = numba.get_num_threads()
    times, out = {}, {}

    def run():
        for n in sorted({threads, 1}):
            numba.set_num_threads(n)
            # Untimed first, and no pause between rounds: a core left idle wakes up late
            # on this virtual machine (after 0.2 s idle, a two-thread run of 64 points at
            # 1e-5 took 0.24 ms a point, median of 30 runs, against 0.14 back to back);
            # a sweep pays that once, not per point.
            _engine.run_points(rows, rest.copy(), metrics, strobes)
            states = rest.copy()
            start = time.perf_counter()
            _engine.run_points(rows, states, metrics, strobes)
            times.setdefault(n, []).append(time.perf_counter() - start)
            assert np.all(states == states[0])  # every lane the same bits
            out[n] = states
        numba.set_num_threads(threads)

    benchmark.pedantic(run, rounds=ENGINE_ROUNDS, iterations=1)
    assert np.all(metrics[:, _engine.METRIC.periods_run] == periods)
    assert np.array_equal(out[1], out[threads])  # and on any thread count
    figures["ensemble"] = ENSEMBLE
    figures.setdefault("points", {})[p["accuracy"]] = {
        "engine": min(times[threads]) / ENSEMBLE, "engine_1": min(times[1]) / ENSEMBLE,
        "threads": threads, "error": _error(out[1][0], exact), "periods": periods,
        "steps": p["steps_per_period"]}


def _matched(points: list[tuple[float, float, float]], target: float) -> tuple[float, str]:
    """Time [s] to reach the error ``target``, from (rtol, time, error) points.

    Points beaten on both time and error by another are dropped first (an error is not
    always monotonic in rtol); the time is then interpolated log-log between the two
    points of what is left that bracket the target, or is the closest point's."""
    front = []
    for point in sorted(points, key=lambda point: point[1]):
        if not front or point[2] < front[-1][2]:
            front.append(point)
    for (r1, t1, e1), (r2, t2, e2) in zip(front, front[1:]):  # e1 > e2, t1 < t2
        if e2 <= target <= e1 and e2 > 0:
            s = math.log(target / e1) / math.log(e2 / e1)
            return (math.exp(math.log(t1) + s * math.log(t2 / t1)),
                    f"rtol {r1:g}: {e1:.1e} in {t1 * 1e3:.3g} ms; {r2:g}: {e2:.1e} in "
                    f"{t2 * 1e3:.3g} ms")
    r, t, e = min(front, key=lambda point: abs(math.log(point[2] / target)))
    return t, f"closest: rtol {r:g}, error {e:.1e}"


def test_lsoda_per_point(benchmark, figures, paper):
    p, periods, exact = paper
    points = []

    def run():
        for rtol in (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11):
            seconds, state = lsoda(p, periods, rtol)
            points.append((rtol, seconds, _error(state, exact)))

    benchmark.pedantic(run, rounds=ALTERNATIVE_ROUNDS, iterations=1)
    row = figures["points"][p["accuracy"]]
    row["lsoda"], row["lsoda_how"] = _matched(_best(points), row["error"])


def _best(points: list[tuple[float, float, float]]) -> list[tuple[float, float, float]]:
    """The shortest time of each tolerance's runs (rtol, time, error); its error, the same
    in every run, with it."""
    best = {}
    for rtol, seconds, error in points:
        if rtol not in best or seconds < best[rtol][1]:
            best[rtol] = (rtol, seconds, error)
    return list(best.values())


def test_diffrax_per_point(benchmark, figures, paper):
    p, periods, exact = paper
    try:
        diffrax_ensemble(p, periods, ENSEMBLE, 1e-6)  # compile
    except ImportError as missing:
        figures["diffrax_skipped"] = str(missing)
        pytest.skip(str(missing))
    points = []

    def run():
        for rtol in (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11):
            seconds, states = diffrax_ensemble(p, periods, ENSEMBLE, rtol)
            points.append((rtol, seconds, _error(states[ENSEMBLE // 2], exact)))

    benchmark.pedantic(run, rounds=ALTERNATIVE_ROUNDS, iterations=1)
    row = figures["points"][p["accuracy"]]
    row["diffrax"], row["diffrax_how"] = _matched(_best(points), row["error"])


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
        pytest.skip("the 1e6-point sweep takes about 20 minutes: pass --million")
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
