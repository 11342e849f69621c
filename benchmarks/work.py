"""Where a solve's RK4 work goes: periods per point by what they were run for, and rounds.

    python -m benchmarks.work [--output FILE]

The least work a point needs (issue 47) is its motion until it nears its orbit, Newton's
runs and the monodromy the orbit is judged on, and the error estimate's runs at twice the
steps. This benchmark counts each, in forcing periods at the point's own steps per period
(a run at twice the steps counts twice), on:

- the paper scene from rest, one point, at accuracy 1e-7 and 1e-5 (``results.solve``, as
  a sweep point runs it: multipliers and error estimate included);
- the benchmark sweeps of benchmarks/cases.py: the 64 x 64 gap x frequency grid and the 32
  x 64 one swept up and down (1024 steps per period, no error estimate);
- the 64 x 64 grid at the automatic step with an error estimate on every point (the
  preset's accuracy, 1e-7).

The periodic-orbit solver books each point's steps by kind (``orbits.WORK``), read here
from every solve a sweep makes (``results.solve_orbits`` wrapped; the solver is not
changed). A sweep's run-time estimate solves a sample of its points first: it is run once
before the counting, and its sample (kept per process) is not counted.
"""

from __future__ import annotations

import argparse
import collections

import numpy as np

from benchmarks.cases import GRID, HALF, sweep_spec
from benchmarks.variants import cpu_model, report
from harvester_sweep import orbits, packing, parameters, results, run_sweep

KINDS = ("trajectory", "Newton centre (copies' and chord steps)", "forward copies",
         "central copies", "error estimate (twice the steps)")
assert len(KINDS) == len(orbits.WORK)


class Tally:
    """Wraps results.solve_orbits while active: the RK4 steps of every solve, by kind
    (orbits.WORK), and the rounds (engine calls) of the solves."""

    def __init__(self):
        self.steps = collections.Counter()
        self.rounds = 0

    def __enter__(self):
        tally, solve = self, results.solve_orbits
        self._saved = solve

        def counted(*args, **kwargs):
            out = solve(*args, **kwargs)
            for kind, steps in zip(orbits.WORK, out.work_by_kind.sum(axis=0)):
                tally.steps[kind] += float(steps)
            tally.rounds += int(out.rounds.max(initial=0))
            return out

        results.solve_orbits = counted
        return self

    def __exit__(self, *exc):
        results.solve_orbits = self._saved


def _point(accuracy: float):
    p = parameters.resolve_parameters("paper", accuracy=accuracy)
    packed = packing.pack_points([p])
    estimated = np.ones(1, dtype=bool)
    results.solve(packed, estimated=estimated)  # (compile)
    with Tally() as tally:
        solved = results.solve(packed, estimated=estimated)
    return tally, 1, int(solved.steps[0])


def _sweep(spec: dict):
    run_sweep(spec, progress=False)  # (compile, and the run-time estimate's sample)
    with Tally() as tally:
        ds = run_sweep(spec, progress=False)
    steps = spec["parameters"].get("steps_per_period")
    return tally, int(ds["status"].size), steps


def _automatic() -> dict:
    spec = sweep_spec(GRID)
    spec["parameters"] = {}
    spec["sweep"].pop("error_estimate")
    return spec


CASES = {
    "paper scene, one point, accuracy 1e-7": lambda: _point(1e-7),
    "paper scene, one point, accuracy 1e-5": lambda: _point(1e-5),
    "64 x 64 grid, 1024 steps, no estimate": lambda: _sweep(sweep_spec(GRID)),
    "32 x 64 up and down, 1024 steps, no estimate":
        lambda: _sweep(sweep_spec(HALF, ["up", "down"])),
    "64 x 64 grid, automatic step, estimate on every point": lambda: _sweep(_automatic()),
}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output")
    args = parser.parse_args(argv)
    lines = ["# RK4 work per point, by what it was run for", "",
             f"Machine: {cpu_model()}. Command: python -m benchmarks.work", "",
             "Forcing periods per point at 1024 steps per period (the paper point: at its own "
             "steps), by kind; rounds: the orbit solver's engine calls.", "",
             "| case | " + " | ".join(KINDS) + " | all | rounds |",
             "| --- |" + " ---: |" * (len(KINDS) + 2)]
    for name, case in CASES.items():
        tally, points, steps = case()
        per = (steps or 1024) * points
        cells = [f"{tally.steps[k] / per:.2f}" for k in orbits.WORK]
        lines.append(f"| {name} | " + " | ".join(cells)
                     + f" | {sum(tally.steps.values()) / per:.2f} | {tally.rounds} |")
    report(lines, args.output)


if __name__ == "__main__":
    main()
