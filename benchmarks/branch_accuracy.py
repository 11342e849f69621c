"""Branch cost of meeting the accuracy target (issue 45): continuation before and after,
in one process, runs alternated.

    python -m benchmarks.branch_accuracy --before COMMIT [--rounds 3] [--output NAME.md]

``COMMIT``'s ``harvester_sweep/continuation.py`` is loaded beside today's as a module of
the same package (the same engine, compiled once), and both follow the paper S-curve
(gap 1 um, 150-300 Hz), a gap branch of the paper scene through both folds (240 Hz,
0.5-3 um), the strong-coupling frequency branch switched onto its doubled branches
(gap 3 um, 150-135 Hz, ``period_doubling="switch"``) and the Neimark-Sacker branch of a
stop on a spring (tests/physics/test_neimark_sacker_accuracy.py's NS_BRANCH) in turn, each round
all; each figure is the best of the rounds (this machine
is shared, and its speed drifts from minute to minute: compare within one run). Reported:
wall time of the branch (the Dataset left out: ``_continue``), points, points whose
estimate is above ``accuracy``, the largest estimate, the flagged bifurcations whose
shift is above ``accuracy`` relative to their value (or NaN: not located at another
step), and each located bifurcation with its reported shift and steps.

With ``--scan``, the Neimark-Sacker point of that branch and the strong-coupling
period doubling near 145.32 Hz (gap 3 um, 150-140 Hz) are also located again at each of
``SCAN_STEPS`` steps per period from where the branch located them (before its
refinement), by both codes, and their distance from the SciPy references' (``REFERENCES``)
is tabled. With ``--moves``, the monodromy of each period doubling and Neimark-Sacker
point that today's code locates on those branches and on the switched strong-coupling
branch (before refinement) is taken by five-point differences over each of ``MOVES``: the
scaled disagreement of its two central differences and its test function are tabled.

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

#: The cases of --scan: the Neimark-Sacker branch and the strong-coupling branch through
#: one period doubling (NS_BRANCH of tests/physics/test_neimark_sacker_accuracy.py, and
#: PD_BRANCH of tests/physics/test_branch_accuracy.py).
SCAN = {
    "stop on a spring, gap 2 um, 155-160 Hz (NS)": CASES[
        "stop on a spring, gap 2 um, 155-160 Hz (NS)"] + ("neimark_sacker",),
    "strong coupling, gap 3 um, 150-140 Hz (PD)": ("strong_coupling", "frequency", 150.0,
                                                   140.0, {"gap": 3e-6}, "mark",
                                                   "period_doubling"),
}
#: Where the SciPy references of tests/physics/test_branch_accuracy.py (and of
#: test_neimark_sacker_accuracy.py) put those
#: bifurcations [Hz]: the NS point's secant on its pair's modulus (MovingStopMap), the
#: doubling's on det(I + M) (reference_period_doubling).
REFERENCES = {"neimark_sacker": 158.0037239231, "period_doubling": 145.3200585540}
#: Moves of the --moves monodromies, relative to the component scales [-].
MOVES = (1e-2, 5e-3, 1.25e-3, 3e-4, 8e-5, 2e-5)
#: Steps per period the --scan locations are taken at [-].
SCAN_STEPS = (1088, 1392, 2096, 2608, 3296, 4160, 5248, 6608, 8336, 10496, 13232, 17856)


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


def _scan(module, case):
    """The bifurcation of ``case`` located by ``module`` on its branch, then again at each
    of SCAN_STEPS: its steps and value as the branch located it, and the values found
    (NaN: not found)."""
    kind = case[-1]
    problem, point = _located(module, case[:6], (kind,))[0]
    k = list(module.TESTED).index(kind)
    values = []
    for steps in SCAN_STEPS:
        other = module._relocate(problem, point, k, steps)
        values.append(math.nan if other is None else other.lam)
    return point.steps, point.lam, values


def _located(module, case, kinds):
    """The problem and the bifurcations of ``kinds`` ``module`` locates on ``case``'s
    branches, before their refinement."""
    flags = [list(BIFURCATIONS).index(kind) for kind in kinds]
    found = []

    def keep(problem, point, accuracy, max_steps):
        if point.bifurcation in flags and point.located:
            found.append((problem, point))
        return point

    accurate, module._accurate = module._accurate, keep
    try:
        _run(module, case)
    finally:
        module._accurate = accurate
    return found


def _moves(case):
    """Lines of the --moves table for ``case``'s doublings and Neimark-Sacker points."""
    lines = []
    kinds = continuation.MULTIPLIER_TESTED
    for problem, point in _located(continuation, case, kinds):
        kind = list(BIFURCATIONS)[point.bifurcation]
        cells = []
        for h in MOVES:
            point.precise = None
            got = problem.multipliers(point, h)
            if got is None:
                cells.append("diverged")
                continue
            test = continuation._multiplier_tests(got[0])[kinds.index(kind)]
            cells.append(f"{got[1]:.1e} / {test:+.1e}")
        point.precise = None
        lines.append(f"| {kind} {point.lam:.6f} | {point.period} | {point.steps} | "
                     + " | ".join(cells) + " |")
    return lines


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
    parser.add_argument("--scan", action="store_true",
                        help="also locate the NS point and a period doubling at SCAN_STEPS")
    parser.add_argument("--moves", action="store_true",
                        help="also table the doublings' and NS points' monodromies at MOVES")
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
             f"--rounds {args.rounds} --output {args.output}"
             + (" --scan" if args.scan else "") + (" --moves`" if args.moves else "`"), "",
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
    if args.scan:
        lines += ["", "Located again at each step per period from the branch's location "
                  "(before its refinement): the distance from the reference's [Hz].", "",
                  "| bifurcation | code | at the branch's step | "
                  + " | ".join(str(n) for n in SCAN_STEPS) + " |",
                  "| --- | --- | --- | " + " | ".join("---:" for _ in SCAN_STEPS) + " |"]
        for case, spec in SCAN.items():
            reference = REFERENCES[spec[-1]]
            for name, module in modules.items():
                steps, value, values = _scan(module, spec)
                lines.append(f"| {case} | {name} | {value - reference:+.2g} ({steps}) | "
                             + " | ".join(f"{v - reference:+.2g}" for v in values) + " |")
    if args.moves:
        lines += ["", "Each doubling's and Neimark-Sacker point's monodromy over moves of h "
                  "of the scales (today's code's locations, before refinement): the largest "
                  "scaled entry of the difference of the central differences over h and 2h, "
                  "and the test function (det(I + M), or |mu|^2 - 1 of the outermost pair).",
                  "", "| bifurcation [Hz] | period | steps | "
                  + " | ".join(f"h = {h:g}" for h in MOVES) + " |",
                  "| --- | ---: | ---: | " + " | ".join("---" for _ in MOVES) + " |"]
        for case in ("stop on a spring, gap 2 um, 155-160 Hz (NS)",
                     "strong coupling, gap 3 um, 150-135 Hz, switch"):
            lines += _moves(CASES[case])
    (RESULTS / args.output).write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
