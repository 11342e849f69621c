"""The beam's 64 x 64 gap x frequency grid, run whole: wall time, CPU use and what the
points did, for the rigid stop and the rod.

    python -m benchmarks.beam_grid [--stops rigid,rod] [--output benchmarks/results/beam_grid.md]

The grid is benchmarks/cases.py's (gap 0.25-4 um, 100-250 Hz, 64 x 64), every point from
rest, at the presets' own budget of periods and accuracy, run as a user
runs it: a sweep file of ``model = "beam"`` through ``beam_cluster.run_beam_file`` in this
process (chunks of points, each solved in one parallel call, each saved as it finishes).
One run per stop, after one point that loads (or compiles) the engine. 'CPU / wall': the
process's CPU time over its wall time (2: both cores busy all along). The machine's load
average before and after each run is written with it: a shared machine's other work takes
cores from the run.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.cases import GRID
from benchmarks.variants import provenance
from harvester_sweep.beam_cluster import run_beam_file

ROOT = Path(__file__).resolve().parents[1]
STOPS = {"rigid": ("rigid stop (bimorph_tip)", "bimorph_tip", {}),
         "rod": ("rod, 5 rod modes (mak_rod)", "mak_rod", {"rod_modes": 5})}


def _sweep(preset: str, fixed: dict, grid: dict) -> dict:
    return {"model": "beam", "preset": preset, "parameters": fixed, "grid": grid}


def run_stop(preset: str, fixed: dict) -> dict:
    """The whole grid of one stop: its wall and CPU time and the points' outcomes."""
    run_beam_file(_sweep(preset, fixed, {"frequency": [140.0]}))  # (the engine loaded)
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as folder:
        start, cpu = time.perf_counter(), time.process_time()
        ds = run_beam_file(_sweep(preset, fixed, GRID), Path(folder) / "grid.nc")
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    status, periods = ds["status"].values, ds["periods_run"].values
    lost = status != 0
    estimate = ds["error_estimate"].values[~lost]
    return {"points": status.size, "wall": wall, "cpu": cpu, "load": (load,
            os.getloadavg()[0]), "not_settled": int(lost.sum()),
            "share": float(periods[lost].sum() / periods.sum()),
            "periods": float(periods.mean()), "max_periods": int(ds.attrs[
                "parameter_max_periods"]), "above": int((estimate > 1e-7).sum())}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--stops", default="rigid,rod",
                        help="which grids, comma-separated: rigid, rod")
    parser.add_argument("--output", type=Path,
                        default=ROOT / "benchmarks/results/beam_grid.md")
    args = parser.parse_args(argv)
    command = "python -m benchmarks.beam_grid" + ("" if args.stops == "rigid,rod" else
                                                   f" --stops {args.stops}")
    lines = ["# The beam's 64 x 64 grid, run whole", "",
             f"Command: `{command}` (benchmarks/beam_grid.py; its docstring says what is "
             f"measured). {provenance()} One run per stop.", "",
             "| stop | points | max_periods | wall time [s] | CPU / wall | ms / point | "
             "not settled | their share of periods_run | mean periods_run | settled above "
             "1e-7 | load average before, after |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
    for key in args.stops.split(","):
        label, preset, fixed = STOPS[key]
        r = run_stop(preset, fixed)
        lines.append(f"| {label} | {r['points']} | {r['max_periods']} | {r['wall']:.0f} | "
                     f"{r['cpu'] / r['wall']:.2f} | {r['wall'] / r['points'] * 1e3:.1f} | "
                     f"{r['not_settled']} | {r['share']:.0%} | {r['periods']:.0f} | "
                     f"{r['above']} | {r['load'][0]:.1f}, {r['load'][1]:.1f} |")
        print(lines[-1], flush=True)
        args.output.parent.mkdir(parents=True, exist_ok=True)
        args.output.write_text("\n".join(lines) + "\n", encoding="utf-8")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
