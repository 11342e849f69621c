"""The benchmark sweeps, defined once for test_speed.py and compare.py: the paper scene at
1024 steps per period on a 64 x 64 gap x frequency grid, the same grid with the stop out
of reach, and a 32 x 64 one swept up and down in frequency (continuation)."""

from __future__ import annotations

GRID = {"gap": {"start": 0.25e-6, "stop": 4e-6, "num": 64},  # [m]
        "frequency": {"start": 100, "stop": 250, "num": 64}}  # [Hz]
FREE = {"gap": {"start": 1.0, "stop": 1.1, "num": 64}, "frequency": GRID["frequency"]}
HALF = {"gap": {**GRID["gap"], "num": 32}, "frequency": GRID["frequency"]}
STEPS_PER_PERIOD = 1024


def sweep_spec(grid: dict, directions: list | None = None) -> dict:
    """The sweep of the paper scene over ``grid`` (swept in ``directions`` when given)."""
    spec = {"preset": "paper", "parameters": {"steps_per_period": STEPS_PER_PERIOD},
            "grid": grid,
            "sweep": {"outputs": ["power", "v_peak", "x_max", "orbit_period"],
                      "error_estimate": "none"}}
    if directions:
        spec["sweep"]["directions"] = directions
    return spec
