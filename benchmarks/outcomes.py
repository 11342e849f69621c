"""Two outputs of one sweep, point by point: what a change to the solver changed.

    harvester-sweep run examples/million_points.toml --output BEFORE.nc --quiet
    (the change)
    harvester-sweep run examples/million_points.toml --output AFTER.nc --quiet
    python -m benchmarks.outcomes BEFORE.nc AFTER.nc [--output FILE.md]

Issue 47 asks of a faster solver the same results: every status and orbit period
unchanged, the metrics within their error estimates. This reports

- the statuses that changed, by direction, with the periods of motion each point ran
  before and after (a change of when attempts are made moves the verdict of points that
  settle, or not, near the end of their budget);
- the orbit periods that changed among the points settled in both;
- for power, v_peak, x_max and impacts_per_period (METRICS), where the sweep has them,
  among the points settled in both: the largest relative change, and how many changed by
  more than their error estimate (the larger of the two), and by more than both results
  can err within their estimates (ERROR_PER_ESTIMATE of each, summed: errors of opposite
  signs at two steps per period), where the sweep has one;
- the RK4 steps and the periods of motion run, by status, before and after.
"""

from __future__ import annotations

import argparse

import numpy as np
import xarray as xr

from benchmarks.variants import provenance, report
from harvester_sweep._engine import STATUS
from harvester_sweep.accuracy import ERROR_PER_ESTIMATE

#: Metrics compared point by point, where the sweep has them.
METRICS = ("power", "v_peak", "x_max", "impacts_per_period")


def compare(before: xr.Dataset, after: xr.Dataset) -> list[str]:
    """The report's lines (Markdown) for two outputs of the same sweep."""
    status_b, status_a = before.status.values.ravel(), after.status.values.ravel()
    run_b, run_a = before.periods_run.values.ravel(), after.periods_run.values.ravel()
    settled = STATUS.settled
    both = (status_b == settled) & (status_a == settled)
    lines = [f"{status_b.size:,} points; settled before {(status_b == settled).sum():,}, "
             f"after {(status_a == settled).sum():,}.", ""]
    lines += ["| status before -> after | points | periods of motion before (mean) | "
              "after (mean) |", "| --- | ---: | ---: | ---: |"]
    for b in np.unique(status_b):
        for a in np.unique(status_a):
            moved = (status_b == b) & (status_a == a)
            if a != b and moved.any():
                lines.append(f"| {STATUS._fields[int(b)]} -> {STATUS._fields[int(a)]} | "
                             f"{moved.sum():,} | {run_b[moved].mean():.1f} | "
                             f"{run_a[moved].mean():.1f} |")
    if status_b.size == (status_b == status_a).sum():
        lines.append("| none | 0 | - | - |")
    orbit_b, orbit_a = before.orbit_period.values.ravel(), after.orbit_period.values.ravel()
    lines += ["", f"Orbit periods changed among the points settled in both: "
              f"{(both & (orbit_b != orbit_a)).sum():,}.", ""]
    estimate = total = None
    if "error_estimate" in before and "error_estimate" in after:
        e_b, e_a = before.error_estimate.values.ravel(), after.error_estimate.values.ravel()
        estimate = np.fmax(e_b, e_a)[both]
        total = ERROR_PER_ESTIMATE * (e_b + e_a)[both]
    lines += ["| metric (settled in both) | largest relative change | changed by more than "
              "the error estimate | than both can err |", "| --- | ---: | ---: | ---: |"]
    for name in METRICS:
        if name not in before or name not in after:
            continue
        b, a = before[name].values.ravel()[both], after[name].values.ravel()[both]
        change = np.abs(a - b) / np.where(b != 0, np.abs(b), 1.0)
        beyond = "-" if estimate is None else f"{(change > estimate).sum():,}"
        either = "-" if total is None else f"{(change > total).sum():,}"
        lines.append(f"| {name} | {np.nanmax(change, initial=0.0):.2e} | {beyond} | "
                     f"{either} |")
    steps_b, steps_a = before.rk4_steps.values.ravel(), after.rk4_steps.values.ravel()
    lines += ["", "| points (status before) | RK4 steps before | after | after / before | "
              "periods of motion a point, before | after |",
              "| --- | ---: | ---: | ---: | ---: | ---: |"]
    for label, mask in (("settled", status_b == settled), ("not settled", status_b != settled),
                        ("all", np.ones_like(both))):
        sb, sa = steps_b[mask].sum(), steps_a[mask].sum()
        lines.append(f"| {label} | {sb:.4e} | {sa:.4e} | {sa / sb:.4f} | "
                     f"{run_b[mask].mean():.2f} | {run_a[mask].mean():.2f} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", help="the sweep's output before the change (netCDF)")
    parser.add_argument("after", help="... and after it")
    parser.add_argument("--output", default=None)
    args = parser.parse_args()
    with xr.open_dataset(args.before) as before, xr.open_dataset(args.after) as after:
        for name in ("status", "periods_run", "rk4_steps", "orbit_period"):
            if name not in before or name not in after:
                parser.error(f"{name}: both outputs must hold it (sweep outputs)")
        if before.status.shape != after.status.shape:
            parser.error("the outputs hold grids of different shapes: not one sweep")
        lines = compare(before, after)
        times = [f"{ds.attrs.get('run_time', float('nan')):.1f}" for ds in (before, after)]
    lines += ["", f"Run time recorded in the files [s]: before {times[0]}, after {times[1]} "
              "(one run each: this machine's speed drifts; see benchmarks.compare)."]
    report([f"# {args.before} against {args.after}", "", provenance(), ""] + lines,
           args.output)


if __name__ == "__main__":
    main()
