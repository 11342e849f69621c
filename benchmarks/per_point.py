"""Per point against SciPy LSODA and JAX/diffrax, each timed in a process of its own, in turn.

    python -m benchmarks.per_point [--accuracy 1e-7] [--rounds 3]

test_speed.py times the engine, LSODA and diffrax one after the other in one process, each
its best of a few runs, so its ratios compare moments of a machine whose speed moves; and
it runs diffrax last, because XLA's threads stay busy for a while after a diffrax run
(conftest.py). Here each round runs the engine, LSODA and diffrax in turn, each in a fresh
process, and takes each ratio within the round:

- the engine: ``results.solve`` of 64 copies of the paper scene at ``--accuracy`` (its
  error estimate and multipliers included), as test_speed.py runs it: the best of
  ENGINE_ROUNDS solves a point on numba's default threads and on one, and its orbit's
  distance from the exact one (alternatives.paper_reference);
- LSODA and diffrax: transient integrations from rest at each tolerance, the best of
  ALTERNATIVE_ROUNDS at each, timed to the period from which it stays within the engine's
  distance (alternatives.matched_time), as test_speed.py times them.

It prints each round's ratios and their median, and the CPU model. A child process
(``--child``) prints its measurements as one line of JSON.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

import numpy as np

from benchmarks.alternatives import RTOLS, matched_time, paper_reference, state_error
from benchmarks.cases import ALTERNATIVE_ROUNDS, ENGINE_ROUNDS

ROOT = Path(__file__).resolve().parents[1]
ENSEMBLE = 64  # copies of the paper scene solved at once, as a sweep's points are


def _scene(accuracy: float) -> dict:
    """The paper scene's parameters at ``accuracy`` [-] (paper_reference's, unsolved)."""
    import harvester_sweep as hs

    return hs.resolve_parameters("paper", accuracy=accuracy)


def solve_round(packed, estimated, threads: int) -> dict:
    """One round of the engine's per-point timing: ``results.solve`` of ``packed`` on
    numba's ``threads`` threads and on one, each solved once untimed first (test_speed.py
    says why); the solve of each thread count, by thread count (its ``run_time`` the
    timed one). numba is left on ``threads`` threads."""
    import numba

    from harvester_sweep import results

    out = {}
    for n in sorted({threads, 1}):
        numba.set_num_threads(n)
        results.solve(packed, estimated=estimated)
        out[n] = results.solve(packed, estimated=estimated)
    numba.set_num_threads(threads)
    return out


def _engine(accuracy: float) -> dict:
    """The engine's best time a point [s] on numba's threads and on one, and its orbit's
    state (x [m], v [m/s], V [V])."""
    import numba

    from harvester_sweep import packing

    packed = packing.pack_points([_scene(accuracy)] * ENSEMBLE)
    estimated = np.ones(ENSEMBLE, dtype=bool)
    threads = numba.get_num_threads()
    times: dict = {}
    for _ in range(ENGINE_ROUNDS):
        for n, solved in solve_round(packed, estimated, threads).items():
            times.setdefault(n, []).append(solved.run_time / ENSEMBLE)
    return {"engine": min(times[threads]), "engine_1": min(times[1]), "threads": threads,
            "state": solved.finals[0, :3].tolist()}


def _alternative(kind: str, accuracy: float, periods: int) -> dict:
    """ALTERNATIVE_ROUNDS runs of ``kind`` at each of its tolerances, in turn: (rtol, time
    [s], states), of which matched_time takes each tolerance's best."""
    from benchmarks.alternatives import diffrax_ensemble, lsoda

    p = _scene(accuracy)
    runs = []
    for _ in range(ALTERNATIVE_ROUNDS):
        for rtol in RTOLS[kind]:
            if kind == "lsoda":
                seconds, states = lsoda(p, periods, rtol)
            else:
                seconds, states = diffrax_ensemble(p, periods, ENSEMBLE, rtol)
                states = states[ENSEMBLE // 2]
            runs.append((rtol, seconds, np.asarray(states).tolist()))
    return {"runs": runs}


def _child(kind: str, accuracy: float, periods: int) -> dict:
    """Run ``kind`` in a fresh process of this checkout; its JSON line."""
    out = subprocess.run(
        [sys.executable, "-m", "benchmarks.per_point", "--child", kind,
         "--accuracy", repr(accuracy), "--periods", str(periods)],
        cwd=ROOT, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(accuracy: float, rounds: int) -> None:
    from benchmarks.variants import cpu_model

    _, exact, periods = paper_reference(accuracy)
    rows = []
    for r in range(rounds):
        engine = _child("engine", accuracy, periods)
        error = state_error(np.array(engine["state"]), exact)
        row = {"round": r + 1, "engine": engine["engine"], "engine_1": engine["engine_1"],
               "threads": engine["threads"], "error": error}
        for kind in ("lsoda", "diffrax"):
            runs = [(rtol, seconds, np.array(states))
                    for rtol, seconds, states in _child(kind, accuracy, periods)["runs"]]
            row[kind], row[kind + "_how"] = matched_time(runs, exact, error)
        rows.append(row)
        print(f"round {r + 1}: engine {1e3 * row['engine']:.3f} ms a point on "
              f"{row['threads']} threads, {1e3 * row['engine_1']:.3f} on 1; LSODA "
              f"{1e3 * row['lsoda']:.2f} ms ({row['lsoda_how']}), diffrax "
              f"{1e3 * row['diffrax']:.2f} ms ({row['diffrax_how']})", flush=True)
    print(f"\nThe paper scene at accuracy {accuracy:g}, ensemble of {ENSEMBLE}; "
          f"{cpu_model()}; each side in a process of its own, in turn, each ratio within "
          "its round.\n")
    print("| round | engine [ms a point] | 1 thread | LSODA [ms] | x | x per core "
          "| diffrax [ms] | x | x per core |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for row in rows:
        e, e1 = row["engine"], row["engine_1"]
        print(f"| {row['round']} | {1e3 * e:.3f} | {1e3 * e1:.3f} | {1e3 * row['lsoda']:.1f} | "
              f"{row['lsoda'] / e:.0f} | {row['lsoda'] / e1:.0f} | {1e3 * row['diffrax']:.2f} | "
              f"{row['diffrax'] / e:.0f} | {row['diffrax'] / e1:.0f} |")
    median = {f"{k} {w}": statistics.median(row[k] / row[e] for row in rows)
              for k in ("lsoda", "diffrax") for w, e in (("x", "engine"), ("per core", "engine_1"))}
    print("\nmedians: " + ", ".join(f"{name} {value:.0f}" for name, value in median.items()))
    print(f"engine's distance from the exact orbit: {max(row['error'] for row in rows):.1e} "
          "(max over ATOL_SCALE)")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--accuracy", type=float, default=1e-7)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--child", choices=("engine", "lsoda", "diffrax"),
                        help=argparse.SUPPRESS)
    parser.add_argument("--periods", type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child == "engine":
        print(json.dumps(_engine(args.accuracy)))
    elif args.child:
        print(json.dumps(_alternative(args.child, args.accuracy, args.periods)))
    else:
        main(args.accuracy, args.rounds)
