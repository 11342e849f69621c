"""Basins of the beam: the attractors found from many starts by the engine's transient
alone are the orbits the up and down sweeps reach through the hysteresis band."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from harvester_sweep.beam_basins import beam_basins
from harvester_sweep.beam_runs import beam_sweep
from harvester_sweep.parameters import ParameterError

# in the one-mode beam's hysteresis band (tests/interface/test_beam_interface.py)
BAND = dict(n_modes=1, frequency=240.0)


def test_the_band_has_the_up_and_the_down_sweeps_orbits_as_attractors():
    ds = beam_basins("bimorph_tip", samples=32, **BAND)
    assert ds.sizes["attractor"] == 2
    assert float(ds["basin_fraction"].sum()) == pytest.approx(1.0)
    assert float(ds["fraction_not_settled"]) == 0 and float(ds["fraction_diverged"]) == 0
    assert sorted(ds["impacts_per_period"].values) == [0, 1]
    sweep = beam_sweep({"frequency": np.arange(200.0, 241.0, 10.0)}, "bimorph_tip",
                       directions="up", n_modes=1)
    down = beam_sweep({"frequency": np.arange(280.0, 239.0, -10.0)}, "bimorph_tip",
                      directions="down", n_modes=1)
    reached = {"up": sweep.sel(frequency=240.0, direction="up"),
               "down": down.sel(frequency=240.0, direction="down")}
    for a in range(2):
        which = "up" if ds["impacts_per_period"][a] == 1 else "down"
        other = reached[which]
        tolerance = 10 * (float(ds["error_estimate"][a]) + float(other["error_estimate"]))
        assert float(ds["power"][a]) == pytest.approx(float(other["power"]),
                                                      rel=tolerance + 1e-12)
        assert int(other["impacts_per_period"]) == int(ds["impacts_per_period"][a])
    # every start is accounted to an attractor, and the same seed draws the same starts
    assert (ds["sample_attractor"] >= 0).all()
    again = beam_basins("bimorph_tip", samples=32, **BAND)
    np.testing.assert_array_equal(again["start_eta_1"], ds["start_eta_1"])
    np.testing.assert_array_equal(again["basin_fraction"], ds["basin_fraction"])


@pytest.mark.parametrize("samples, box", [(0, 1.0), (True, 1.0), (8, 0.0), (8, float("nan"))])
def test_bad_basin_options_are_refused(samples, box):
    with pytest.raises(ParameterError, match="samples|box"):
        beam_basins("bimorph_tip", samples=samples, box=box, n_modes=1)


@pytest.mark.parametrize("seed", [-1, 2**64, 1.5])
def test_a_bad_seed_is_refused_in_one_line(seed):
    """numpy's generator raised on a negative seed, and a seed of 2^64 or more was drawn
    from and then failed as the dataset's netCDF attribute, after the solves."""
    with pytest.raises(ParameterError, match=r"seed \[-\] = .*: must be an integer in 0"):
        beam_basins("bimorph_tip", samples=2, seed=seed, n_modes=1)


def test_the_same_seed_gives_the_same_numbers_on_any_thread_count():
    """Each start's run is the same bits on one thread as on two (the modal engine's
    points run alone, whichever thread takes them)."""
    threads = numba.get_num_threads()
    first = beam_basins("bimorph_tip", samples=32, seed=0, **BAND)
    numba.set_num_threads(1)
    try:
        again = beam_basins("bimorph_tip", samples=32, seed=0, **BAND)
    finally:
        numba.set_num_threads(threads)
    assert first.sizes["attractor"] == 2
    for name in first.data_vars:
        np.testing.assert_array_equal(first[name].values, again[name].values, err_msg=name)
