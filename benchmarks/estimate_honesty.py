"""How right ``error_estimate`` is: each settled point's outputs against the same orbit at
REFERENCE times its steps per period, by configuration.

    python -m benchmarks.estimate_honesty [--cases NAME ...] [--output FILE.md]

Each case is a grid of points from rest (``CASES``), solved as a sweep solves them
(automatic step, error estimate on). Each settled point is then run again at REFERENCE
times its final steps per period, from its orbit, whose own error is REFERENCE^-4 of the
point's. The error is the estimate's own measure (``accuracy.halving_error``) of the
point's outputs against that run. With RK4's fourth order the error is about 16/15 of the
estimate (``ERROR_PER_ESTIMATE``), so the table gives error / (16/15 estimate), for points
clear of the stops and points with impacts apart: its median, 90th percentile and
largest, how many points are above 2 and above 5, and how many err by more than their
``accuracy``. The worst points are listed after the table. A point whose reference run
ends on another orbit period is left out and counted.
"""

from __future__ import annotations

import argparse

import numpy as np

from benchmarks.variants import provenance, report
from harvester_sweep._engine import METRIC, PARAM, STATUS
from harvester_sweep.accuracy import ERROR_PER_ESTIMATE, halving_error
from harvester_sweep.packing import Packed, pack_points
from harvester_sweep.parameters import resolve_parameters
from harvester_sweep.results import solve

#: The reference runs take this many times a point's steps per period [-].
REFERENCE = 8
#: Worst points listed after the table, per case.
WORST = 3

_F = np.linspace(100.0, 250.0, 31)  # [Hz]
_G = np.linspace(0.5e-6, 4e-6, 8)  # [m]
#: name: (preset, the points' parameters).
CASES = {
    "paper": ("paper", [dict(gap=g, frequency=f) for g in _G for f in _F]),
    "two stops": ("paper", [dict(gap=g, lower_gap=g, frequency=f) for g in _G for f in _F]),
    "latched law": ("paper", [dict(gap=g, frequency=f, impact_velocity_mode="latched")
                              for g in _G for f in _F]),
    "strong coupling, loads": ("strong_coupling", [dict(gap=2e-6, frequency=f, resistance=r)
                                                   for r in (1e3, 1e4, 1e5, 1e6) for f in _F]),
    "restitution 0.5": ("paper", [dict(gap=g, frequency=f, restitution=0.5)
                                  for g in _G for f in _F]),
    "moving stop": ("paper", [dict(gap=g, frequency=f, stop_mass=5e-3,
                                   stop_support_stiffness=1e5, stop_support_damping=1.0)
                              for g in _G[::2] for f in _F]),
    "accuracy 1e-9": ("paper", [dict(gap=g, frequency=f, accuracy=1e-9)
                                for g in _G[::2] for f in _F]),
    "other contact laws": ("paper", [dict(gap=2e-6, frequency=f, contact_law=law)
                                     for law in ("hunt_crossley", "flores", "gonthier")
                                     for f in _F]),
}


def measure(preset: str, points: list) -> dict:
    """Error over (16/15) estimate of the settled points of ``points`` (parameter dicts of
    ``preset``), with what the table and the worst points need."""
    values = [resolve_parameters(preset, **{k: (v if isinstance(v, str) else float(v))
                                            for k, v in p.items()}) for p in points]
    packed = pack_points(values)
    run = solve(packed, estimated=np.ones(len(values), dtype=bool))
    rows = packed.rows.copy()
    rows[:, PARAM.steps] = REFERENCE * run.steps
    reference = solve(Packed(rows, run.finals.copy(), packed.refused,
                             np.full(len(values), np.nan), packed.max_steps))
    m, fine = run.metrics, reference.metrics
    error = np.array([halving_error(m[i], fine[i]) for i in range(len(values))])
    estimated = (m[:, METRIC.status] == STATUS.settled) & np.isfinite(run.errors)
    same = fine[:, METRIC.orbit_period] == m[:, METRIC.orbit_period]
    impacts = (m[:, METRIC.impacts_per_period] > 0) | (m[:, METRIC.impacts_per_period_lower] > 0)
    accuracy = np.array([p["accuracy"] for p in values])
    return {"ratio": error / (ERROR_PER_ESTIMATE * run.errors), "error": error,
            "estimate": run.errors, "steps": run.steps, "accuracy": accuracy,
            "kept": estimated & same, "left_out": int((estimated & ~same).sum()),
            "impacts": impacts, "points": points}


def lines_of(name: str, r: dict) -> tuple[list, list]:
    """The case's table rows and its worst points (Markdown)."""
    rows, worst = [], []
    for label, mask in (("clear of the stops", r["kept"] & ~r["impacts"]),
                        ("with impacts", r["kept"] & r["impacts"])):
        if not mask.any():
            continue
        q = r["ratio"][mask]
        rows.append(f"| {name} | {label} | {mask.sum()} | {np.median(q):.3g} | "
                    f"{np.quantile(q, 0.9):.3g} | {q.max():.3g} | {(q > 2).sum()} | "
                    f"{(q > 5).sum()} | {(r['error'][mask] > r['accuracy'][mask]).sum()} |")
    for i in np.argsort(-np.where(r["kept"], r["ratio"], -np.inf))[:WORST]:
        if r["kept"][i]:
            point = ", ".join(f"{k} {v}" if isinstance(v, str) else f"{k} {v:.4g}"
                              for k, v in r["points"][i].items())
            worst.append(f"- {name}: {point}; {r['steps'][i]:.0f} steps a period: "
                         f"estimate {r['estimate'][i]:.3g}, error {r['error'][i]:.3g}")
    if r["left_out"]:
        worst.append(f"- {name}: {r['left_out']} points left out (their reference run ends "
                     "on another orbit period)")
    return rows, worst


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    parser.add_argument("--output", default=None)
    args = parser.parse_args()
    table = ["| case | points | n | median | 90th percentile | largest | above 2 | above 5 | "
             "error above accuracy |", "| --- | --- | ---: | ---: | ---: | ---: | ---: | "
             "---: | ---: |"]
    worst = []
    for name in args.cases:
        rows, points = lines_of(name, measure(*CASES[name]))
        table += rows
        worst += points
    report([f"# error_estimate against runs at {REFERENCE} times the steps", "",
            provenance(), "", "Error over 16/15 of the estimate:", ""] + table
           + ["", "The worst points:", ""] + worst, args.output)


if __name__ == "__main__":
    main()
