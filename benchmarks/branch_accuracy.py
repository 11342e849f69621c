"""Branch cost of meeting the accuracy target (issue 45): continuation before and after,
in one process, runs alternated.

    python -m benchmarks.branch_accuracy --before COMMIT [--rounds 3] [--output NAME.md]

``COMMIT``'s ``harvester_sweep/continuation.py`` is loaded beside today's as a module of
the same package (the same engine, compiled once), and both follow the paper S-curve
(gap 1 um, 150-300 Hz), a gap branch of the paper scene through both folds (240 Hz,
0.5-3 um), the strong-coupling frequency branch switched onto its doubled branches
(gap 3 um, 150-135 Hz, ``period_doubling="switch"``) and the Neimark-Sacker branch of a
stop on a spring (tests/physics/test_branch_accuracy.py's NS_BRANCH) in turn, each round
all; each figure is the best of the rounds (this machine
is shared, and its speed drifts from minute to minute: compare within one run). Reported:
wall time of the branch (the Dataset left out: ``_continue``), points, points whose
estimate is above ``accuracy``, the largest estimate, the flagged bifurcations whose
shift is above ``accuracy`` relative to their value (or NaN: not located at another
step), and each located bifurcation with its reported shift and steps.

Writes benchmarks/results/NAME.md (branch_accuracy_45b.md unless told).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
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
RESULTS = ROOT / "benchmarks" / "results"
#: The stop on a spring of the Neimark-Sacker case: 2.5 g on a 100 Hz support, 1 % damping.
_STOP = dict(stop_mass=2.5e-3, stop_support_stiffness=2.5e-3 * (2 * math.pi * 100.0) ** 2,
             stop_support_damping=2 * 0.01 * 2.5e-3 * 2 * math.pi * 100.0,
             hertz_stiffness=9.03e8)
CASES = {
    "paper S-curve, gap 1 um, 150-300 Hz": ("paper", "frequency", 150.0, 300.0,
                                            {"gap": 1e-6}, "mark"),
    "paper gap branch, 240 Hz, 0.5-3 um": ("paper", "gap", 0.5e-6, 3e-6,
                                           {"frequency": 240.0}, "mark"),
    "strong coupling, gap 3 um, 150-135 Hz, switch": ("strong_coupling", "frequency", 150.0,
                                                      135.0, {"gap": 3e-6}, "switch"),
    "stop on a spring, gap 2 um, 155-160 Hz (NS)": ("paper", "frequency", 155.0, 160.0,
                                                    {"gap": 2e-6, **_STOP}, "mark"),
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
    preset, parameter, start, stop, fixed, doubling = case
    spec = module.check_continuation(preset, parameter, start, stop,
                                     **{k: module.DEFAULTS[k] for k in (
                                         "step", "min_step", "max_step", "max_points")},
                                     period_doubling=doubling, fixed=dict(fixed))
    began = time.perf_counter()
    branch = module._continue(spec)
    return time.perf_counter() - began, branch, spec


def _summary(branch, spec, accuracy):
    error = np.array([pt.error for pt in branch.points])
    kinds = list(BIFURCATIONS)
    located = [f"{kinds[pt.bifurcation]} {pt.lam:.10g} ({pt.shift:+.2g}, "
               f"{getattr(pt, 'steps', spec.steps)} steps)"
               for pt in branch.points if pt.bifurcation]
    # located bifurcations whose shift (relative to the value) is above the target
    shifted = sum(1 for pt in branch.points if pt.bifurcation and not
                  abs(pt.shift) <= accuracy * (abs(pt.lam) or abs(spec.stop - spec.start)))
    if len(located) > 4:  # (a switched branch locates dozens)
        located = located[:4] + [f"... {len(located)} in all on {len(branch.stops)} branches"]
    return (len(branch.points), int(np.sum(~(error <= accuracy))), float(np.nanmax(error)),
            f"{shifted} of {sum(1 for pt in branch.points if pt.bifurcation)}",
            "; ".join(located))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", required=True, help="the commit to compare with")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--output", default="branch_accuracy_45b.md",
                        help="file name under benchmarks/results")
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
             f"--rounds {args.rounds} --output {args.output}`", "",
             f"CPU: {_cpu()}, {len(os.sched_getaffinity(0))} cores, shared with other "
             "work while measured: compare within this run only. Before: continuation.py "
             f"of {args.before}, loaded beside today's in one process; runs alternated, each "
             "the best of the rounds (the branch alone, without its Dataset).", "",
             "| branch | code | wall time [s] (rounds) | points | above accuracy | "
             "largest estimate | shifts above (NaN counted) | located (shift, steps) |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | --- |"]
    for case in CASES:
        for name in modules:
            t = times[name, case]
            points, above, worst, shifted, located = out[name, case]
            lines.append(f"| {case} | {name} | {min(t):.2f} ("
                         + ", ".join(f"{v:.2f}" for v in t) + f") | {points} | {above} | "
                         f"{worst:.2g} | {shifted} | {located} |")
        ratio = min(times["after", case]) / min(times["before", case])
        lines.append(f"| {case} | after / before | {ratio:.2f} | | | | | |")
    (RESULTS / args.output).write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
