"""Compare the speed of two checkouts of harvester_sweep in one process, runs alternated.

    git worktree add /tmp/before <commit>
    python -m benchmarks.compare /tmp/before .   [--rounds 3]

This machine's speed drifts by 5-10 % from minute to minute, more than many a change
gains; two packages loaded side by side (as hs_a and hs_b, copied to a temporary folder)
and run in turn see the same drift, so their ratio is what a change did (a checkout
compared with itself gives 1.000). Each figure is the best of the rounds:

- the 64 x 64 gap x frequency sweep of benchmarks/test_speed.py, the same grid with
  the stop out of reach, and a 32 x 64 one swept up and down in frequency (each point
  from the state of the one before), on all threads: RK4 steps per second;
- one thread, 64 points for 60 periods (no settling): the paper scene in 64 identical
  lanes at 368 and 1168 steps per period (the steps of accuracies 1e-5 and 1e-7), and 64
  frequencies from 130 to 150 Hz at 1024 steps with the stop in reach and out of reach:
  microseconds per point and period.
"""

from __future__ import annotations

import argparse
import importlib
import shutil
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import numba
import numpy as np

from benchmarks.cases import FREE, GRID, HALF, STEPS_PER_PERIOD, sweep_spec

SWEEPS = {  # name: (grid, directions)
    "64 x 64 sweep [M steps/s]": (GRID, None),
    "64 x 64, stop out of reach [M steps/s]": (FREE, None),
    "32 x 64 swept up and down (continuation) [M steps/s]": (HALF, ["up", "down"]),
}
POINTS = {  # name: (steps per period, gap [m] or None for the preset's, spread frequencies)
    "paper, 368 steps, 64 identical lanes": (368, None, False),
    "paper, 1168 steps, 64 identical lanes": (1168, None, False),
    "paper, 1024 steps, 130-150 Hz": (1024, None, True),
    "stop out of reach, 1024 steps, 130-150 Hz": (1024, 1.0, True),
}
PERIODS = 60


def _load(tag: str, checkout: Path, into: Path):
    shutil.copytree(checkout / "harvester_sweep", into / f"hs_{tag}",
                    ignore=shutil.ignore_patterns("__pycache__"))
    return importlib.import_module(f"hs_{tag}")


def _api(hs) -> SimpleNamespace:
    """The engine's entry points in a checkout, before or after it became _engine/."""
    try:
        packing = importlib.import_module(hs.__name__ + ".packing")
        engine = importlib.import_module(hs.__name__ + "._engine")
        return SimpleNamespace(pack_parameters=packing.pack_parameters,
                               initial_state=packing.initial_state,
                               run_points=engine.run_points, n_metrics=len(engine.METRIC))
    except ModuleNotFoundError:  # a checkout from before harvester_sweep._engine
        kernel = importlib.import_module(hs.__name__ + ".kernel")
        lanes = importlib.import_module(hs.__name__ + ".lanes")
        return SimpleNamespace(pack_parameters=kernel.pack_parameters,
                               initial_state=kernel.initial_state, run_points=lanes.run_points,
                               n_metrics=kernel.NM)


def _sweep_rate(hs, grid, directions=None) -> float:
    start = time.perf_counter()
    ds = hs.run_sweep(sweep_spec(grid, directions), None, progress=False)
    return int(ds.periods_run.sum()) * STEPS_PER_PERIOD / (time.perf_counter() - start)


def _points(hs, steps, gap, spread):
    rows = []
    for f in np.linspace(130.0, 150.0, 64) if spread else [140.0] * 64:
        extra = {} if gap is None else {"gap": gap}
        p = hs.resolve_parameters("paper", steps_per_period=steps, frequency=float(f),
                                  max_periods=PERIODS, settle_tolerance=1e-300, **extra)
        rows.append(hs.api.pack_parameters(p))
    rest = np.repeat(hs.api.initial_state(p)[None, :], 64, axis=0)
    return np.array(rows), rest


def _per_period(hs, rows, rest) -> float:
    states, metrics = rest.copy(), np.empty((64, hs.api.n_metrics))
    start = time.perf_counter()
    hs.api.run_points(rows, states, metrics, np.empty((64, 0, 3)))
    return (time.perf_counter() - start) / (64 * PERIODS)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("a", type=Path, help="the checkout to compare with (a folder)")
    parser.add_argument("b", type=Path, help="the checkout compared (a folder)")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        sys.path.insert(0, tmp)
        mods = {"a": _load("a", args.a, Path(tmp)), "b": _load("b", args.b, Path(tmp))}
        for hs in mods.values():
            hs.api = _api(hs)
            _sweep_rate(hs, {"gap": [1e-6], "frequency": [140.0]})  # compile
        points = {(t, name): _points(hs, *case) for t, hs in mods.items()
                  for name, case in POINTS.items()}
        best: dict = {}
        threads = numba.get_num_threads()
        for _ in range(args.rounds):
            for t, hs in mods.items():
                for name, (grid, directions) in SWEEPS.items():
                    rate = _sweep_rate(hs, grid, directions) / 1e6
                    best[t, name] = max(best.get((t, name), 0.0), rate)
                numba.set_num_threads(1)
                for name in POINTS:
                    us = _per_period(hs, *points[t, name]) * 1e6
                    key = (t, name + " [us per point and period, 1 thread]")
                    best[key] = min(best.get(key, np.inf), us)
                numba.set_num_threads(threads)
    print(f"a: {args.a}\nb: {args.b}\nbest of {args.rounds} rounds\n")
    print("| measure | a | b | b / a |\n| --- | ---: | ---: | ---: |")
    for name in dict.fromkeys(name for _, name in best):
        a, b = best["a", name], best["b", name]
        print(f"| {name} | {a:.3g} | {b:.3g} | {b / a:.3f} |")


if __name__ == "__main__":
    main()
