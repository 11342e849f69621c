"""Where the 1e6-point sweep's time goes: the points that never settle, and the orbit
solver's cost over the engine's own steps.

    harvester-sweep run examples/million_points.toml --output OUT.nc --quiet
    python -m benchmarks.million_split OUT.nc [--chunks 6] [--rounds 2] [--output FILE.md]

- From the sweep's output: the RK4 steps (``rk4_steps``) of the settled points and of the
  points that never settle, which run the whole budget (max_periods) whatever the solver.
- For ``--chunks`` of the sweep's chunks, evenly spaced, on one thread: the chunk solved as
  the sweep solves it (chunks.compute_chunk, its ``run_time``), and the engine alone
  (engine.run_points, no settling test) running each point as many periods, at its final
  step, as the solve ran in all: the solver's cost over the steps it asks for. The chunk
  again on all threads, for the threads' gain. Best of ``--rounds``.
- ``--sample`` points that never settle, at random: the engine alone running them through
  their budget, one thread: their rate.
- A projection to the whole sweep: its steps at the chunks' nanoseconds per step, on all
  threads at the chunks' gain; the same with the engine alone, the floor of any solver that
  asks for as many periods; and the never-settling points' steps at their engine rate, the
  part that no solver keeping their status can skip.
"""

from __future__ import annotations

import argparse

import numba
import numpy as np
import xarray as xr

from benchmarks.variants import best, provenance, report
from harvester_sweep import _engine
from harvester_sweep._engine import METRIC, PARAM, STATUS
from harvester_sweep.chunks import compute_chunk
from harvester_sweep.packing import pack_points
from harvester_sweep.sweep_file import load_sweep

SWEEP = "examples/million_points.toml"


def _chunk_points(spec, chunk: int) -> list:
    """The parameter dicts of a chunk's points, in the order the chunk runs them (the
    sweep has no continuation: a line is one point)."""
    lines = spec.chunk_lines(chunk)
    index = [axis.tolist() for axis in np.unravel_index(np.asarray(lines), spec.line_shape)]
    axes = [(a, spec.grid[a].tolist()) for a in spec.line_axes]
    return [spec.point_parameters({a: grid[j[i]] for (a, grid), j in zip(axes, index)})
            for i in range(len(lines))]


def _engine_alone(points: list, steps: np.ndarray, rk4_steps: np.ndarray) -> float:
    """Seconds the engine alone takes to run each point from rest for the periods its
    solve ran in all (rk4_steps / steps) at its final steps per period, on one thread."""
    packed = pack_points(points)
    rows = packed.rows.copy()
    rows[:, PARAM.steps] = steps
    rows[:, PARAM.max_periods] = np.maximum(1.0, np.round(rk4_steps / steps))
    rows[:, PARAM.tolerance] = 0.0  # (no settling: every point runs its periods)
    metrics = np.empty((len(rows), len(METRIC)))

    def run():
        _engine.run_points(rows, packed.states.copy(), metrics, np.empty((len(rows), 0, 3)))

    return best(run, 1)[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweep_output", help="the netCDF file of " + SWEEP)
    parser.add_argument("--chunks", type=int, default=6)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--sample", type=int, default=256)
    parser.add_argument("--output", default=None)
    args = parser.parse_args()
    threads = numba.get_num_threads()
    ds = xr.open_dataset(args.sweep_output)
    status = ds.status.values.ravel()
    steps = ds.rk4_steps.values.ravel().astype(float)
    settled = status == STATUS.settled
    total = {"settled": steps[settled].sum(), "not settled": steps[~settled].sum()}

    spec = load_sweep(SWEEP)
    rows, seconds = [], {"solve": 0.0, "engine": 0.0, "solve_all": 0.0}
    chosen = np.linspace(0, spec.n_chunks - 1, args.chunks).round().astype(int)
    sampled = 0.0
    for chunk in chosen:
        points = _chunk_points(spec, chunk)
        solve_1 = min(compute_chunk(spec, chunk, threads=1)["run_time"]
                      for _ in range(args.rounds))
        result = compute_chunk(spec, chunk, threads=1)
        solve_n = min(compute_chunk(spec, chunk, threads=threads)["run_time"]
                      for _ in range(args.rounds))
        numba.set_num_threads(1)
        run_steps = result["rk4_steps"].ravel().astype(float)
        per_period = result["steps_per_period"].ravel().astype(float)
        alone = min(_engine_alone(points, per_period, run_steps) for _ in range(args.rounds))
        numba.set_num_threads(threads)
        ok = result["metrics"][:, 0, spec.metrics.index("status")] == STATUS.settled
        n_steps = run_steps.sum()
        sampled += n_steps
        seconds["solve"] += solve_1
        seconds["engine"] += alone
        seconds["solve_all"] += solve_n
        rows.append(f"| {chunk} | {len(points)} | {(~ok).sum()} | {n_steps:.3e} | "
                    f"{run_steps[~ok].sum() / n_steps:.3f} | {solve_1:.3f} | {alone:.3f} | "
                    f"{solve_1 / alone:.2f} | {solve_n:.3f} | {solve_1 / solve_n:.2f} |")

    # the points that never settle, through their budget at the steps they ran
    never = np.flatnonzero(~settled)
    pick = np.random.default_rng(0).choice(never, min(args.sample, len(never)), replace=False)
    names = ds.status.dims
    at = np.unravel_index(pick, ds.status.shape)
    values = [{name: float(ds[name].values[k]) for name, k in zip(names, point)}
              for point in zip(*at)]
    never_points = [spec.point_parameters(v) for v in values]
    numba.set_num_threads(1)
    never_seconds = min(_engine_alone(never_points, ds.steps_per_period.values[at].astype(float),
                                      ds.rk4_steps.values[at].astype(float))
                        for _ in range(args.rounds))
    numba.set_num_threads(threads)
    never_ns = never_seconds / ds.rk4_steps.values[at].sum() * 1e9

    solve_ns = seconds["solve"] / sampled * 1e9
    engine_ns = seconds["engine"] / sampled * 1e9
    gain = seconds["solve"] / seconds["solve_all"]
    all_steps = sum(total.values())
    lines = [
        "# Where the 1e6-point sweep's time goes",
        "",
        provenance() + f" Command: python -m benchmarks.million_split OUT.nc "
        f"--chunks {args.chunks} --rounds {args.rounds}",
        "",
        f"The sweep's output ({len(status):,} points): RK4 steps by status.",
        "",
        "| points | count | RK4 steps | share of steps | periods a point (mean) |",
        "| --- | ---: | ---: | ---: | ---: |",
    ]
    per = ds.rk4_steps.values.ravel() / ds.steps_per_period.values.ravel()
    for kind, mask in (("settled", settled), ("not settled", ~settled)):
        lines.append(f"| {kind} | {mask.sum():,} | {total[kind]:.3e} | "
                     f"{total[kind] / all_steps:.3f} | {per[mask].mean():.1f} |")
    lines += [
        "",
        f"Chunks of {SWEEP} solved as the sweep solves them (1 thread; best of "
        f"{args.rounds}), and the engine alone running each point as many periods at its "
        f"final step, without the solver; the chunk again on {threads} threads.",
        "",
        "| chunk | points | not settled | RK4 steps | their share | solve, 1 thread [s] | "
        "engine alone [s] | solve / engine | solve, all threads [s] | threads' gain |",
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
        *rows,
        "",
        f"Over the chunks: {solve_ns:.2f} ns a step solved, {engine_ns:.2f} ns by the engine "
        f"alone (the solver's share {1 - engine_ns / solve_ns:.2f}); {threads} threads "
        f"{gain:.2f}x one. {len(pick)} points that never settle, by the engine alone through "
        f"their budget: {never_ns:.2f} ns a step.",
        "",
        "Projected to the whole sweep (its steps at these rates, on all threads at this gain):",
        "",
        f"- as solved: {all_steps * solve_ns * 1e-9 / gain / 60:.1f} min;",
        f"- the points that never settle, by the engine alone (no solver can skip their "
        f"budget and keep their status): {total['not settled'] * never_ns * 1e-9 / gain / 60:.1f}"
        f" min;",
        f"- the engine alone for every step (a solver that cost nothing beyond the periods "
        f"it asks for): {all_steps * engine_ns * 1e-9 / gain / 60:.1f} min.",
    ]
    report(lines, args.output)


if __name__ == "__main__":
    main()
