"""The beam's error estimates are honest: the one-mode beam at its tip is the tip-mass
model, so each settled point's outputs must lie within twice its ``error_estimate`` of the
lane engine's orbit of the reduced model at accuracy 1e-11 (plain RK4 on its own, an
independent reference), and within the accuracy asked.

The points are of the 24 x 24 grid of benchmarks/engines.py (gap 0.25-4 um, 180-300 Hz):
where a contact sub-step cut at the separation, its error set by where the separation
falls in it, makes the change between two halvings no bound on the error
(docs/numerics.md, "The beam"; benchmarks/results/beam_accuracy.md)."""

from __future__ import annotations

import numpy as np
import pytest

from harvester_sweep import bimorph as bm
from harvester_sweep import run_scene
from harvester_sweep.beam_parameters import bimorph, resolve_beam_parameters
from harvester_sweep.beam_runs import beam_scene, beam_sweep

ACCURACY = 1e-7
GAPS = np.linspace(0.25e-6, 4e-6, 24)  # [m]: benchmarks/engines.py's grid
FREQUENCIES = np.linspace(180.0, 300.0, 24)  # [Hz]
#: (gap index, frequency index): the six of the grid whose error exceeds twice the estimate
#: with sub-steps cut at the separation, and the three nearest their estimates without.
POINTS = [(2, 17), (3, 16), (0, 18), (5, 14), (14, 2), (1, 19), (5, 12), (7, 11), (6, 12)]
OUTPUTS = ("power", "v_peak", "x_max")
#: Where the two engines part at their finest steps: the beam's power settles 1.3e-10 and
#: 2.3e-10 from the lane engine's at 1e-11 at (2, 17) and (5, 12), sub-steps to 1.9e-8 s [-].
FLOOR = 5e-10


@pytest.fixture(scope="module")
def reduced():
    return bm.as_tip_mass_parameters(bimorph(resolve_beam_parameters("bimorph_tip",
                                                                     n_modes=1)))


@pytest.mark.parametrize("frequency", [150.0, 200.0])  # [Hz]: mak_rod striking once a period
def test_the_rod_faces_error_is_within_twice_the_estimate_and_the_accuracy(frequency):
    """``stop_face_max`` is in the estimate: against the same orbit at 8 times the grid
    steps and an eighth of the contact sub-step, whose own error (RK4's fourth order) is
    about 4,000 times smaller, the rod face's error stays within twice the estimate. (The
    reference is the finer orbit of a point first solved at 4 times the steps: the one
    halving its estimate takes, at an accuracy that asks for no more.)"""
    got, _ = beam_scene("mak_rod", periods=1, frequency=frequency, accuracy=ACCURACY)
    steps, sub = int(got["steps_per_period"]), float(got["contact_step"])
    ref, _ = beam_scene("mak_rod", periods=1, frequency=frequency, accuracy=0.01,
                        steps_per_period=4 * steps, contact_step=sub / 4)
    assert ref["steps_per_period"] == 8 * steps and ref["contact_step"] == sub / 8
    assert got["status"] == ref["status"] == 0 and got["impacts_per_period"] >= 1
    estimate = float(got["error_estimate"])
    assert estimate <= ACCURACY
    error = abs(got["stop_face_max"] - ref["stop_face_max"]) / ref["stop_face_max"]
    assert error <= 2 * estimate + FLOOR, (error, estimate)
    assert error <= ACCURACY, error


@pytest.mark.parametrize("i, j", POINTS)
def test_the_beams_error_is_within_twice_its_estimate_and_the_accuracy(reduced, i, j):
    # (after the rod's test: a cold suite compiles the tip-mass engine of the reference
    # while the beam's tests run, conftest.BEAM_FIRST)
    gap, f = float(GAPS[i]), float(FREQUENCIES[j])
    beam = beam_sweep({"gap": [gap], "frequency": [f]}, "bimorph_tip", n_modes=1,
                      accuracy=ACCURACY)
    ref = run_scene("paper", **reduced, gap=gap, frequency=f, accuracy=1e-11).metrics
    assert int(beam["status"].values.ravel()[0]) == 0 and ref["status"] == "settled"
    got = {name: float(beam[name].values.ravel()[0]) for name in OUTPUTS}
    # the same orbit (both from the linear steady state)
    assert abs(got["x_max"] - ref["x_max"]) < 1e-3 * abs(ref["x_max"])
    estimate = float(beam["error_estimate"].values.ravel()[0])
    assert estimate <= ACCURACY
    for name in OUTPUTS:
        error = abs(got[name] - ref[name]) / abs(ref[name])
        assert error <= 2 * estimate + FLOOR, (name, error, estimate)
        assert error <= ACCURACY, (name, error)
