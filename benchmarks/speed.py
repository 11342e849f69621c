"""Speed of the sweep engine, end to end, and against SciPy's LSODA, in one run.

    python benchmarks/speed.py            # writes benchmarks/results/speed.md

1. A 64 x 64 gap x frequency sweep of the paper scene at 1024 steps per period, from rest,
   through ``run_sweep`` (steady-state detection, contact location, metrics, netCDF):
   RK4 steps per second and the share of the CPU's double-precision peak that is.
2. Per point at matched error: the engine's default scene against SciPy LSODA (the same
   equations, tests/reference.py's right-hand side without event restarts) integrating
   the same number of forcing periods at the rtol that reaches the engine's error.
3. A new process running a one-point sweep with the on-disk cache warm.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from reference import Reference  # noqa: E402

import harvester_sweep as hs  # noqa: E402

FLOPS_PER_STEP = 100  # one RK4 step of this system, counted by hand (4 stages + update)


def cpu() -> tuple[str, int, float, int]:
    """CPU model, cores, clock [Hz] and double-precision flops per cycle per core."""
    text = Path("/proc/cpuinfo").read_text()
    model = next((line.split(":", 1)[1].strip() for line in text.splitlines()
                  if line.startswith("model name")), platform.processor())
    mhz = max(float(line.split(":", 1)[1]) for line in text.splitlines()
              if line.startswith("cpu MHz"))
    flags = next(line for line in text.splitlines() if line.startswith("flags")).split()
    width = 8 if "avx512f" in flags else 4 if "avx" in flags else 2
    per_cycle = width * 2 * (2 if "fma" in flags else 1)  # two FP pipes, FMA counts 2
    return model, os.cpu_count() or 1, mhz * 1e6, per_cycle


def sweep_rate() -> tuple[float, float, int]:
    """RK4 steps per second of the 64 x 64 sweep, wall seconds and steps."""
    spec = {"preset": "paper", "parameters": {"steps_per_period": 1024},
            "grid": {"gap": {"start": 0.25e-6, "stop": 4e-6, "num": 64},
                     "frequency": {"start": 100, "stop": 250, "num": 64}},
            "sweep": {"outputs": ["power", "v_peak", "x_max", "orbit_period"],
                      "error_estimate": "none"}}
    hs.run_sweep({**spec, "grid": {"gap": [1e-6], "frequency": [140.0]}}, progress=False)
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        ds = hs.run_sweep(spec, Path(tmp) / "speed.nc", progress=False)
        wall = time.perf_counter() - start
    steps = int(ds.periods_run.sum()) * 1024
    return steps / wall, wall, steps


def lsoda_matched() -> dict:
    """Engine scene vs LSODA over the same periods at the rtol that matches its error."""
    scene = hs.run_scene("paper")
    periods, engine_time = scene.metrics["periods_run"], scene.metrics["run_time"]
    p = scene.parameters
    T = 1 / p["frequency"]
    exact = Reference(p).integrate(np.zeros(3), 0.0, periods * T)[0]
    scale = np.array([1e-6, 1e-2, 1e-5])

    def engine_error() -> float:
        row = hs.kernel.pack_parameters(dict(p, max_periods=periods))
        state = hs.kernel.initial_state(p)
        series = hs.lanes.record_series(row, state, periods)
        return float(np.max(np.abs(series[-1, :3] - exact[:3]) / scale))

    target = engine_error()
    ref = Reference(p)

    def rhs(t, y):  # the switched system as a user would write it: no event restarts
        return ref.rhs(t, y, y[0] > p["gap"])

    for rtol in [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11]:
        start = time.perf_counter()
        sol = solve_ivp(rhs, (0, periods * T), np.zeros(8), method="LSODA", rtol=rtol,
                        atol=rtol * np.array([1e-6, 1e-2, 1e-5, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9]))
        elapsed = time.perf_counter() - start
        error = float(np.max(np.abs(sol.y[:3, -1] - exact[:3]) / scale))
        if error <= target:
            break
    return {"periods": periods, "engine_time": engine_time, "engine_error": target,
            "lsoda_rtol": rtol, "lsoda_time": elapsed, "lsoda_error": error}


def cold_start() -> float:
    """Wall time of a new process running a one-point sweep (cache warm), best of 3."""
    with tempfile.TemporaryDirectory() as tmp:
        sweep = Path(tmp) / "one.toml"
        sweep.write_text('preset = "paper"\n[grid]\nfrequency = [140.0]\n')
        times = []
        for _ in range(3):
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "harvester_sweep.cli", "run", str(sweep),
                            "--output", str(Path(tmp) / "one.nc"), "--quiet"], check=True)
            times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    model, cores, clock, per_cycle = cpu()
    peak = cores * clock * per_cycle
    rate, wall, steps = sweep_rate()
    matched = lsoda_matched()
    start_up = cold_start()
    lines = [
        "# Speed of the sweep engine",
        "",
        f"- command: `python benchmarks/speed.py`; date {time.strftime('%Y-%m-%d %H:%M')}",
        f"- machine: {model}, {cores} cores at {clock / 1e9:.2f} GHz, {per_cycle} DP flops/cycle"
        f"/core: peak {peak / 1e9:.0f} GFLOP/s; numba threads {hs.lanes.numba.get_num_threads()}",
        "",
        "| measure | value |",
        "| --- | ---: |",
        f"| 64 x 64 gap x frequency sweep, 1024 steps/period: wall time | {wall:.2f} s |",
        f"| RK4 steps (all periods run) | {steps:.3g} |",
        f"| RK4 steps per second, end to end | {rate / 1e6:.0f} M/s |",
        f"| share of DP peak (~{FLOPS_PER_STEP} flops/step) | "
        f"{100 * rate * FLOPS_PER_STEP / peak:.1f} % |",
        f"| paper scene from rest: engine ({matched['periods']} periods, final-state error "
        f"{matched['engine_error']:.1e}) | {matched['engine_time'] * 1e3:.1f} ms |",
        f"| SciPy LSODA, same periods, rtol {matched['lsoda_rtol']:g} (error "
        f"{matched['lsoda_error']:.1e}) | {matched['lsoda_time'] * 1e3:.0f} ms |",
        f"| LSODA / engine per point at matched error | "
        f"{matched['lsoda_time'] / matched['engine_time']:.0f} x |",
        f"| one-point sweep in a new process, cache warm | {start_up:.2f} s |",
        f"| 1e6-point sweep at this rate, ~{steps / 4096 / 1024:.0f} periods x 1024 steps "
        f"per point (estimate) | {1e6 * steps / 4096 / rate / 60:.0f} min |",
    ]
    text = "\n".join(lines) + "\n"
    out = ROOT / "benchmarks" / "results" / "speed.md"
    out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
