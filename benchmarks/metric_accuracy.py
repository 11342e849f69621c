"""How right the metrics that ``error_estimate`` does not cover are: the contact force's
peak and the approach velocities, at the automatic step, against the same orbit at 32768
steps a period (whose own error is below 1e-7 of each), with SciPy's DOP853 at rtol 1e-12
beside it (tests/helpers.reference_orbit; its contact force peak searched on the dense
output around the largest of 40001 samples).

    python -m benchmarks.metric_accuracy      # prints a Markdown table

The estimated metrics (power, v_peak, x_max, x_min) are shown against the same reference
with their ``error_estimate``, to compare.
"""

from __future__ import annotations

import platform

from harvester_sweep import run_scene
from tests.helpers import reference_orbit

CASES = [
    ("paper", {}),
    ("paper", {"gap": 3e-6, "frequency": 145.0}),
    ("strong_coupling", {"gap": 2e-6, "frequency": 150.0}),
    ("strong_coupling", {"gap": 7.425e-6}),  # a slow impact near grazing (an orbit of 7)
]
UNCOVERED = ("contact_force_max", "approach_velocity", "approach_velocity_min")
COVERED = ("power", "v_peak", "x_max")
FINE = 32768


def _rel(value, reference):
    return abs(value / reference - 1.0)


def main() -> None:
    print(f"{platform.processor() or platform.machine()}, python {platform.python_version()}"
          f"\n\nRelative errors at the automatic step (x_max's relative to the amplitude).\n")
    print("| case | steps | error_estimate | " + " | ".join(COVERED) + " | "
          + " | ".join(f"{name} (SciPy)" for name in UNCOVERED) + " |")
    print("| --- | ---: | ---: | " + " | ".join("---:" for _ in COVERED + UNCOVERED) + " |")
    for preset, over in CASES:
        auto = run_scene(preset, **over)
        fine = run_scene(preset, steps_per_period=FINE, **over).metrics
        # (the SciPy reference measures one forcing period: an orbit of several has none)
        scipy = reference_orbit(auto) if auto.metrics["orbit_period"] == 1 else None
        m = auto.metrics
        amplitude = 0.5 * (fine["x_max"] - fine["x_min"])
        cells = [f"{_rel(m['power'], fine['power']):.1e}",
                 f"{_rel(m['v_peak'], fine['v_peak']):.1e}",
                 f"{abs(m['x_max'] - fine['x_max']) / amplitude:.1e}"]
        cells += [f"{_rel(m[name], fine[name]):.1e} "
                  + (f"({_rel(m[name], scipy[name]):.1e})" if scipy else "(-)")
                  for name in UNCOVERED]
        case = preset + "".join(f", {k} {v:g}" for k, v in over.items())
        print(f"| {case} | {int(m['steps_per_period'])} | {m['error_estimate']:.1e} | "
              + " | ".join(cells) + " |")
    print("\nThe contact force's peak against the step (relative error against the same "
          f"orbit at {FINE} steps):\n")
    steps = (512, 1024, 2048, 4096, 8192)
    print("| case | " + " | ".join(f"{n}" for n in steps) + " |")
    print("| --- | " + " | ".join("---:" for _ in steps) + " |")
    for preset, over in CASES[:3]:
        fine = run_scene(preset, steps_per_period=FINE, **over).metrics["contact_force_max"]
        peaks = [run_scene(preset, steps_per_period=n, **over).metrics["contact_force_max"]
                 for n in steps]
        cells = [f"{peak / fine - 1:+.1e}" for peak in peaks]
        case = preset + "".join(f", {k} {v:g}" for k, v in over.items())
        print(f"| {case} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
