"""The beam sweep's run-time estimate said before a run against the time the run took.

    python -m benchmarks.beam_estimate [--rounds N] [--output benchmarks/results/beam_estimate.md]

Each case is a beam sweep file (written to a temporary folder) run on the command line as
the guide says (``harvester-sweep beam-sweep FILE --output OUT.nc``) in a new process: the
estimate is read from the line the command prints before it starts, the run's time from
the line it prints after (the estimate's sample included), beside the process's wall time.
The cases alternate, N rounds. Prints a Markdown table (and writes it to --output) with the
CPU's model (lscpu) and the load average before and after.
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

from benchmarks.steady_states import _cpu

#: name -> sweep file: the 32 x 32 gap x frequency grid of both presets from rest, and a
#: 16 x 40 grid swept up and down.
CASES = {
    "bimorph_tip, 5 modes, 32 x 32 from rest": """model = "beam"
preset = "bimorph_tip"
[grid]
gap = { start = 0.25e-6, stop = 4e-6, num = 32 }
frequency = { start = 100, stop = 250, num = 32 }
""",
    "bimorph_tip, 3 modes, 16 x 40 up and down": """model = "beam"
preset = "bimorph_tip"
[parameters]
n_modes = 3
[grid]
gap = { start = 0.25e-6, stop = 4e-6, num = 16 }
frequency = { start = 100, stop = 250, num = 40 }
[sweep]
directions = ["up", "down"]
""",
    "mak_rod, 32 x 32 from rest": """model = "beam"
preset = "mak_rod"
[grid]
gap = { start = 0.25e-6, stop = 4e-6, num = 32 }
frequency = { start = 100, stop = 250, num = 32 }
""",
}

_ESTIMATE = re.compile(r"roughly ([0-9.,]+) (s|min|h)")
_TOOK = re.compile(r"settled\) in ([0-9.e+]+) s")
_UNIT = {"s": 1.0, "min": 60.0, "h": 3600.0}


def run_case(text: str, folder: Path) -> tuple[float, float, float]:
    """(estimate, the run's time, the process's wall time) [s] of one sweep file."""
    sweep, out = folder / "sweep.toml", folder / "out.nc"
    sweep.write_text(text)
    if out.exists():
        out.unlink()
    began = time.perf_counter()
    err = subprocess.run(["harvester-sweep", "beam-sweep", str(sweep), "--output", str(out)],
                         capture_output=True, text=True, check=True).stderr
    wall = time.perf_counter() - began
    said = _ESTIMATE.search(err)
    took = _TOOK.search(err)
    if said is None or took is None:
        raise RuntimeError(f"no estimate or time in: {err}")
    estimate = float(said.group(1).replace(",", "")) * _UNIT[said.group(2)]
    return estimate, float(took.group(1)), wall


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--output", type=Path)
    args = parser.parse_args(argv)
    load = os.getloadavg()[0]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.rounds):
            for name, text in CASES.items():
                estimate, took, wall = run_case(text, Path(tmp))
                rows.append(f"| {name} | {estimate:.3g} | {took:.3g} | {wall:.3g} | "
                            f"{took / estimate:.2f} |")
                print(rows[-1], flush=True)
    lines = ["# The beam sweep's run-time estimate against the run", "",
             f"Machine: `lscpu` \"{_cpu()}\"; load average {load:.2f} before, "
             f"{os.getloadavg()[0]:.2f} after. Command: `python -m benchmarks.beam_estimate "
             f"--rounds {args.rounds}`.", "",
             "| case | estimate [s] | run, the sample included [s] | process wall [s] | "
             "run / estimate |", "| --- | ---: | ---: | ---: | ---: |", *rows]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.output:
        args.output.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
