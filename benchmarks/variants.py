"""The speed of the model's variants against the rigid stop, in one process, runs alternated.

    python -m benchmarks.variants [--rounds 5]

One thread, 64 points for 60 periods (no settling) at 1024 steps per period, the paper
scene at 64 frequencies from 200 to 260 Hz with the stop 1 um away (an impact a period
over most of it): a rigid stop, stops on both sides, and a stop on a spring (stiff and
soft, as tests/physics/test_moving_stop.py). Microseconds per point and period, best of
the rounds, and the ratio to the rigid stop; the machine's CPU model heads the table.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import subprocess
import time
from pathlib import Path

import numba
import numpy as np

from harvester_sweep import _engine, resolve_parameters
from harvester_sweep.packing import initial_state, pack_parameters

STEPS, PERIODS, POINTS = 1024, 60, 64


def _support(mass, frequency, damping_ratio):
    w = 2 * math.pi * frequency
    return dict(stop_mass=mass, stop_support_stiffness=mass * w * w,
                stop_support_damping=2 * damping_ratio * mass * w, hertz_stiffness=9.03e8)


VARIANTS = {
    "rigid stop": {},
    "stops on both sides (lower_gap 1 um)": {"lower_gap": 1e-6},
    "stiff moving stop (25 g, 3 kHz)": _support(2.5e-2, 3000.0, 0.05),
    "soft moving stop (2.5 g, 400 Hz)": _support(2.5e-3, 400.0, 0.05),
}


def _points(extra):
    rows = [pack_parameters(resolve_parameters(
        "paper", gap=1e-6, frequency=float(f), steps_per_period=STEPS, max_periods=PERIODS,
        settle_tolerance=1e-300, **extra)) for f in np.linspace(200.0, 260.0, POINTS)]
    rest = initial_state(resolve_parameters("paper", **extra))
    return np.array(rows), np.repeat(rest[None, :], POINTS, axis=0)


def _per_period(rows, rest) -> float:
    states, metrics = rest.copy(), np.empty((POINTS, len(_engine.METRIC)))
    start = time.perf_counter()
    _engine.run_points(rows, states, metrics, np.empty((POINTS, 0, 3)), settle=False)
    return (time.perf_counter() - start) / (POINTS * PERIODS)


def cpu_model() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        return next(line.split(":", 1)[1].strip() for line in out.splitlines()
                    if line.startswith("Model name"))
    except (OSError, StopIteration):
        return platform.processor() or "unknown"


def provenance() -> str:
    """Where a result was measured: the commit, the CPU (lscpu), its cores, numba and its
    threads, Python."""
    root = Path(__file__).resolve().parents[1]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root,
                            capture_output=True, text=True).stdout.strip()
    import numba

    return (f"Commit {commit}. CPU: {cpu_model()}; {os.cpu_count()} cores, numba "
            f"{numba.__version__} on {numba.config.NUMBA_NUM_THREADS} threads; Python "
            f"{platform.python_version()}.")


def best(function, rounds):
    """(best wall time [s], the last result) of ``rounds`` calls after an uncounted one."""
    result = function()
    fastest = math.inf
    for _ in range(rounds):
        start = time.perf_counter()
        result = function()
        fastest = min(fastest, time.perf_counter() - start)
    return fastest, result


def report(lines: list, output=None) -> None:
    """Print a benchmark's markdown ``lines``, and write them to ``output`` when given."""
    text = "\n".join(lines) + "\n"
    print(text)
    if output:
        Path(output).write_text(text, encoding="utf-8")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    cases = {name: _points(extra) for name, extra in VARIANTS.items()}
    numba.set_num_threads(1)
    for rows, rest in cases.values():  # compile
        _per_period(rows[:1].repeat(POINTS, axis=0), rest)
    best = {name: math.inf for name in cases}
    for _ in range(args.rounds):
        for name, (rows, rest) in cases.items():
            best[name] = min(best[name], _per_period(rows, rest) * 1e6)
    print(f"CPU: {cpu_model()}; best of {args.rounds} rounds, one thread\n")
    print("| variant | us per point and period | / rigid stop |\n| --- | ---: | ---: |")
    for name, us in best.items():
        print(f"| {name} | {us:.3g} | {us / best['rigid stop']:.2f} |")


if __name__ == "__main__":
    main()
