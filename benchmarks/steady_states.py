"""Steady states by transient integration (a checkout before the periodic-orbit solver)
against periodic orbits (this checkout), in one process, runs alternated.

    git worktree add /tmp/before 12842c4
    python -m benchmarks.steady_states /tmp/before .   [--rounds 3] [--chunks 5]

Figures (each time the best of the rounds, the two checkouts run in turn so that they see
the same drift of this shared machine):

- 64 x 64 gap x frequency sweeps (paper scene, 1024 steps per period, every point from rest,
  no error estimate), end to end through ``run_sweep``: the grid of benchmarks/cases.py and
  the one issue 19 measured (2658 of its points never touch the stop):
  wall time, RK4 steps (Jacobian copies included after), time per settled point, how
  far the two agree where both settled, and what of the time after was the engine's
  calls and what the solver's Python between them;
- single scenes at the default accuracy (1e-7): the paper scene, a lightly damped
  resonance and a 1 GOhm load, the last two against the closed form;
- chunks of 4096 points spread over examples/million_points.toml, each checkout with its
  own defaults (error estimate on a sample of 64 points before, on every point after):
  wall time and status counts, extrapolated to the 1e6 points.

Writes benchmarks/results/steady_states.md.
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from benchmarks.cases import GRID, STEPS_PER_PERIOD, sweep_spec
from benchmarks.compare import _load
from benchmarks.engine_calls import EngineCalls
from tests.helpers import phasor

ROOT = Path(__file__).resolve().parents[1]
RESULT = ROOT / "benchmarks" / "results" / "steady_states.md"
GRIDS = {
    "64 x 64 gap x frequency sweep of benchmarks/cases.py (0.25-4 um, 100-250 Hz)": GRID,
    "64 x 64 gap x frequency sweep of issue 19 (0-10 um, 100-300 Hz)":
        {"gap": {"start": 0.0, "stop": 10e-6, "num": 64},
         "frequency": {"start": 100, "stop": 300, "num": 64}},
}
SCENES = {
    "paper scene": {},
    "lightly damped resonance (zeta 0.002, 150 Hz, no stop in reach)":
        {"damping_ratio": 0.002, "frequency": 150.0, "gap": 1.0},
    "1 GOhm load (no stop in reach)": {"resistance": 1e9, "gap": 1.0},
}


def _cpu() -> str:
    out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    for line in out.splitlines():
        if line.startswith("Model name"):
            return line.split(":", 1)[1].strip()
    return "unknown"


def _best(runs: dict, rounds: int, work) -> dict:
    """``work(tag, hs)`` for each checkout in turn, ``rounds`` times; best time of each and
    the result of that run."""
    best = {}
    for _ in range(rounds):
        for tag, hs in runs.items():
            start = time.perf_counter()
            out = work(tag, hs)
            elapsed = time.perf_counter() - start
            if tag not in best or elapsed < best[tag][0]:
                best[tag] = (elapsed, out)
    return best


def _sweep_with_calls(spec):
    """``work`` for _best: a checkout's ``run_sweep`` of ``spec``, and for the checkout
    after, the spans of its engine calls (EngineCalls)."""
    def work(tag, hs):
        if tag != "after":
            return hs.run_sweep(spec, progress=False), None
        with EngineCalls(__import__(hs.__name__ + "._engine", fromlist=["x"])) as calls:
            return hs.run_sweep(spec, progress=False), calls
    return work


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--chunks", type=int, default=5)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    into = Path(tempfile.mkdtemp())
    sys.path.insert(0, str(into))
    runs = {"before": _load("a", args.before, into), "after": _load("b", args.after, into)}
    for hs in runs.values():  # compile or load each engine outside the timings
        hs.run_scene("paper")
    lines = ["# Steady states: transient integration before, periodic orbits after",
             "", f"- command: `python -m benchmarks.steady_states {args.before} "
             f"{args.after} --rounds {args.rounds} --chunks {args.chunks}`",
             f"- machine: {_cpu()}, 2 cores; each time the best of {args.rounds}, "
             "the two checkouts alternated in one process", ""]

    for title, grid in GRIDS.items():
        spec = sweep_spec(grid)
        spec["sweep"]["outputs"] = [*spec["sweep"]["outputs"], "impacts_per_period"]
        res = _best(runs, args.rounds, _sweep_with_calls(spec))
        (t0, (a, _)), (t1, (b, calls)) = res["before"], res["after"]
        steps_a = float(a.periods_run.sum()) * STEPS_PER_PERIOD
        steps_b = float(b.rk4_steps.sum())
        settled_a, settled_b = int((a.status == 0).sum()), int((b.status == 0).sum())
        both = (a.status == 0) & (b.status == 0) & (a.orbit_period == b.orbit_period)
        diff = float((abs(a.power - b.power) / abs(a.power)).where(both).max())
        free = ((a.status == 0) & (b.status == 0) & (a.impacts_per_period == 0)
                & (b.impacts_per_period == 0))
        free_a = float(a.periods_run.where(free).sum()) * STEPS_PER_PERIOD
        free_b = float(b.rk4_steps.where(free).sum())
        lines += [f"## {title}, paper scene, 1024 steps per period, from rest", "",
                  "| | before | after | before / after |", "| --- | ---: | ---: | ---: |",
                  f"| wall time, run_sweep end to end | {t0:.2f} s | {t1:.2f} s | "
                  f"**{t0 / t1:.1f} x** |",
                  f"| RK4 steps (after: Newton's copies included) | {steps_a:.3g} | "
                  f"{steps_b:.3g} | {steps_a / steps_b:.1f} x |",
                  f"| ... of the {int(free.sum())} points settled off the stop in both | "
                  f"{free_a:.3g} | {free_b:.3g} | {free_a / free_b:.0f} x |",
                  f"| settled points | {settled_a} | {settled_b} | |",
                  f"| wall time per settled point | {1e3 * t0 / settled_a:.3f} ms | "
                  f"{1e3 * t1 / settled_b:.3f} ms | {t0 / settled_a / (t1 / settled_b):.1f} x |",
                  ] + ([
                  f"| after's wall time in its {len(calls.spans)} engine calls (before / it) | "
                  f"| {calls.seconds:.2f} s | {t0 / calls.seconds:.1f} x |",
                  f"| ... in the solver's Python between them (before / end to end less it) | "
                  f"| {calls.between:.2f} s | {t0 / (t1 - calls.between):.1f} x |",
                  ] if calls.spans else [  # (a compiled solver calls the engine from compiled code)
                  "| after's engine calls | | not seen: its solver calls the engine from "
                  "compiled code | |"]) + [
                  "", f"Largest relative difference of `power` where both settled on orbits "
                  f"of the same period ({int(both.sum())} points): {diff:.1e}.", ""]

    lines += ["## Single scenes at the default accuracy (1e-7)", "",
              "| scene | before: time, periods, steps/period, error estimate | after: time, "
              "periods of the motion, RK4 steps, steps/period, error estimate | error against "
              "the closed form before / after |", "| --- | --- | --- | --- |"]
    for name, overrides in SCENES.items():
        res = _best(runs, 5, lambda tag, hs: hs.run_scene("paper", **overrides))
        (t0, a), (t1, b) = res["before"], res["after"]
        ma, mb = a.metrics, b.metrics
        exact = ""
        if overrides.get("gap") == 1.0:
            X, V = phasor(**b.parameters)
            power = abs(V) ** 2 / (2 * b.parameters["resistance"])
            exact = (f"{abs(ma['power'] / power - 1):.1e} / "
                     f"{abs(mb['power'] / power - 1):.1e}")
        lines.append(
            f"| {name} | {1e3 * t0:.1f} ms, {ma['periods_run']}, {ma['steps_per_period']}, "
            f"{ma['error_estimate']:.1e} | {1e3 * t1:.1f} ms, {mb['periods_run']}, "
            f"{mb['rk4_steps']:,}, {mb['steps_per_period']}, {mb['error_estimate']:.1e} | "
            f"{exact} |")
    lines.append("")

    million = ROOT / "examples" / "million_points.toml"
    picks = None
    rows = []
    totals = {"before": 0.0, "after": 0.0}
    for tag, hs in runs.items():
        sweep_file = __import__(hs.__name__ + ".sweep_file", fromlist=["x"])
        chunks = __import__(hs.__name__ + ".chunks", fromlist=["x"])
        spec = sweep_file.load_sweep(million)
        picks = np.linspace(0, spec.n_chunks - 1, args.chunks).round().astype(int)
        for k in picks:
            start = time.perf_counter()
            c = chunks.compute_chunk(spec, int(k))
            elapsed = time.perf_counter() - start
            status = c["metrics"][..., list(spec.metrics).index("status")].ravel()
            totals[tag] += elapsed
            rows.append((tag, int(k), elapsed, np.bincount(status.astype(int), minlength=4)))
    n_chunks = spec.n_chunks
    lines += ["## examples/million_points.toml, a sample of its chunks", "",
              f"{args.chunks} of its {n_chunks} chunks of 4096 points, spread evenly, each "
              "checkout with its defaults (before: error estimate on ~64 points of the grid; "
              "after: on every point, each meeting the accuracy target). Run one after the "
              "other, not alternated.", "",
              "| checkout | chunk | time | settled / not settled / diverged |",
              "| --- | ---: | ---: | --- |"]
    lines += [f"| {tag} | {k} | {t:.1f} s | {s[0]} / {s[1]} / {s[2]} |" for tag, k, t, s in rows]
    lines += ["", "Extrapolated to the whole sweep (time of the sample x chunks / sample): "
              + ", ".join(f"{tag} {math.ceil(totals[tag] * n_chunks / args.chunks / 60)} min"
                          for tag in totals), ""]
    lines += _bounds(runs, args.rounds, million)
    lines += _by_kind(runs, args.rounds)
    text = "\n".join(lines)
    print(text)
    RESULT.write_text(text)


def _alone(tag: str, hs, points: list, estimate: bool) -> tuple:
    """``points`` (parameter dicts) solved alone by checkout ``hs``, as its sweeps run a
    point (before: the transient engine; after: the periodic-orbit solver, with an error
    estimate on every point if ``estimate``): wall time [s] (packing not included) and
    RK4 steps."""
    engine = __import__(hs.__name__ + "._engine", fromlist=["x"])
    packed = __import__(hs.__name__ + ".packing", fromlist=["x"]).pack_points(points)
    n = len(points)
    start = time.perf_counter()
    if tag == "before":
        metrics = np.empty((n, len(engine.METRIC)))
        engine.run_points(packed.rows, packed.states.copy(), metrics, np.empty((n, 0, 3)))
        elapsed = time.perf_counter() - start
        return elapsed, float((metrics[:, engine.METRIC.periods_run]
                               * packed.rows[:, engine.PARAM.steps]).sum())
    results = __import__(hs.__name__ + ".results", fromlist=["x"])
    solved = results.solve(packed, estimated=np.full(n, estimate))
    return time.perf_counter() - start, float(solved.rk4_steps.sum())


def _bounds(runs: dict, rounds: int, million: Path) -> list:
    """What bounds the gains: the engine's rate with and without contact in uniform runs
    (this checkout), and the points of the 1e6 sweep's chunk 0 that never settle, solved
    alone by each checkout, with how long its settled points took to settle."""
    hs = runs["after"]
    engine = __import__(hs.__name__ + "._engine", fromlist=["x"])
    packing = __import__(hs.__name__ + ".packing", fromlist=["x"])
    rates = {}
    for gap in (1e-6, 1.0):
        packed = packing.pack_points([hs.resolve_parameters("paper", gap=gap,
                                                            steps_per_period=1024)] * 1024)
        rows = packed.rows.copy()
        rows[:, engine.PARAM.max_periods] = 16
        metrics = np.empty((1024, len(engine.METRIC)))
        best = math.inf
        for _ in range(rounds):
            start = time.perf_counter()
            engine.run_points(rows, packed.states.copy(), metrics, np.empty((1024, 0, 3)),
                              settle=False)
            best = min(best, time.perf_counter() - start)
        rates[gap] = 1024 * 16 * 1024 / best
    lines = ["## What bounds the gains", "",
             "Uniform runs of this checkout's engine, 1024 points of the paper scene at 1024 "
             "steps a period, 16 periods each, no steady-state test (best of "
             f"{rounds}): {rates[1e-6]:.3g} RK4 steps/s at gap 1 um (contact), "
             f"{rates[1.0]:.3g} at gap 1 m.", ""]

    sweep_file = __import__(hs.__name__ + ".sweep_file", fromlist=["x"])
    results = __import__(hs.__name__ + ".results", fromlist=["x"])
    spec = sweep_file.load_sweep(million)
    points = [spec.point_parameters(spec.values_at(i))
              for i in range(spec.lines_per_chunk * spec.line_length)]
    solved = results.solve(packing.pack_points(points), estimated=np.ones(len(points), bool))
    status = solved.metrics[:, engine.METRIC.status]
    motion = solved.metrics[:, engine.METRIC.periods_run]
    settled = status == engine.STATUS.settled
    stuck = [p for p, s in zip(points, status) if s == engine.STATUS.not_settled]
    times = {tag: _alone(tag, other, stuck, True)[0] for tag, other in runs.items()}
    lines += [f"Chunk 0 of examples/million_points.toml ({len(points)} points): "
              f"{len(stuck)} do not settle within their budget; solved alone they take "
              f"{times['before']:.1f} s before and {times['after']:.1f} s after. Of its "
              f"{int(settled.sum())} settled points, {int((settled & (motion > 300)).sum())} "
              f"needed more than 300 periods of motion and "
              f"{int((settled & (motion > 500)).sum())} more than 500.", ""]
    return lines


def _by_kind(runs: dict, rounds: int) -> list:
    """The issue grid's points by what they do (after: settled off the stop, settled with
    contact, not settled), each kind solved alone by each checkout (_alone: no resolving
    or datasets): where the time before went, and what is left."""
    hs = runs["after"]
    grid = GRIDS["64 x 64 gap x frequency sweep of issue 19 (0-10 um, 100-300 Hz)"]
    spec = __import__(hs.__name__ + ".sweep_file", fromlist=["x"]).load_sweep(sweep_spec(grid))
    points = [spec.point_parameters(spec.values_at(i)) for i in range(spec.n_lines)]
    engine = __import__(hs.__name__ + "._engine", fromlist=["x"])
    after = __import__(hs.__name__ + ".results", fromlist=["x"]).solve(
        __import__(hs.__name__ + ".packing", fromlist=["x"]).pack_points(points))
    status = after.metrics[:, engine.METRIC.status]
    impacts = after.metrics[:, engine.METRIC.impacts_per_period]
    kinds = {"all": np.ones(len(status), bool),
             "settled off the stop": (status == 0) & (impacts == 0),
             "settled with contact": (status == 0) & (impacts > 0),
             "not settled": status != 0}
    lines = ["## The issue grid's points by kind, each kind solved alone", "",
             "The points of the issue's 64 x 64 grid by what they do after, each kind solved "
             "alone by each checkout (engine and solver only: no resolving, packing or "
             f"datasets; best of {rounds}, alternated). The kinds do not add up to all: "
             "solved alone, a kind fills the engine's lanes less well.", "",
             "| points | n | before: time, RK4 steps | after: time, RK4 steps | before / after |",
             "| --- | ---: | ---: | ---: | ---: |"]
    for name, mask in kinds.items():
        chosen = [p for p, m in zip(points, mask) if m]
        res = _best(runs, rounds, lambda tag, hs: _alone(tag, hs, chosen, False))
        (t0, (_, s0)), (t1, (_, s1)) = res["before"], res["after"]
        lines.append(f"| {name} | {int(mask.sum())} | {t0:.3f} s, {s0:.3g} | {t1:.3f} s, "
                     f"{s1:.3g} | {t0 / t1:.1f} x |")
    return lines + [""]


if __name__ == "__main__":
    main()
