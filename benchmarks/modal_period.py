"""The modal engine's cost of one forcing period, on an orbit with contact and on a motion
clear of the stops, for each beam preset.

    python -m benchmarks.modal_period [--output benchmarks/results/modal_period.md]

Each case is one point at its first steps (``beam_packing.first_steps``): the motion from
rest is run for SETTLE periods (its budget), then the period map alone
(``modal_map.map_states``, one thread) for PERIODS periods from where it got to, best of
ROUNDS runs; 'measured': the same periods through ``modal_map.measure``, which also books
the outputs' extrema, the power and the force's peak at every sample. 'clear of the
stops' puts the stop 1 m away: the same equations, no contact, each damped mode decaying
as exp(Re lam t) from the state the first run ended on.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numba
import numpy as np

from benchmarks.variants import provenance
from harvester_sweep import beam_runs, modal_map
from harvester_sweep.beam_parameters import resolve_beam_parameters

ROOT = Path(__file__).resolve().parents[1]
SETTLE, PERIODS, ROUNDS = 400, 200, 3
#: (label, preset, overrides): the rod in its 5 modes, as benchmarks.beam_grid runs it.
CASES = (("rigid stop (bimorph_tip), 136 Hz, gap 4 um", "bimorph_tip",
          {"frequency": 136.0, "gap": 4e-6}),
         ("rigid stop (bimorph_tip), 136 Hz, clear of the stops", "bimorph_tip",
          {"frequency": 136.0, "gap": 1.0}),
         ("rod, 5 rod modes (mak_rod), 110 Hz, gap 2 um", "mak_rod",
          {"frequency": 110.0, "gap": 2e-6, "rod_modes": 5}),
         ("rod, 5 rod modes (mak_rod), 110 Hz, clear of the stops", "mak_rod",
          {"frequency": 110.0, "gap": 1.0, "rod_modes": 5}))


def period_cost(preset: str, overrides: dict) -> dict:
    """One case: its state size, steps per period, impacts per period, us per period."""
    p = resolve_beam_parameters(preset, **overrides)
    group = beam_runs._Group([p], [beam_runs.system_of(p)], [None])
    pack = group.packs([0], 0, budget=[SETTLE])
    metrics, ends, _ = modal_map.run(pack, group.starts)
    best, booked = np.inf, np.inf
    for _ in range(ROUNDS):
        start = time.perf_counter()
        _, ok = modal_map.map_states(pack, ends, np.array([PERIODS]))
        best = min(best, time.perf_counter() - start)
        start = time.perf_counter()
        modal_map.measure(pack, ends, np.array([PERIODS]))
        booked = min(booked, time.perf_counter() - start)
    assert ok[0]
    D, S, K = pack[0].dims
    steps = pack[0].rrow[modal_map.RealFields(*modal_map.real_fields(D, S, K)).steps]
    return {"D": D, "steps": int(steps), "impacts": metrics[0, modal_map.modal.HEAD.impacts],
            "us": best / PERIODS * 1e6, "booked": booked / PERIODS * 1e6}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", type=Path,
                        default=ROOT / "benchmarks/results/modal_period.md")
    args = parser.parse_args(argv)
    numba.set_num_threads(1)
    lines = ["# The modal engine's cost of a forcing period", "",
             "Command: `python -m benchmarks.modal_period` (benchmarks/modal_period.py; its "
             f"docstring says what is measured). {provenance()} Best of {ROUNDS} runs of "
             f"{PERIODS} periods, one thread.", "",
             "| case | state size | grid steps / period | impacts / period | us / period | "
             "us / period, measured |",
             "| --- | ---: | ---: | ---: | ---: | ---: |"]
    for label, preset, overrides in CASES:
        r = period_cost(preset, overrides)
        lines.append(f"| {label} | {r['D']} | {r['steps']} | {r['impacts']:g} | "
                     f"{r['us']:.1f} | {r['booked']:.1f} |")
        print(lines[-1], flush=True)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text("\n".join(lines) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
