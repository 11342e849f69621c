"""The run-time estimate said before a run against the time the run took (issue 44).

    python -m benchmarks.estimate [--rounds N] [--million-restitutions K] [--full-million]
                                  [--output benchmarks/results/estimate_44.md]

The examples run as the guide says, each in a new process on the command line
(``harvester-sweep run``, ``basins``, ``continue``): the estimate is read from the line the
command prints before it starts, the time from the line it prints after (its integration
time, or a basin map's whole time), beside the process's wall time (its start included:
importing and loading the compiled engine, about 2 s here). The 1e6-point example is
measured on a sub-grid of it (its first K restitutions of 50, every other axis whole:
K x 20,000 points) unless --full-million. The
benchmark grids of benchmarks/cases.py run in this process through ``run_sweep``, the
estimate taken afresh before each run (its sample measured anew). Each case runs N rounds,
the cases alternating, and every (estimate, measured) pair is printed: on a shared machine
a run's time varies, and so does the estimate's, which is measured too.

Prints a Markdown table (and writes it to --output): case, estimate, measured,
measured / estimate; with the CPU's model (lscpu) and the load average before and after.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import tomllib

import harvester_sweep as hs
from benchmarks.cases import FREE, GRID, HALF, sweep_spec
from benchmarks.steady_states import _cpu
from harvester_sweep import run_estimate
from harvester_sweep.sweep_file import load_sweep

ROOT = Path(__file__).resolve().parents[1]

UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0, "days": 86400.0}
SAID = re.compile(r"roughly ([\d.,e+]+) (s|min|h|days) on")


def _cli(args: list, cwd: Path) -> tuple[float, str]:
    """Run ``harvester-sweep args`` in a new process: its wall time [s] and stderr+stdout."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "harvester_sweep.cli", *map(str, args)],
                          cwd=cwd, capture_output=True, text=True, check=True)
    return time.perf_counter() - start, done.stderr + done.stdout


def _said(text: str) -> float:
    """The estimate [s] a command printed before it started."""
    found = SAID.search(text)
    return float(found.group(1).replace(",", "")) * UNITS[found.group(2)] if found else None


def _took(text: str, pattern: str) -> float:
    return float(re.search(pattern, text).group(1))


def examples(tmp: Path, restitutions: int, full: bool):
    """(case, command, estimate [s], integration [s], process wall [s]) per example."""
    million = tomllib.loads((ROOT / "examples/million_points.toml").read_text())
    sub = tmp / "million_sub.toml"
    if not full:
        grid = million["grid"]
        grid["restitution"]["stop"] = (grid["restitution"]["start"] + (
            grid["restitution"]["stop"] - grid["restitution"]["start"])
            * (restitutions - 1) / (grid["restitution"]["num"] - 1))
        grid["restitution"]["num"] = restitutions
        sub.write_text("\n".join(
            [f'preset = "{million["preset"]}"', "[grid]"]
            + [f"{a} = {{ " + ", ".join(f"{k} = {v!r}" if not isinstance(v, str)
                                        else f'{k} = "{v}"' for k, v in e.items()) + " }"
               for a, e in grid.items()]
            + ["[sweep]", f"outputs = {million['sweep']['outputs']!r}"]) + "\n")
    ex = ROOT / "examples"
    cases = [
        ("paper_frequency_response", ["run", ex / "paper_frequency_response.toml",
                                      "--output", tmp / "fr.nc"], r"in ([\d.]+) s of"),
        ("paper_basins", ["basins", ex / "paper_basins.toml", "--output", tmp / "b.nc"],
         r"starts \(.*\) in ([\d.]+) s"),
        ("paper_s_curve", ["continue", ex / "paper_s_curve.toml", "--output", tmp / "c.nc"],
         r"points in ([\d.]+) s,"),
        ("million_points" + ("" if full else f" ({restitutions} of 50 restitutions)"),
         ["run", ex / "million_points.toml" if full else sub, "--output", tmp / "m.nc",
          "--yes"], r"in ([\d.]+) s of"),
    ]
    for name, args, pattern in cases:
        for path in tmp.glob("*.nc"):
            path.unlink()
        wall, text = _cli(args, tmp)
        yield name, "harvester-sweep " + " ".join(
            str(a).replace(str(ROOT) + "/", "").replace(str(tmp) + "/", "") for a in args), \
            _said(text), _took(text, pattern), wall


def grids():
    """(case, estimate [s], run_sweep wall [s]) per benchmark grid, in this process."""
    hs.run_sweep(sweep_spec({"gap": [1e-6], "frequency": [140.0]}), progress=False)
    for name, grid, directions in (("64 x 64 gap x frequency", GRID, None),
                                   ("64 x 64, stop out of reach", FREE, None),
                                   ("32 x 64, up and down", HALF, ["up", "down"])):
        spec = load_sweep(sweep_spec(grid, directions))
        run_estimate._SAMPLES.clear()  # (measured afresh, as a new process would)
        began = time.perf_counter()
        work = run_estimate.estimate(spec, spec.n_points, numba.get_num_threads())
        took = time.perf_counter() - began
        began = time.perf_counter()
        hs.run_sweep(spec, progress=False, yes=True)
        yield name, work.seconds, time.perf_counter() - began, took


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--million-restitutions", type=int, default=2)
    parser.add_argument("--full-million", action="store_true")
    parser.add_argument("--output", type=Path)
    args = parser.parse_args()
    lines = [f"CPU: {_cpu()}; numba threads: {numba.get_num_threads()}; load average "
             f"before: {_load()}", "",
             "| case | command | estimate [s] | measured [s] | process wall [s] | "
             "measured / estimate |", "| --- | --- | ---: | ---: | ---: | ---: |"]
    print("\n".join(lines), flush=True)

    def row(text):
        print(text, flush=True)
        lines.append(text)

    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.rounds):
            for name, command, said, took, wall in examples(
                    Path(tmp), args.million_restitutions, args.full_million):
                row(f"| {name} | `{command}` | {f'{said:.3g}' if said else 'none printed'} | "
                    f"{took:.3g} | {wall:.3g} | "
                    f"{f'{took / said:.2f}' if said else '(no estimate)'} |")
            for name, said, wall, took in grids():
                row(f"| {name} (cases.py) | `run_sweep` in this process | {said:.3g} (its "
                    f"sample {took:.2g}) | {wall:.3g} | - | {wall / said:.2f} |")
    lines += ["", f"Load average after: {_load()}"]
    print(lines[-1])
    if args.output:
        args.output.write_text("\n".join(lines) + "\n")


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


if __name__ == "__main__":
    main()
