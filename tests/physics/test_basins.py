"""Basins of coexisting attractors against independent references: the closed-form
stop-free orbit, transient integration from rest, and the count of starts."""

import numba
import numpy as np
import pytest

from harvester_sweep import (
    ParameterError,
    basin_fractions,
    basin_map,
    basins,
    packing,
    resolve_parameters,
    run_scene,
)
from harvester_sweep._engine import METRIC, STATUS, run_points
from tests.helpers import phasor

# A point of the benchmark grid inside the stop's hysteresis band: from rest the motion
# reaches an orbit with one impact a period, and a stop-free orbit coexists.
BAND = {"gap": 0.25e-6 + 18 * 3.75e-6 / 63, "frequency": 100 + 61 * 150 / 63,
        "steps_per_period": 1024}


def test_one_attractor_far_below_the_band():
    """Every start reaches the one orbit, the closed-form stop-free phasor."""
    ds = basin_fractions(frequency=100.0, steps_per_period=512, samples=64)
    assert ds.sizes["attractor"] == 1
    assert float(ds.basin_fraction[0]) == 1.0
    assert float(ds.fraction_not_settled) == float(ds.fraction_diverged) == 0.0
    p = resolve_parameters("paper", frequency=100.0, steps_per_period=512)
    _, V = phasor(**p)
    assert float(ds.power[0]) == pytest.approx(abs(V) ** 2 / (2 * p["resistance"]), rel=1e-5)


def test_an_unforced_device_has_one_attractor_rest():
    """With no base motion the device only loses energy (damping, the load, the contact's
    damping), so every start, a box of micrometres and millimetres a second and a shock,
    ends at rest: one attractor, no power, no motion. Before, every start was counted not
    settled: its decaying motion was measured against its own amplitude, which shrank
    with it."""
    for kwargs in ({"samples": 8}, {"samples": 4, "shock": 0.5}):
        ds = basin_fractions("paper", amplitude=0.0, **kwargs)
        assert ds.sizes["attractor"] == 1, ds
        assert float(ds.basin_fraction[0]) == 1.0
        assert float(ds.fraction_not_settled) == float(ds.fraction_diverged) == 0.0
        assert int(ds.orbit_period[0]) == 1
        assert float(ds.impact_basin_fraction) == 0.0
        assert abs(float(ds.x_max[0])) < 1e-15 and abs(float(ds.x_min[0])) < 1e-15
        assert float(ds.power[0]) < 1e-30


def test_where_no_start_settles_the_share_that_strikes_is_unknown(tmp_path, capsys):
    """Three periods settle no start of the band: every start is counted not settled, and
    the impact basin fraction and its error are NaN, where they read 0 +- 0 (a map of
    such points read as "never strikes"); the summary says so in words and percent."""
    grid = {"frequency": [BAND["frequency"], BAND["frequency"] + 5.0]}
    ds = basin_map(grid, samples=8, gap=BAND["gap"], steps_per_period=512, max_periods=3,
                   progress=False)
    assert (ds.fraction_not_settled == 1.0).all() and ds.sizes["attractor"] == 0
    assert np.isnan(ds.impact_basin_fraction).all()
    assert np.isnan(ds.impact_basin_fraction_error).all()
    assert "NaN where none" in ds.impact_basin_fraction.attrs["long_name"]
    from harvester_sweep.cli import _basin_summary

    said = _basin_summary(ds, 1.0)
    assert "unknown: no start reached an orbit" in said
    assert "up to 100% of a point's starts reached no orbit" in said


def test_two_attractors_in_the_band_each_the_orbit_a_reference_finds():
    """Both coexisting orbits are found, every start is counted once, the stop-free one is
    the closed-form phasor (to RK4's error at 1024 steps) and the impacting one is the orbit
    transient integration reaches from rest."""
    ds = basin_fractions(samples=256, **BAND)
    fractions = ds.basin_fraction.values
    total = fractions.sum() + float(ds.fraction_not_settled) + float(ds.fraction_diverged)
    assert total == pytest.approx(1.0, abs=1e-12)
    impacts = ds.impacts_per_period.values
    assert (impacts > 0).any() and (impacts == 0).any()
    assert np.all(fractions[:2] > 0.05)

    free = int(np.flatnonzero(impacts == 0)[0])
    p = resolve_parameters("paper", **BAND)
    _, V = phasor(**p)
    assert float(ds.power[free]) == pytest.approx(abs(V) ** 2 / (2 * p["resistance"]),
                                                  rel=1e-5)

    p = resolve_parameters("paper", settle_tolerance=1e-12, **BAND)
    packed = packing.pack_points([p])
    metrics = np.empty((1, len(METRIC)))
    run_points(packed.rows, packed.states.copy(), metrics, np.empty((1, 0, 3)))
    assert metrics[0, METRIC.status] == STATUS.settled
    assert metrics[0, METRIC.impacts_per_period] > 0
    hit = int(np.flatnonzero(impacts > 0)[0])
    assert float(ds.power[hit]) == pytest.approx(metrics[0, METRIC.power], rel=1e-7)


def test_the_same_seed_gives_the_same_numbers_on_any_thread_count():
    threads = numba.get_num_threads()
    first = basin_fractions(samples=96, seed=3, **BAND)
    numba.set_num_threads(1)
    try:
        again = basin_fractions(samples=96, seed=3, **BAND)
    finally:
        numba.set_num_threads(threads)
    for name in ("basin_fraction", "power", "x_max", "spectral_radius"):
        np.testing.assert_array_equal(first[name].values, again[name].values)
    other = basin_fractions(samples=96, seed=4, **BAND)
    assert not np.array_equal(first.basin_fraction.values, other.basin_fraction.values)


def test_a_shock_of_nothing_returns_every_start_to_the_orbit_from_rest():
    """Starts spread over every forcing phase of the orbit reached from rest, nudged by a
    1e-9 m/s shock, all reach that orbit again (each compared with the orbit at its own
    phase): one attractor holds every start, and it is the scene's orbit."""
    ds = basin_fractions(samples=64, shock=1e-9, **BAND)
    assert ds.sizes["attractor"] == 1
    assert float(ds.basin_fraction[0]) == float(ds.impact_basin_fraction) == 1.0
    scene = run_scene("paper", **BAND).metrics
    for name in ("power", "x_max", "impacts_per_period"):
        assert float(ds[name][0]) == pytest.approx(scene[name], rel=1e-7), name


def test_a_shock_in_the_band_knocks_some_starts_onto_the_stop_free_orbit():
    """A 0.03 m/s shock on the impacting orbit sends some starts to the coexisting
    stop-free orbit, the closed-form phasor; every start is counted once."""
    ds = basin_fractions(samples=128, shock=0.03, **BAND)
    fractions, impacts = ds.basin_fraction.values, ds.impacts_per_period.values
    assert fractions.sum() + float(ds.fraction_not_settled) + float(ds.fraction_diverged) \
        == pytest.approx(1.0, abs=1e-12)
    assert float(ds.impact_basin_fraction) == pytest.approx(fractions[impacts > 0].sum())
    free = np.flatnonzero(impacts == 0)
    assert free.size == 1 and 0 < fractions[free[0]] < 0.5
    p = resolve_parameters("paper", **BAND)
    _, V = phasor(**p)
    assert float(ds.power[free[0]]) == pytest.approx(abs(V) ** 2 / (2 * p["resistance"]),
                                                     rel=1e-5)


def test_a_map_holds_each_points_basins_whatever_the_engine_calls(monkeypatch):
    """Each point of a map has the basins basin_fractions finds there with the same draws,
    bit for bit, whether the points share engine calls or not; one attractor far below
    the band; every start counted once."""
    grid = {"gap": [BAND["gap"], 2 * BAND["gap"]], "frequency": [100.0, BAND["frequency"]]}
    kwargs = dict(samples=48, seed=2, steps_per_period=1024, progress=False)
    shared = basin_map(grid, **kwargs)
    monkeypatch.setattr(basins, "CALL_STARTS", 48)  # one point a call
    alone = basin_map(grid, **kwargs)
    for name in shared.data_vars:
        np.testing.assert_array_equal(shared[name].values, alone[name].values)
    total = (shared.basin_fraction.fillna(0).sum("attractor") + shared.fraction_not_settled
             + shared.fraction_diverged)
    np.testing.assert_allclose(total.values, 1.0, atol=1e-12)
    below = shared.sel(frequency=100.0)
    np.testing.assert_array_equal(below.basin_fraction.values[:, 0], 1.0)
    point = basin_fractions(samples=48, seed=2, **BAND)
    at = shared.isel(gap=0, frequency=1).isel(attractor=slice(0, point.sizes["attractor"]))
    for name in ("basin_fraction", "power", "x_max", "impact_basin_fraction"):
        np.testing.assert_array_equal(at[name].values, point[name].values)


@pytest.mark.parametrize("kwargs, words", [
    ({"samples": 0}, "samples [-] = 0"),
    ({"samples": 2.5}, "samples [-] = 2.5"),
    ({"seed": -1}, "seed [-] = -1"),
    ({"seed": 2**64}, "seed [-] = 18446744073709551616"),  # (its netCDF attribute failed)
    ({"box": {"x": -1e-6}}, "box.x [m] = -1e-06"),
    ({"box": {"y": 1e-6}}, "box.y: unknown"),
    ({"gap": "wide"}, "gap"),
    ({"shock": -0.01}, "shock [m/s] = -0.01"),
    ({"shock": 0.01, "box": {"x": 1e-6}}, "box and shock"),
])
def test_bad_input_is_refused_in_one_line_naming_it(kwargs, words):
    with pytest.raises(ParameterError) as error:
        basin_fractions(**kwargs)
    assert words in str(error.value) and "\n" not in str(error.value)
