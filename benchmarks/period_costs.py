"""Where a forcing period's time goes in the lane engine, and how a small solve's rounds use
the threads.

    python -m benchmarks.period_costs [--output FILE] [--rounds 7]

Issue 47 asks the orbit solver for a per-point time that is below what the engine's calls
alone take. This measures what those calls are made of:

- *A period's cost, split.* 64 points of the paper scene for 60 periods (no settling), one
  thread, at 512, 1024 and 2048 steps per period: the time per point and period is fitted
  by a line, ``fixed + steps * per_step``. The slope is the cost of a plain RK4 step (the
  vector loop); the intercept what a period costs whatever its steps: the steps finished
  in scalar code (contact switches located, graded sub-steps and quarter steps next to a
  touch or a separation, extrema and force peaks placed, the period's end and the
  steady-state test's books). Two cases: the stop 1 um away at 130-150 Hz (an impact a
  period), and out of reach (gap 1 m); each booking every metric (``PARAM.book`` 1, as a
  run whose metrics are read) and booking none but the end state (0, as Newton's copies).
- *A solve's rounds.* The paper point solved from rest, 64 copies (the per-point case of
  benchmarks/test_speed.py), at accuracy 1e-5 and 1e-7: each round's wall time on one
  thread and on numba's threads, and its RK4 steps against the engine's ``SHORT_CALL``
  (a call with fewer runs on one thread).

Best of ``--rounds`` runs after an uncounted one.
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np

from benchmarks.variants import best, provenance, report
from harvester_sweep import orbits, packing, results, run_scene
from harvester_sweep._engine import METRIC, PARAM, scheduler
from harvester_sweep.parameters import resolve_parameters
from harvester_sweep.period_map import run_lanes

POINTS, PERIODS = 64, 60
STEPS = (512, 1024, 2048)
CASES = {"stop 1 um away, 130-150 Hz (an impact a period)": 1e-6,
         "stop out of reach (gap 1 m)": 1.0}
ACCURACIES = (1e-5, 1e-7)


def _rows(gap: float, steps: int, book: float):
    rows = [resolve_parameters("paper", gap=gap, frequency=float(f), steps_per_period=steps,
                               max_periods=PERIODS, settle_tolerance=1e-300)
            for f in np.linspace(130.0, 150.0, POINTS)]
    packed = packing.pack_points(rows)
    packed.rows[:, PARAM.book] = book
    return packed.rows, packed.states


def _per_period(rows, states, rounds) -> tuple[float, float]:
    """(best time per point and period [s], mean impacts per period)."""
    metrics = np.empty((len(rows), len(METRIC)))

    def run():
        run_lanes(rows, states.copy(), metrics, np.empty((len(rows), 0, 3)), 1,
                  np.empty((0, 0, 0)))  # (no point carries its monodromy)
        return metrics[:, METRIC.periods_run].sum(), metrics[:, METRIC.impacts_per_period].mean()

    seconds, (periods, impacts) = best(run, rounds)
    return seconds / periods, impacts


def _costs(rounds) -> list:
    lines = ["## A period's cost, split (one thread)", "",
             "Time per point and period at each step count, and the line through them: "
             "fixed (per period) + steps x per step.", "",
             "| case | metrics booked | " + " | ".join(f"{s} steps [us]" for s in STEPS)
             + " | per step [ns] | fixed per period [us] | impacts per period |",
             "| --- | --- | " + " | ".join("---:" for _ in STEPS) + " | ---: | ---: | ---: |"]
    for case, gap in CASES.items():
        for book, booked in ((1.0, "every metric"), (0.0, "end state alone")):
            runs = [_per_period(*_rows(gap, s, book), rounds) for s in STEPS]
            t = np.array([r[0] for r in runs])
            slope, intercept = np.polyfit(STEPS, t, 1)
            lines.append(f"| {case} | {booked} | "
                         + " | ".join(f"{x * 1e6:.2f}" for x in t)
                         + f" | {slope * 1e9:.2f} | {intercept * 1e6:.2f} "
                         f"| {runs[0][1]:.2f} |")
    return lines


class _Timed:
    """orbits._rounds timed, one round a call (solve_orbits given on_points): each round's
    wall time and RK4 steps."""

    def __init__(self):
        self.rounds = []

    def __enter__(self):
        self._saved = saved = orbits._rounds

        def timed(pts, threads, one):
            steps = pts.work.sum()
            start = time.perf_counter()
            out = saved(pts, threads, one)
            self.rounds.append((time.perf_counter() - start, pts.work.sum() - steps))
            return out

        orbits._rounds = timed
        return self

    def __exit__(self, *exc):
        orbits._rounds = self._saved


def _solve_rounds(accuracy, threads, rounds) -> list:
    """Each round's best wall time [s] and its RK4 steps, solving the paper point's 64
    copies at ``accuracy`` on ``threads`` threads."""
    p = run_scene("paper", accuracy=accuracy).parameters
    packed = packing.pack_points([p] * POINTS)
    estimated = np.ones(POINTS, dtype=bool)
    numba.set_num_threads(threads)
    fastest = None
    for k in range(rounds + 1):
        with _Timed() as timed:
            orbits.solve_orbits(packed.rows, packed.states, None, estimated, packed.accuracy,
                                packed.max_steps, 0, on_points=lambda done: None)
        if k > 0:
            fastest = timed.rounds if fastest is None else [
                (min(a[0], b[0]), a[1]) for a, b in zip(fastest, timed.rounds)]
    return fastest


def _rounds_table(rounds) -> list:
    most = numba.get_num_threads()
    lines = ["## A solve's rounds", "",
             f"The paper point from rest, {POINTS} copies, error estimate on (as "
             "benchmarks/test_speed.py's per-point case): each round's best wall time on "
             f"one thread and on {most}, and its RK4 steps (the engine call's budget; below "
             f"SHORT_CALL = {scheduler.SHORT_CALL:,} the call runs on one thread).", ""]
    for accuracy in ACCURACIES:
        one = _solve_rounds(accuracy, 1, rounds)
        many = _solve_rounds(accuracy, most, rounds)
        numba.set_num_threads(most)
        lines += [f"Accuracy {accuracy:g}:", "",
                  f"| round | RK4 steps | 1 thread [ms] | {most} threads [ms] | ratio |",
                  "| ---: | ---: | ---: | ---: | ---: |"]
        for k, ((t1, steps), (tn, _)) in enumerate(zip(one, many)):
            lines.append(f"| {k + 1} | {int(steps):,} | {t1 * 1e3:.3f} | {tn * 1e3:.3f} "
                         f"| {t1 / tn:.2f} |")
        t1, tn = sum(r[0] for r in one), sum(r[0] for r in many)
        lines += [f"| all | {int(sum(r[1] for r in one)):,} | {t1 * 1e3:.3f} "
                  f"| {tn * 1e3:.3f} | {t1 / tn:.2f} |", ""]
    return lines


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output")
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args(argv)
    results.compile_solver()
    most = numba.get_num_threads()
    numba.set_num_threads(1)
    lines = ["# Where a period's time goes, and a small solve's rounds", "",
             f"{provenance()} Command: python -m benchmarks.period_costs "
             f"--rounds {args.rounds}", ""]
    lines += _costs(args.rounds) + [""]
    numba.set_num_threads(most)
    lines += _rounds_table(args.rounds)
    report(lines, args.output)


if __name__ == "__main__":
    main()
