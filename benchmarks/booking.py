"""What booking the metrics costs, in one process, runs alternated.

    python -m benchmarks.booking [--rounds 5]

- One thread, the per-point cases of benchmarks/compare.py, each point run booking
  every metric (PARAM.book 1) and booking none of its extrema and force peaks (0, as a
  Newton iterate's perturbed copies run): microseconds per point and period.
- The 64 x 64 sweep of benchmarks/cases.py on all threads, storing ``power`` alone and
  storing every metric: M RK4 steps per second.
- Where the RK4 steps of the 64 x 64 sweeps go (stop in reach and out of reach, with and
  without an error estimate): Newton iterates, their perturbed copies (which book
  nothing), and the motion with the estimates.

Best of the rounds; the machine's CPU model heads the tables.
"""

from __future__ import annotations

import argparse
import math
import time
from types import SimpleNamespace

import numba

import harvester_sweep as hs
from benchmarks.cases import FREE, GRID, STEPS_PER_PERIOD, sweep_spec
from benchmarks.compare import POINTS, _per_period, _points
from benchmarks.variants import cpu_model
from benchmarks.work import Tally
from harvester_sweep import _engine, orbits
from harvester_sweep._engine import PARAM
from harvester_sweep.packing import initial_state, pack_parameters
from harvester_sweep.sweep_file import METRIC_OUTPUTS


def _sweep_rate(outputs) -> float:
    spec = sweep_spec(GRID)
    spec["sweep"]["outputs"] = list(outputs)
    start = time.perf_counter()
    ds = hs.run_sweep(spec, None, progress=False)
    return int(ds.rk4_steps.sum()) / (time.perf_counter() - start) / 1e6


def _shares(grid, estimate: str, parameters: dict | None = None) -> dict:
    """Fractions of a sweep's RK4 steps run by the Newton iterates (their centre lanes),
    their perturbed copies (where the monodromy is not carried along the run) and the
    rest (motion, estimates), as the orbit solver books them (``orbits.WORK``), from every
    solve of the sweep (work.Tally); ``parameters`` set beside the grid's."""
    counts = dict.fromkeys(("Newton iterates", "perturbed copies", "motion and estimates"), 0.0)
    kinds = dict(zip(orbits.WORK, ("motion and estimates", "Newton iterates",
                                   "perturbed copies", "perturbed copies",
                                   "motion and estimates")))
    spec = sweep_spec(grid)
    spec["sweep"]["error_estimate"] = estimate
    spec["parameters"].update(parameters or {})
    with Tally() as tally:
        hs.run_sweep(spec, None, progress=False)
    for kind, steps in tally.steps.items():
        counts[kinds[kind]] += steps
    total = sum(counts.values())
    return {name: n / total for name, n in counts.items()}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    hs.api = SimpleNamespace(pack_parameters=pack_parameters, initial_state=initial_state,
                             run_points=_engine.run_points, n_metrics=len(_engine.METRIC))
    cases = {name: _points(hs, *case) for name, case in POINTS.items()}
    sweeps = {"power alone": ["power"], "every metric": list(METRIC_OUTPUTS)}
    threads = numba.get_num_threads()
    _sweep_rate(["power"])  # compile
    best: dict = {}
    for _ in range(args.rounds):
        numba.set_num_threads(1)
        for name, (rows, rest) in cases.items():
            for book in (1.0, 0.0):
                rows[:, PARAM.book] = book
                key = (name, book)
                best[key] = min(best.get(key, math.inf), _per_period(hs, rows, rest) * 1e6)
        numba.set_num_threads(threads)
        for name, outputs in sweeps.items():
            best[name] = max(best.get(name, 0.0), _sweep_rate(outputs))
    print(f"CPU: {cpu_model()}; best of {args.rounds} rounds\n")
    print("| one thread [us per point and period] | every metric | no extrema or peaks "
          "| ratio |\n| --- | ---: | ---: | ---: |")
    for name in cases:
        a, b = best[name, 1.0], best[name, 0.0]
        print(f"| {name} | {a:.3g} | {b:.3g} | {b / a:.3f} |")
    print(f"\n| 64 x 64 sweep at {STEPS_PER_PERIOD} steps, {threads} threads [M RK4 steps/s] "
          "| M steps/s |\n| --- | ---: |")
    for name in sweeps:
        print(f"| {name} | {best[name]:.3g} |")
    print("\n| 64 x 64 sweep | Newton iterates | perturbed copies | motion and estimates |"
          "\n| --- | ---: | ---: | ---: |")
    for label, grid in (("stop in reach", GRID), ("stop out of reach", FREE)):
        for estimate in ("none", "all"):
            shares = _shares(grid, estimate)
            print(f"| {label}, error_estimate {estimate} | "
                  + " | ".join(f"{100 * s:.0f} %" for s in shares.values()) + " |")


if __name__ == "__main__":
    main()
