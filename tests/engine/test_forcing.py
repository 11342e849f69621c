"""The forcing next to a contact switch, from the step's start phase and Taylor series,
against math.sin."""

import math

import numpy as np

from harvester_sweep._engine.rk4 import forcing as _forcing


def test_forcing_series_matches_sin_down_to_16_steps_per_period():
    worst = 0.0
    for phi in np.linspace(0.0, 2.0 * math.pi, 37):
        for d in np.linspace(-2.0 * math.pi / 16, 2.0 * math.pi / 16, 101):
            value = _forcing(2.5, math.sin(phi), math.cos(phi), d)
            worst = max(worst, abs(value - 2.5 * math.sin(phi + d)) / 2.5)
    assert worst < 2e-15
