"""The benchmark sweeps, defined once for test_speed.py and compare.py: the paper scene at
1024 steps per period on a 64 x 64 gap x frequency grid, the same grid with the stop out
of reach, and a 32 x 64 one swept up and down in frequency (continuation); and how many
runs each time is the best of."""

from __future__ import annotations

GRID = {"gap": {"start": 0.25e-6, "stop": 4e-6, "num": 64},  # [m]
        "frequency": {"start": 100, "stop": 250, "num": 64}}  # [Hz]
FREE = {"gap": {"start": 1.0, "stop": 1.1, "num": 64}, "frequency": GRID["frequency"]}
HALF = {"gap": {**GRID["gap"], "num": 32}, "frequency": GRID["frequency"]}
STEPS_PER_PERIOD = 1024

# Every time is the best of some runs: on this shared machine one run of the same code
# varies (the 64 x 64 sweep read 323-361 M steps/s in three single runs; of 30
# back-to-back two-thread ensembles of 64 points at 1e-5, the slowest took 2.0x the
# median, 0.278 against 0.136 ms a point, on 2026-11-21). The alternatives (one core)
# get ALTERNATIVE_ROUNDS too, the engine's per-point ensemble ENGINE_ROUNDS, the one-point
# sweep in a new process COLD_START_ROUNDS.
SWEEP_ROUNDS = 3
ALTERNATIVE_ROUNDS = 3
ENGINE_ROUNDS = 10
COLD_START_ROUNDS = 3


def sweep_spec(grid: dict, directions: list | None = None) -> dict:
    """The sweep of the paper scene over ``grid`` (swept in ``directions`` when given)."""
    spec = {"preset": "paper", "parameters": {"steps_per_period": STEPS_PER_PERIOD},
            "grid": grid,
            "sweep": {"outputs": ["power", "v_peak", "x_max", "orbit_period"],
                      "error_estimate": "none"}}
    if directions:
        spec["sweep"]["directions"] = directions
    return spec
