"""The tip-mass model on each of the two engines: what the specialised lane engine is worth.

    python -m benchmarks.engines [--side 24] [--rounds 3] [--output FILE]

The one-mode beam at its tip (``bimorph_tip``, ``n_modes = 1``) is the tip-mass model:
three states (the mode, its rate, the voltage), one Hertz stop. The modal engine, which
runs any linear system with contact surfaces, solves it as the beam
(``beam_runs.beam_sweep``); the lane engine solves the same model, written as the reduced
tip-mass parameters (``bimorph.as_tip_mass_parameters``), as a sweep (``run_sweep``). The
same gap x frequency grid on both, every point from its linear steady state, at the
presets' accuracy (1e-7), both threads; the runs alternate and each time is the best of
the rounds. The two engines' outputs are compared point by point: their difference
against the sum of the two error estimates.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numba
import numpy as np

from benchmarks.variants import cpu_model, report
from harvester_sweep import bimorph as bm
from harvester_sweep import run_sweep
from harvester_sweep.beam_parameters import bimorph, resolve_beam_parameters
from harvester_sweep.beam_runs import beam_sweep

GAP = (0.25e-6, 4e-6)  # [m]
FREQUENCY = (180.0, 300.0)  # [Hz]: both folds of the one-mode beam's response


def _grid(side: int) -> dict:
    return {"gap": np.linspace(*GAP, side), "frequency": np.linspace(*FREQUENCY, side)}


def modal(grid: dict):
    return beam_sweep(grid, "bimorph_tip", n_modes=1)


def lanes(grid: dict, reduced: dict):
    fixed = {k: v for k, v in reduced.items() if k not in grid}
    spec = {"preset": "paper", "parameters": fixed,
            "grid": {k: [float(x) for x in v] for k, v in grid.items()},
            "sweep": {"outputs": ["power", "v_peak", "x_max"]}}
    return run_sweep(spec, progress=False)


def agreement(a, b) -> tuple[int, list]:
    """Points settled on both, and each where the power differs by more than twice the sum
    of the two estimates (plus 1e-12): its gap [m], frequency [Hz], relative difference,
    that over the two estimates, and each engine's x_max [m] (apart where the two settled
    on different orbits of a point that has two)."""
    ok = (a["status"].values == 0) & (b["status"].values == 0)
    pa, pb = a["power"].values, b["power"].values
    estimates = a["error_estimate"].values + b["error_estimate"].values
    rel = np.abs(pa - pb) / np.abs(pb)
    outside = ok & (rel > 2 * estimates + 1e-12)
    return int(ok.sum()), [(a["gap"].values[i], a["frequency"].values[j], rel[i, j],
                            rel[i, j] / estimates[i, j], a["x_max"].values[i, j],
                            b["x_max"].values[i, j]) for i, j in zip(*np.nonzero(outside))]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--side", type=int, default=24)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--output")
    args = parser.parse_args(argv)
    grid = _grid(args.side)
    reduced = bm.as_tip_mass_parameters(bimorph(resolve_beam_parameters("bimorph_tip",
                                                                          n_modes=1)))
    runs = {"modal engine (one-mode beam)": lambda: modal(grid),
            "lane engine (reduced tip-mass model)": lambda: lanes(grid, reduced)}
    load = [os.getloadavg()[0]]
    results = {name: run() for name, run in runs.items()}  # (compile, and the outputs)
    best = dict.fromkeys(runs, math.inf)
    for _ in range(args.rounds):
        for name, run in runs.items():
            start = time.perf_counter()
            run()
            best[name] = min(best[name], time.perf_counter() - start)
    load.append(os.getloadavg()[0])
    points = args.side ** 2
    lane = best["lane engine (reduced tip-mass model)"]
    lines = [f"# The tip-mass model on the two engines ({args.side} x {args.side} points)", "",
             f"Machine: {cpu_model()}, {numba.get_num_threads()} threads; load average "
             f"{load[0]:.2f} before, {load[1]:.2f} after.", "",
             f"Command: python -m benchmarks.engines --side {args.side} --rounds "
             f"{args.rounds}", "",
             "| engine | best of rounds [s] | ms per point | / lane engine |",
             "| --- | ---: | ---: | ---: |"]
    for name, t in best.items():
        lines.append(f"| {name} | {t:.3f} | {1e3 * t / points:.3f} | {t / lane:.2f} |")
    settled, outside = agreement(*results.values())
    lines += ["", f"Points settled on both: {settled} of {points}; the power differs by more "
              f"than twice the sum of the two estimates at {len(outside)}:", "",
              "| gap [um] | frequency [Hz] | relative difference | / sum of estimates | "
              "x_max modal [um] | x_max lanes [um] |", "|" + " ---: |" * 6]
    lines += [f"| {1e6 * g:.3f} | {f:.2f} | {r:.2e} | {q:.1f} | {1e6 * xa:.4f} | "
              f"{1e6 * xb:.4f} |" for g, f, r, q, xa, xb in outside]
    report(lines, args.output)


if __name__ == "__main__":
    main()
