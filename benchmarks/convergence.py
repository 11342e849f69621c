"""Error of the RK4 engine against run time on the paper scene, plain steps vs located switches.

    python -m benchmarks.convergence            # prints a Markdown table

The reference is SciPy's DOP853 at rtol 1e-12, restarted at every contact switch
(tests/helpers.py), settled on the steady orbit. Run time is the best of 3 runs, after
compilation.
"""

from __future__ import annotations

import platform
from pathlib import Path

import numpy as np

from harvester_sweep import run_scene
from tests.helpers import reference_orbit

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    reference = reference_orbit(run_scene("paper", steps_per_period=8192,
                                           settle_tolerance=1e-12))
    print(f"paper scene, {platform.processor() or platform.machine()}, "
          f"python {platform.python_version()}\n")
    print("| steps/period | plain: v_rms rel. error | order | located: v_rms rel. error "
          "| order | located: run time [s] |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: |")
    previous = {}
    for n in [128, 256, 512, 1024, 2048, 4096, 8192]:
        row = [f"{n}"]
        for locate in (False, True):
            runs = [run_scene("paper", steps_per_period=n, settle_tolerance=1e-13,
                              locate_switches=locate) for _ in range(3)]
            error = abs(runs[0].metrics["v_rms"] / reference["v_rms"] - 1)
            order = (np.log2(previous[locate] / error) if locate in previous else float("nan"))
            previous[locate] = error
            row += [f"{error:.2e}", f"{order:.2f}"]
            if locate:
                row.append(f"{min(r.metrics['run_time'] for r in runs):.4f}")
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
