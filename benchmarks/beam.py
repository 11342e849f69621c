"""The beam's cost: per point and per forcing period against the number of modes, against
SciPy on the same modal equations at matched accuracy, and the 64 x 64 grid.

    python -m benchmarks.beam [--quick] [--output benchmarks/results/beam.md]

Three measurements, each on the two beam presets (``bimorph_tip``: the tip strikes a rigid
stop; ``mak_rod``: the beam strikes at 0.8 L a steel rod in 5 modes):

1. Modes: ``solve_beam`` on 8 frequencies (130-150 Hz, the paper's 1 m/s^2 and 1 um gap)
   at 1 to 8 bending modes: wall time per point, the metric ``periods_run`` and the wall
   time per period it counts; and the period map alone (``modal_map.map_states`` over
   MAP_PERIODS periods from the settled orbit, at the steps the point chose): the engine's
   cost of one forcing period.
2. SciPy: the same modal equations (``system_of(p).system``: y' = M y + f A sin(w t) +
   sum_s b_s F_s, F_s the Hertz law ``models.hertz.force.py_func`` at the penetration
   c_s y - g_s and its rate c_s M y) integrated for SCIPY_PERIODS periods from the
   engine's settled state at 140 Hz, 5 modes, by DOP853 (restarted at every touch,
   separation and clip of the force, located by events), LSODA and Radau (through the
   switches), at tolerances from 1e-4 down until each meets the engine's error estimate.
   The error of a run is the larger of its mean power's relative error and its end
   state's (relative to the engine's component scales), both against DOP853 with events
   at rtol 1e-12; the engine's is measured the same way.
3. The 64 x 64 gap x frequency grid of benchmarks/cases.py (0.25-4 um, 100-250 Hz) through
   ``beam_sweep``: a sub-grid (every 8th gap and frequency; ``--quick``: every 32nd) timed
   at the presets' budget of periods and at 1000, the full grid's time extrapolated by its
   number of points (and the full grid run where that is under FULL_GRID_LIMIT).

Every time is the best of ROUNDS runs after a first, uncounted one (numba's compilation
or its cache). The machine is shared: the ratios are taken within one run.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from benchmarks.cases import GRID
from benchmarks.variants import best, provenance
from harvester_sweep import modal_map
from harvester_sweep.beam_packing import pack_beam
from harvester_sweep.beam_parameters import resolve_beam_parameters
from harvester_sweep.beam_runs import beam_sweep, points_of, solve_beam, system_of
from harvester_sweep.models import beam as beam_model
from harvester_sweep.models.hertz import force

ROOT = Path(__file__).resolve().parents[1]
CASES = {"rigid stop (bimorph_tip)": ("bimorph_tip", {}),
         "rod, 5 rod modes (mak_rod)": ("mak_rod", {"rod_modes": 5})}
#: Frequencies of the modes table [Hz], and the forcing periods the period map is timed on.
FREQUENCIES = np.linspace(130.0, 150.0, 8)
MAP_PERIODS = 20
#: The SciPy comparison: its frequency [Hz], periods integrated, the reference's rtol, the
#: tolerances tried (loosest first) and the longest run before a method is given up [s].
SCIPY_FREQUENCY = 140.0
SCIPY_PERIODS = 3
REFERENCE_RTOL = 1e-12
TOLERANCES = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11]
SCIPY_LIMIT = 60.0
#: Best of this many timed runs.
ROUNDS = 3
#: The whole 64 x 64 grid is run (without --quick) where the sub-grid's estimate is under
#: this [s]; otherwise its time is extrapolated. 0: never, as the estimate is no bound (the
#: points that never settle are not spread evenly over the grid) [s].
FULL_GRID_LIMIT = 0.0


def _period_map_time(points, sol, periods, rounds):
    """Wall time [s] of ``periods`` forcing periods of the period map for every point,
    from its settled state, at the steps the point chose."""
    packs = [pack_beam(p, system_of(p), int(sol.values["steps_per_period"][i]),
                       float(sol.values["contact_step"][i])) for i, p in enumerate(points)]
    starts = np.array(sol.ends)
    counts = np.full(len(points), periods, dtype=np.int64)
    return best(lambda: modal_map.map_states(packs, starts, counts), rounds)[0]


def modes_table(modes, frequencies, rounds) -> list[str]:
    lines = ["| stop | modes | state size | steps / period | periods_run / point | "
             "ms / point | us / period (periods_run) | us / period (period map) | "
             "error estimate, largest | not settled |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for label, (preset, extra) in CASES.items():
        for n in modes:
            points = [resolve_beam_parameters(preset, n_modes=n, frequency=f, **extra)
                      for f in frequencies]
            wall, sol = best(lambda: solve_beam(points), rounds)
            v = sol.values
            periods = float(np.sum(v["periods_run"]))
            per_map = _period_map_time(points, sol, MAP_PERIODS, rounds)
            lines.append(
                f"| {label} | {n} | {len(system_of(points[0]).system.matrix)} | "
                f"{np.median(v['steps_per_period']):.0f} | {periods / len(points):.1f} | "
                f"{wall / len(points) * 1e3:.2f} | {wall / periods * 1e6:.0f} | "
                f"{per_map / (MAP_PERIODS * len(points)) * 1e6:.0f} | "
                f"{np.nanmax(v['error_estimate']):.2g} | {int(np.sum(v['status'] != 0))} |")
            print(lines[-1], flush=True)
    return lines


def scipy_model(p, bs):
    """The right-hand side of the modal equations with the mean power's integral V^2 as a
    last component, the switching functions of each surface, and whether each pushes."""
    sysm, A, w = bs.system, p["amplitude"], 2 * math.pi * p["frequency"]
    kh, ch = p["hertz_stiffness"], bs.contact_damping
    M, f, C, g, B = sysm.matrix, sysm.forcing, sysm.surfaces, sysm.gaps, sysm.inputs
    CM = C @ M  # the penetration's rate: the force acts on accelerations, not on it
    volt = sysm.outputs[list(sysm.output_names).index("voltage")]
    law = force.py_func

    def rhs(t, y, on=None):
        x = y[:-1]
        dy = M @ x + f * (A * math.sin(w * t))
        d, r = C @ x - g, CM @ x
        for s in range(len(g)):
            if on is None or on[s]:
                dy = dy + B[s] * law(kh, d[s], r[s], ch)
        return np.append(dy, (volt @ x) ** 2)

    def pushing(x):
        return (C @ x - g > 0) & (1 + ch * (CM @ x) > 0)

    def switches():
        events = []
        for s in range(len(g)):
            for kind in (0, 1):
                def event(t, y, on, s=s, kind=kind):
                    x = y[:-1]
                    return C[s] @ x - g[s] if kind == 0 else 1 + ch * (CM[s] @ x)
                event.terminal = True
                events.append(event)
        return events

    return rhs, pushing, switches()


def scipy_run(p, bs, y0, periods, method, rtol):
    """(end state, mean power [W], rhs evaluations) of ``method`` over ``periods`` forcing
    periods from y0; DOP853 is restarted at every switch of the force, located by events."""
    rhs, pushing, events = scipy_model(p, bs)
    T = periods / p["frequency"]
    y = np.append(y0, 0.0)
    atol = np.append(rtol * bs.scale, 1e-30)
    if method != "DOP853":
        res = solve_ivp(rhs, (0.0, T), y, method=method, rtol=rtol, atol=atol)
        return res.y[:-1, -1], res.y[-1, -1] / T / p["resistance"], res.nfev
    t, on, nfev = 0.0, pushing(y0), 0
    while t < T:
        res = solve_ivp(rhs, (t, T), y, method="DOP853", rtol=rtol, atol=atol, events=events,
                        args=(on,))
        t, y, nfev = res.t[-1], res.y[:, -1], nfev + res.nfev
        if res.status == 1:
            # which side of the switch the motion goes on to: a tiny Euler step ahead; then
            # a step clear of the switch, where its event would fire again at once
            nudge = 1e-10 / p["frequency"]
            on = pushing((y + nudge * rhs(t, y, on))[:-1])
            step = solve_ivp(rhs, (t, min(t + nudge, T)), y, method="DOP853", rtol=rtol,
                             atol=atol, args=(on,))
            t, y, nfev = step.t[-1], step.y[:, -1], nfev + step.nfev
    return y[:-1], y[-1] / T / p["resistance"], nfev


def scipy_section(periods, tolerances, rounds, limit) -> list[str]:
    lines = []
    summary = ["| stop | integrator | rtol needed | error | ms / period | "
               "time ratio to the engine (per period) | per point, ratio* | "
               "power alone: rtol needed | power alone: ratio (per period) |",
               "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for label, (preset, extra) in CASES.items():
        p = resolve_beam_parameters(preset, frequency=SCIPY_FREQUENCY, **extra)
        bs = system_of(p)
        point_time, sol = best(lambda: solve_beam([p]), rounds)
        v = {name: float(values[0]) for name, values in sol.values.items()
             if np.ndim(values) == 1}
        y0 = np.asarray(sol.ends[0])
        pack = pack_beam(p, bs, int(v["steps_per_period"]), v["contact_step"])
        engine_time, (end, _) = best(
            lambda: modal_map.map_states([pack], y0[None], np.array([periods])), rounds * 3)
        start = time.perf_counter()
        ref_end, ref_power, ref_nfev = scipy_run(p, bs, y0, periods, "DOP853", REFERENCE_RTOL)
        ref_time = time.perf_counter() - start

        names = ["power"] + [c.name for c in beam_model.state(p["n_modes"], p["rod_modes"])]

        def error(end, power):
            return max(abs(power / ref_power - 1),
                       float(np.max(np.abs(end - ref_end) / bs.scale)))

        def worst(end, power):
            parts = np.append(abs(power / ref_power - 1), np.abs(end - ref_end) / bs.scale)
            return names[int(np.argmax(parts))]

        engine_error = error(end[0], v["power"])
        engine_worst = worst(end[0], v["power"])
        target = v["error_estimate"]
        lines += [f"### {label}: {len(bs.system.matrix)} states, 5 bending modes, "
                  f"{SCIPY_FREQUENCY:g} Hz, {periods} periods from the settled state",
                  "",
                  f"Engine: {int(v['steps_per_period'])} steps per period, contact sub-step "
                  f"{v['contact_step']:.3g} s; error estimate {target:.2g}, error against the "
                  f"reference {engine_error:.2g} (largest in {engine_worst}); period map "
                  f"{engine_time / periods * 1e3:.3f} ms per period; the whole point "
                  f"(solve_beam from rest, periods_run "
                  f"{v['periods_run']:.0f}) {point_time * 1e3:.1f} ms. Reference: DOP853 with "
                  f"events at rtol {REFERENCE_RTOL:g}, {ref_time / periods:.2f} s per period, "
                  f"{ref_nfev} evaluations.",
                  "",
                  "| integrator | rtol | evaluations | error | largest in | ms / period | "
                  "ratio to the engine |",
                  "| --- | ---: | ---: | ---: | --- | ---: | ---: |"]
        for method in ("DOP853", "LSODA", "Radau"):
            met = power_met = None
            for rtol in tolerances:
                start = time.perf_counter()
                e_end, e_power, nfev = scipy_run(p, bs, y0, periods, method, rtol)
                took = time.perf_counter() - start
                err = error(e_end, e_power)
                if power_met is None and abs(e_power / ref_power - 1) <= target:
                    power_met = (rtol, took)
                name = "DOP853 + events" if method == "DOP853" else method
                lines.append(f"| {name} | {rtol:g} | {nfev} | {err:.2g} | "
                             f"{worst(e_end, e_power)} | {took / periods * 1e3:.1f} | "
                             f"{took / engine_time:.0f} |")
                print(label, lines[-1], flush=True)
                if err <= target:
                    met = (rtol, err, took)
                    break
                if took > limit:
                    break
            name = "DOP853 + events" if method == "DOP853" else method
            power_only = ("not met | " if power_met is None else
                          f"{power_met[0]:g} | {power_met[1] / engine_time:.0f} |")
            if met is None:
                summary.append(f"| {label} | {name} | not met to {tolerances[-1]:g} "
                               f"(or over {limit:g} s) | | | | | {power_only}")
            else:
                rtol, err, took = met
                per_period = took / periods
                per_point = per_period * v["periods_run"] / point_time
                summary.append(f"| {label} | {name} | {rtol:g} | {err:.2g} | "
                               f"{per_period * 1e3:.1f} | {took / engine_time:.0f} | "
                               f"{per_point:.0f} | {power_only}")
        lines.append("")
    return summary + [""] + lines


def _axis(spec):
    return np.linspace(spec["start"], spec["stop"], spec["num"])


def grid_section(stride, budgets, run_full) -> list[str]:
    gaps, frequencies = _axis(GRID["gap"]), _axis(GRID["frequency"])
    lines = ["| stop | max_periods | points timed | wall time [s] | CPU / wall | ms / point | "
             "not settled | their share of periods_run | 64 x 64 [s] |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    notes = []
    for label, (preset, extra) in CASES.items():
        axes = {"gap": gaps[::stride], "frequency": frequencies[::stride]}

        def sweep(axes, budget):
            ds = beam_sweep(axes, preset, **extra, max_periods=budget)
            return ds["status"].values, ds["periods_run"].values

        def solve(axes, budget):
            points = points_of(preset, dict(extra, max_periods=budget), axes)[0]
            v = solve_beam(points).values
            return v["status"], v["periods_run"]

        try:  # (one point: the engine is compiled by the sections before)
            sweep({"gap": [2e-6]}, budgets[0])
        except Exception as failure:  # the API's own failure, reported with the times
            notes.append(f"beam_sweep failed ({type(failure).__name__}: {failure}); "
                         "timed solve_beam on the same points (what beam_sweep runs before "
                         "it builds the dataset) instead")
            sweep = solve
        for budget in budgets:
            start, cpu = time.perf_counter(), time.process_time()
            status, periods = sweep(axes, budget)
            wall = time.perf_counter() - start
            cpu = time.process_time() - cpu
            n = status.size
            lost = status != 0
            share = float(periods[lost].sum() / periods.sum())
            full = wall * gaps.size * frequencies.size / n
            if run_full and full < FULL_GRID_LIMIT:
                start = time.perf_counter()
                sweep({"gap": gaps, "frequency": frequencies}, budget)
                full = f"{time.perf_counter() - start:.0f} run (estimate {full:.0f})"
            else:
                full = f"{full:.0f} extrapolated"
            lines.append(f"| {label} | {budget} | {n} | {wall:.2f} | {cpu / wall:.2f} | "
                         f"{wall / n * 1e3:.1f} | {int(lost.sum())} | {share:.0%} | "
                         f"{full} |")
            print(lines[-1], flush=True)
    return lines + [""] + [f"- {note}" for note in dict.fromkeys(notes)]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="fewer modes, points, periods and tolerances (minutes)")
    parser.add_argument("--output", type=Path, default=ROOT / "benchmarks/results/beam.md")
    args = parser.parse_args(argv)
    if args.quick:
        modes, frequencies, rounds = (1, 3, 5, 8), FREQUENCIES[::4], 1
        periods, tolerances, limit, stride = 1, TOLERANCES[1::2], 20.0, 32
    else:
        modes, frequencies, rounds = range(1, 9), FREQUENCIES, ROUNDS
        periods, tolerances, limit, stride = SCIPY_PERIODS, TOLERANCES, SCIPY_LIMIT, 8
    command = "python -m benchmarks.beam" + (" --quick" if args.quick else "")
    head = ["# The beam: cost against modes, against SciPy, and the 64 x 64 grid", "",
            f"Command: `{command}` (benchmarks/beam.py; its docstring says what each table "
            f"measures). {provenance()} (With the working tree's changes.) "
            "The machine is shared with other engineers' work: absolute times vary from run "
            f"to run, the ratios within a table are taken in the same run. Best of "
            f"{rounds} runs after an uncounted one (the grid: one run).", ""]
    sections = []

    def write(sections):  # after each section: a run cut short keeps what it measured
        args.output.parent.mkdir(parents=True, exist_ok=True)
        args.output.write_text("\n".join(head + sections).rstrip() + "\n", encoding="utf-8")

    print("modes", flush=True)
    sections += ["## Cost against the number of modes", "",
                 f"`solve_beam` on {len(frequencies)} frequencies from {frequencies[0]:g} to "
                 f"{frequencies[-1]:g} Hz (the paper's scene otherwise), in one call: wall "
                 "time per point; the metric `periods_run` (the periods of transient and of "
                 "the orbit's measurement; the period map's runs for Newton's monodromies "
                 "are not in it) and the wall time per period it counts; the period map "
                 f"alone over {MAP_PERIODS} periods from each settled orbit at the steps it "
                 "chose.", ""]
    sections += modes_table(modes, frequencies, rounds) + [""]
    print("scipy", flush=True)
    sections += ["## Against SciPy at matched accuracy", "",
                 "Each SciPy integrator at the loosest tolerance (atol = rtol x each "
                 "component's scale) whose error is at most the engine's error estimate. "
                 "'ratio to the engine' is SciPy's time over the engine's period map for "
                 "the same periods; *'per point' is SciPy's time per period times the "
                 "engine's `periods_run`, over the engine's whole `solve_beam` for the point "
                 "(SciPy given the engine's Newton for free: a lower bound). 'power alone': "
                 "the loosest tolerance whose mean power alone is within the engine's "
                 "error estimate, and its time ratio.", ""]
    sections += scipy_section(periods, tolerances, rounds, limit)
    print("grid", flush=True)
    sections += ["## The 64 x 64 gap x frequency grid", "",
                 f"`beam_sweep({{'gap': ..., 'frequency': ...}}, preset, max_periods=...)` on "
                 f"every {stride}th gap and frequency of benchmarks/cases.py's grid (gap "
                 f"{GRID['gap']['start'] * 1e6:g}-{GRID['gap']['stop'] * 1e6:g} um, "
                 f"{GRID['frequency']['start']}-{GRID['frequency']['stop']} Hz, 5 modes, "
                 "accuracy 1e-7), one timed run each, at the presets' budget of periods "
                 "(20000) and at 1000. The 64 x 64 grid's time is extrapolated from the "
                 "sub-grid by the number of points, and the grid is run where that estimate "
                 f"is under {FULL_GRID_LIMIT:g} s (a point that does not settle spends its "
                 "whole budget, at every level of the step check). 'CPU / "
                 "wall': the process's CPU time over the wall time (2: both cores busy).",
                 ""]
    write(sections)
    sections += grid_section(stride, (20000, 1000), not args.quick)
    write(sections)
    print(f"written {args.output}", file=sys.stderr)


if __name__ == "__main__":
    main()
