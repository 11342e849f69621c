"""Where a beam solve's work goes: forcing periods per point by what they were run for.

    python -m benchmarks.beam_work [--output FILE]

The beam's points are solved by their own solver (``beam_runs.solve_beam``): a short
transient, Newton attempts on the period map with monodromies by the variational
equations (the motion integrated on between them, as the tip-mass solver's), the orbit
measured by the modal engine, then the same at twice the steps (chord steps with the last
monodromy taken, Newton where they stall and the motion would settle slowly) until the
change meets the accuracy target, and the Floquet multipliers by the variational equations
at the step reported. This counts the modal engine's work by what it was run for, in
forcing periods at each point's first steps per period (a run at twice the steps counts
twice; a run that carries the variational equations counts as a run), on a gap x frequency
grid of each preset at its own budget and accuracy. The solver is not changed:
``modal_map``'s calls and the solver's phases are wrapped while a solve runs.
"""

from __future__ import annotations

import argparse
import collections
import time

import numpy as np

from benchmarks.variants import provenance, report
from harvester_sweep import beam_runs, modal_map
from harvester_sweep._engine.modal import RealFields, real_fields
from harvester_sweep.beam_parameters import resolve_beam_parameters

GAPS = (0.5e-6, 1e-6, 2e-6, 4e-6)  # [m]
FREQUENCIES = tuple(np.linspace(110.0, 240.0, 6))  # [Hz]
PRESETS = ("bimorph_tip", "mak_rod")
KINDS = {
    "transient": "the motion: transient and pieces between attempts (the first steps)",
    "newton": "Newton's attempts: runs, and copies where any (the first steps)",
    "measure": "the orbit measured (the first steps)",
    "chord": "chord steps (finer steps)",
    "finer": "the orbit measured, or the motion settled and measured (finer steps)",
    "multipliers": "multipliers' monodromy (the step reported)",
}
#: Runs that carried the variational equations (counted in their kind above too).
VARIATIONAL = "of all: runs carrying the variational equations"
_FIELDS = RealFields(*real_fields(0, 0, 0))


class Tally:
    """While active: the modal engine's work, in periods at each point's first steps, by
    kind (KINDS). The solver's phases (Newton or its chord steps, measuring, the
    multipliers) are wrapped to say what an engine call is for; a call outside them is the
    motion (at the first steps: the transient, the pieces between attempts) or a finer
    step's run."""

    def __init__(self, first: dict):
        self.periods = collections.Counter()
        self.first = first  # forcing frequency [rad/s], rounded -> first steps per period
        self.phase = None
        self._saved = []

    def _replace(self, owner, name, make):
        saved = getattr(owner, name)
        self._saved.append((owner, name, saved))
        setattr(owner, name, make(saved))

    def _ratios(self, packs) -> np.ndarray:
        """Each pack's steps per period over its point's first ones [-]."""
        return np.array([pk.rrow[_FIELDS.steps] / self.first[round(pk.rrow[_FIELDS.omega], 6)]
                         for pk in packs])

    def _book(self, packs, periods, kind, ratios=None):
        ratios = self._ratios(packs) if ratios is None else ratios
        self.periods[kind] += float(np.sum(np.asarray(periods, dtype=float) * ratios))

    def _phase(self, kind):
        def make(saved):
            def wrapped(*args, **kwargs):
                outer = self.phase
                chord = kind == "newton" and (kwargs.get("jac") is not None
                                              or (len(args) > 5 and args[5] is not None))
                self.phase = "chord" if chord else kind
                try:
                    return saved(*args, **kwargs)
                finally:
                    self.phase = outer
            return wrapped
        return make

    def __enter__(self):
        self._replace(beam_runs._Group, "newton", self._phase("newton"))
        self._replace(beam_runs._Group, "measure", self._phase("measure"))
        self._replace(beam_runs, "_multipliers", self._phase("multipliers"))

        def runs(saved):
            # (a run to steady state, or a measure of an orbit: their periods run)
            def wrapped(packs, *args):
                out = saved(packs, *args)
                ratios = self._ratios(packs)
                kind = self.phase
                if kind in (None, "measure"):  # (at the first steps, or finer)
                    kind = (kind or "transient") if np.all(ratios == 1.0) else "finer"
                self._book(packs, out[0][:, beam_runs.HEAD.periods_run], kind, ratios)
                return out
            return wrapped

        def map_states(saved):
            def wrapped(packs, states, periods):
                self._book(packs, periods, self.phase)
                return saved(packs, states, periods)
            return wrapped

        def variational(saved):
            def wrapped(packs, states, periods):
                # (outside Newton: the monodromy of an orbit the motion settled on, counted
                # with Newton's)
                self._book(packs, periods, self.phase or "newton")
                self._book(packs, periods, VARIATIONAL)
                return saved(packs, states, periods)
            return wrapped

        self._replace(modal_map, "run", runs)
        self._replace(modal_map, "measure", runs)
        self._replace(modal_map, "map_states", map_states)
        self._replace(modal_map, "variational_monodromies", variational)
        return self

    def __exit__(self, *exc):
        for owner, name, saved in reversed(self._saved):
            setattr(owner, name, saved)


def _case(preset: str):
    """(tally, points, settled, wall time [s], share of periods_run of the points not
    settled) of the preset's grid, solved once untimed (compile) and once counted."""
    points = [resolve_beam_parameters(preset, frequency=float(f), gap=g)
              for f in FREQUENCIES for g in GAPS]
    first = {round(2 * np.pi * p["frequency"], 6):
             beam_runs.first_steps(p, beam_runs.system_of(p))[0] for p in points}
    beam_runs.solve_beam(points[:1])
    with Tally(first) as tally:
        start = time.perf_counter()
        solved = beam_runs.solve_beam(points)
        wall = time.perf_counter() - start
    status = solved.values["status"]
    run = solved.values["periods_run"]
    settled = status == 0
    return tally, len(points), int(settled.sum()), wall, float(run[~settled].sum() / run.sum())


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output")
    args = parser.parse_args(argv)
    lines = ["# A beam solve's work, by what it was run for", "",
             f"{provenance()} Command: python -m benchmarks.beam_work", "",
             "Each preset at its own budget and accuracy on gaps "
             f"{', '.join(f'{g:g}' for g in GAPS)} m x {len(FREQUENCIES)} frequencies "
             f"{FREQUENCIES[0]:g}-{FREQUENCIES[-1]:g} Hz, every "
             "point from rest. Forcing periods per point at its first steps "
             "per period (a run at twice the steps counts twice), by kind.", "",
             "| preset | points (settled) | " + " | ".join(KINDS.values())
             + f" | all | {VARIATIONAL} | wall [ms / point] | periods_run of the points not "
             "settled |",
             "| --- | ---: |" + " ---: |" * (len(KINDS) + 4)]
    for preset in PRESETS:
        tally, n, settled, wall, share = _case(preset)
        cells = [f"{tally.periods[k] / n:.1f}" for k in KINDS]
        every = sum(tally.periods[k] for k in KINDS)
        lines.append(f"| {preset} | {n} ({settled}) | " + " | ".join(cells)
                     + f" | {every / n:.1f} | {tally.periods[VARIATIONAL] / n:.1f} "
                     f"| {wall / n * 1e3:.1f} | {100 * share:.0f} % |")
    report(lines, args.output)


if __name__ == "__main__":
    main()
