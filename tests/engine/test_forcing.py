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


def _shifted_start():
    """The paper point at 1 um, its state in contact at step 300 of a period from rest."""
    from harvester_sweep import packing, resolve_parameters

    p = resolve_parameters("paper", gap=1e-6, frequency=245.0, steps_per_period=1024)
    row = packing.pack_parameters(p)
    state = packing.initial_state(p)
    state[:3] = (1.2e-6, -2e-3, 1e-5)  # inside the stop, leaving it
    return p, row, state


def test_a_period_started_at_a_forcing_phase_is_scipys_on_the_same_equations():
    """A run whose forcing phase starts at phi follows A sin(w t + phi): SciPy's DOP853 on
    the same equations from t0 = phi / w, with the contact switches located, to RK4's error
    at 1024 steps."""
    from harvester_sweep._engine import PARAM, record_series
    from tests.helpers import Reference

    p, row, state = _shifted_start()
    phase = 2 * math.pi * 300 / 1024
    row[PARAM.phase] = phase
    engine = record_series(row, state, 1)[-1, :3]
    w = 2 * math.pi * p["frequency"]
    reference, _ = Reference(p).integrate(state[:3], phase / w, phase / w + 1 / p["frequency"])
    scale = np.array([1e-6, 2 * math.pi * 245.0 * 1e-6, 1e-5])
    assert np.all(np.abs(engine - reference[:3]) / scale < 3e-7)
    row[PARAM.phase] = 0.0  # (and the phase matters: a start at phase 0 ends elsewhere)
    assert np.max(np.abs(record_series(row, state, 1)[-1, :3] - reference[:3]) / scale) > 1e-3


def test_a_start_at_step_k_with_its_phase_retraces_the_run_from_phase_zero():
    """From the state at step k of a run from phase 0, a run started at phase 2 pi k / N
    takes the same RK4 steps: it reaches the state at step k + N, up to rounding."""
    from harvester_sweep._engine import PARAM, record_series

    _, row, state = _shifted_start()
    n = int(row[PARAM.steps])
    whole = record_series(row, state, 2)
    for k in (1, 300, 777):
        row[PARAM.phase] = 2 * math.pi * k / n
        start = state.copy()
        start[:3] = whole[k, :3]
        shifted = record_series(row, start, 1)
        scale = np.max(np.abs(whole[:, :3]), axis=0)
        assert np.all(np.abs(shifted[:, :3] - whole[k:k + n + 1, :3]) / scale < 1e-11)
