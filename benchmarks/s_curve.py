"""The paper scene's S-curve (gap 1 um, 150-300 Hz): continuation against up/down sweeps.

    python -m benchmarks.s_curve [--rounds 3] [--spacings 1 0.1 0.01]

- ``continue_branch`` over 150-300 Hz (the issue's speed target: under 10 s on 2 cores):
  wall time (best of the rounds, the engine compiled beforehand), points, the located folds
  and grazing, each with the width of its bracket;
- up and down sweeps (``run_sweep``, the state continued along frequency, no error
  estimate) over the same range at the same step per period, one per spacing: wall time,
  and the frequencies between which each sweep leaves its branch, against the located
  folds. A sweep brackets a band edge to its spacing at best; the time for the spacing
  that would bracket it as tightly as the continuation locates it is extrapolated from
  the finest sweep's time per point.

Writes benchmarks/results/s_curve.md.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from benchmarks.steady_states import _cpu
from harvester_sweep import continue_branch, run_sweep
from harvester_sweep._engine import STATUS, warm_up
from harvester_sweep.outputs import BIFURCATIONS

ROOT = Path(__file__).resolve().parents[1]
RESULT = ROOT / "benchmarks" / "results" / "s_curve.md"
START, STOP, GAP = 150.0, 300.0, 1e-6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--spacings", type=float, nargs="+", default=[1.0, 0.1, 0.01])
    args = parser.parse_args()
    warm_up()
    times = []
    for _ in range(args.rounds):
        began = time.perf_counter()
        branch = continue_branch("paper", "frequency", START, STOP, gap=GAP)
        times.append(time.perf_counter() - began)
    kinds = list(BIFURCATIONS)
    lines = [f"# S-curve of the paper scene (gap {GAP:g} m, {START:g}-{STOP:g} Hz)", "",
             f"`python -m benchmarks.s_curve --rounds {args.rounds} --spacings "
             + " ".join(f"{s:g}" for s in args.spacings) + "`", "",
             f"CPU: {_cpu()}, {len(__import__('os').sched_getaffinity(0))} cores", "",
             "## Continuation", "",
             f"`continue_branch`: {branch.sizes['point']} points in "
             + ", ".join(f"{t:.2f}" for t in times) + f" s (best {min(times):.2f} s), "
             f"{int(branch.attrs['steps_per_period'])} steps per period.", "",
             "| located | frequency [Hz] | bracket [Hz] | shift at 2x steps [Hz] | x_max [m] |",
             "| --- | ---: | ---: | ---: | ---: |"]
    folds = []
    for i in np.flatnonzero(branch["bifurcation"].values):
        kind = kinds[int(branch["bifurcation"][i])]
        f = float(branch["frequency"][i])
        if kind == "fold":
            folds.append(f)
        lines.append(f"| {kind} | {f:.9f} | {float(branch['frequency_precision'][i]):.1e} | "
                     f"{float(branch['frequency_shift'][i]):+.1e} | "
                     f"{float(branch['x_max'][i]):.6e} |")
    low, high = sorted(folds)
    precision = max(float(branch["frequency_precision"][i])
                    for i in np.flatnonzero(branch["bifurcation"].values))
    lines += ["", "## Up and down sweeps at the same step", "",
              "| spacing [Hz] | points | wall time [s] | up leaves the upper branch | "
              "down leaves the lower branch |", "| ---: | ---: | ---: | --- | --- |"]
    per_point = None
    for spacing in args.spacings:
        num = int(round((STOP - START) / spacing)) + 1
        began = time.perf_counter()
        ds = run_sweep({"preset": "paper",
                        "parameters": {"gap": GAP, "max_periods": 20000,
                                       "steps_per_period": int(branch.attrs["steps_per_period"])},
                        "grid": {"frequency": {"start": START, "stop": STOP, "num": num}},
                        "sweep": {"directions": ["up", "down"], "outputs": ["x_max"],
                                  "error_estimate": "none"}}, progress=False)
        wall = time.perf_counter() - began
        per_point = wall / (2 * num)
        f = ds["frequency"].values
        cells = []
        for direction, fold, window in (("up", high, (240.0, 270.0)),
                                        ("down", low, (210.0, 230.0))):
            x = ds["x_max"].sel(direction=direction).values
            # (a point that did not settle is on neither branch: it is listed, not counted)
            settled = ds["status"].sel(direction=direction).values == STATUS.settled
            near = (f > window[0]) & (f < window[1])
            inside = np.flatnonzero(near & settled)
            jump = np.flatnonzero(np.diff(x[inside] > 1.1 * GAP))
            if jump.size != 1:
                cells.append(f"{jump.size} jumps in {window[0]:g}-{window[1]:g} Hz")
                continue
            a, b = f[inside][jump[0]], f[inside][jump[0] + 1]
            unsettled = f[near & ~settled]
            cells.append(f"{a:.3f}-{b:.3f} Hz (fold {fold:.5f}: "
                         + ("inside" if a < fold < b else "outside") + ")"
                         + (f", not settled at {', '.join(f'{u:.3f}' for u in unsettled)} Hz"
                            if unsettled.size else ""))
        lines.append(f"| {spacing:g} | {2 * num} | {wall:.2f} | {cells[0]} | {cells[1]} |")
    needed = 2 * ((STOP - START) / precision + 1)
    lines += ["", f"A sweep that brackets the band edges to the continuation's widest bracket "
              f"({precision:.1e} Hz) needs {needed:.2e} points; at the finest sweep's "
              f"{per_point * 1e3:.2f} ms a point that is {needed * per_point / 3600:.1f} h, "
              f"against {min(times):.2f} s for the whole branch with its unstable part, "
              "multipliers, error estimates and grazing.", ""]
    RESULT.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
