"""The examples on a machine shared with other work: wall time beside busy processes.

    python -m benchmarks.loaded [--busy 2] [--rounds 3] [--before /tmp/before]

Starts ``--busy`` processes that spin on a core each, then runs, in turn, the paper's
continuation (examples/paper_s_curve.toml) and frequency response
(examples/paper_frequency_response.toml) through the command line, as a user would:
on numba's default threads and on one (``NUMBA_NUM_THREADS=1``), and, with ``--before``,
another checkout's package on its default threads. Each figure is the median of the rounds,
the configurations alternated within each round, so that they see the same load. The
engine is compiled (or loaded from its cache) by a first run that is not counted.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The environment as the user gave it, before a package import sets anything in it
#: (harvester_sweep sets OMP_WAIT_POLICY): each checkout run sets its own.
_ENVIRONMENT = dict(os.environ)
EXAMPLES = {
    "continuation (paper_s_curve.toml)": ["continue", str(ROOT / "examples/paper_s_curve.toml")],
    "frequency response (paper_frequency_response.toml)":
        ["run", str(ROOT / "examples/paper_frequency_response.toml"), "--quiet"],
}


def _run(root: Path, command: list, env: dict, folder: str) -> float:
    """Wall time [s] of one command-line run of the package at ``root`` (run from
    ``folder``: ``python -m`` puts the working folder first on the path)."""
    out = Path(folder) / "out.nc"
    out.unlink(missing_ok=True)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "harvester_sweep.cli", *command, "--output", str(out)],
                   cwd=folder, env={**_ENVIRONMENT, "PYTHONPATH": str(root), **env}, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def main(argv=None) -> None:
    from benchmarks.variants import cpu_model  # (imports the package: after _ENVIRONMENT)

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--busy", type=int, default=2, help="busy processes beside the runs")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--before", type=Path, help="another checkout to compare with")
    args = parser.parse_args(argv)
    configs = {"default threads": (ROOT, {}), "one thread": (ROOT, {"NUMBA_NUM_THREADS": "1"})}
    if args.before is not None:
        configs = {"before, default threads": (args.before.resolve(), {}), **configs}
    times = {(e, c): [] for e in EXAMPLES for c in configs}
    with tempfile.TemporaryDirectory() as folder:
        for root, env in configs.values():  # compile or load the cache, uncounted
            _run(root, EXAMPLES[next(iter(EXAMPLES))], env, folder)
        busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                for _ in range(args.busy)]
        try:
            for _ in range(args.rounds):
                for example, command in EXAMPLES.items():
                    for config, (root, env) in configs.items():
                        times[example, config].append(_run(root, command, env, folder))
        finally:
            for process in busy:
                process.kill()
    print(f"CPU: {cpu_model()}; {os.cpu_count()} cores; {args.busy} busy processes; "
          f"median of {args.rounds} rounds [s]\n")
    print("| example | " + " | ".join(configs) + " |")
    print("| --- |" + " ---: |" * len(configs))
    for example in EXAMPLES:
        print(f"| {example} | "
              + " | ".join(f"{statistics.median(times[example, c]):.2f}" for c in configs)
              + " |")


if __name__ == "__main__":
    main()
