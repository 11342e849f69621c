"""Branch cost of meeting the accuracy target (issue 45): continuation before and after,
in one process, runs alternated.

    python -m benchmarks.branch_accuracy --before COMMIT [--rounds 3]

``COMMIT``'s ``harvester_sweep/continuation.py`` is loaded beside today's as a module of
the same package (the same engine, compiled once), and both follow the paper S-curve
(gap 1 um, 150-300 Hz) and a gap branch of the paper scene through both folds (240 Hz,
0.5-3 um) in turn, each round both; each figure is the best of the rounds (this machine
is shared, and its speed drifts from minute to minute: compare within one run). Reported:
wall time of the branch (the Dataset left out: ``_continue``), points, points whose
estimate is above ``accuracy``, the largest estimate, and each located bifurcation with
its reported change at twice the steps.

Writes benchmarks/results/branch_accuracy_45.md.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.steady_states import _cpu
from harvester_sweep import continuation
from harvester_sweep._engine import warm_up
from harvester_sweep.outputs import BIFURCATIONS

ROOT = Path(__file__).resolve().parents[1]
RESULT = ROOT / "benchmarks" / "results" / "branch_accuracy_45.md"
CASES = {
    "paper S-curve, gap 1 um, 150-300 Hz": ("paper", "frequency", 150.0, 300.0,
                                            {"gap": 1e-6}),
    "paper gap branch, 240 Hz, 0.5-3 um": ("paper", "gap", 0.5e-6, 3e-6,
                                           {"frequency": 240.0}),
}


def _before(commit: str):
    """continuation.py of ``commit``, as a module of today's package."""
    source = subprocess.run(["git", "show", f"{commit}:harvester_sweep/continuation.py"],
                            cwd=ROOT, check=True, capture_output=True, text=True).stdout
    name = "harvester_sweep._continuation_before"
    spec = importlib.util.spec_from_loader(name, loader=None)
    module = importlib.util.module_from_spec(spec)
    module.__package__ = "harvester_sweep"
    sys.modules[name] = module
    exec(compile(source, f"{commit}:continuation.py", "exec"), module.__dict__)
    return module


def _run(module, case):
    preset, parameter, start, stop, fixed = case
    spec = module.check_continuation(preset, parameter, start, stop,
                                     **{k: module.DEFAULTS[k] for k in (
                                         "step", "min_step", "max_step", "max_points",
                                         "period_doubling")}, fixed=dict(fixed))
    began = time.perf_counter()
    branch = module._continue(spec)
    return time.perf_counter() - began, branch, spec


def _summary(branch, spec, accuracy):
    error = np.array([pt.error for pt in branch.points])
    kinds = list(BIFURCATIONS)
    located = [f"{kinds[pt.bifurcation]} {pt.lam:.10g} ({pt.shift:+.2g}, "
               f"{getattr(pt, 'steps', spec.steps)} steps)"
               for pt in branch.points if pt.bifurcation]
    return (len(branch.points), int(np.sum(~(error <= accuracy))), float(np.nanmax(error)),
            "; ".join(located))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", required=True, help="the commit to compare with")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    warm_up()
    modules = {"before": _before(args.before), "after": continuation}
    times = {(name, case): [] for name in modules for case in CASES}
    out = {}
    for _ in range(args.rounds):
        for case, spec in CASES.items():
            for name, module in modules.items():
                took, branch, checked = _run(module, spec)
                times[name, case].append(took)
                out[name, case] = _summary(branch, checked, checked.base["accuracy"])
    lines = ["# Branch cost of the accuracy target (issue 45)", "",
             f"`python -m benchmarks.branch_accuracy --before {args.before} "
             f"--rounds {args.rounds}`", "",
             f"CPU: {_cpu()}, {len(os.sched_getaffinity(0))} cores, shared with other "
             "work while measured: compare within this run only. Before: continuation.py "
             f"of {args.before}, loaded beside today's in one process; runs alternated, each "
             "the best of the rounds (the branch alone, without its Dataset).", "",
             "| branch | code | wall time [s] (rounds) | points | above accuracy | "
             "largest estimate | located (shift at 2x steps, steps) |",
             "| --- | --- | ---: | ---: | ---: | ---: | --- |"]
    for case in CASES:
        for name in modules:
            t = times[name, case]
            points, above, worst, located = out[name, case]
            lines.append(f"| {case} | {name} | {min(t):.2f} ("
                         + ", ".join(f"{v:.2f}" for v in t) + f") | {points} | {above} | "
                         f"{worst:.2g} | {located} |")
        ratio = min(times["after", case]) / min(times["before", case])
        lines.append(f"| {case} | after / before | {ratio:.2f} | | | | |")
    RESULT.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
