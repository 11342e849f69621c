"""The beam model through its API and the command line: bad input refused in one line,
the CF dataset of a sweep (model, units, the mode dimension, the rod's metric present only
with a rod), its netCDF round trip, the stop's hysteresis between an up and a down sweep,
and `parameters --model beam`. Each point is one to three modes (a second or less)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from harvester_sweep.beam_parameters import (
    BEAM_PARAMETER_PRESETS,
    BEAM_PARAMETERS,
    resolve_beam_parameters,
)
from harvester_sweep.beam_runs import beam_scene, beam_sweep
from harvester_sweep.cli import main
from harvester_sweep.parameters import PARAMETERS, ParameterError

#: Bad beam input: (preset, overrides, what the one line must name).
BAD = [
    ("bimorph_tip", {"contact_position": "0.05"}, ["contact_position [m]", "0.05"]),
    ("bimorph_tip", {"n_modes": "9"}, ["n_modes [-]", "[1, 8]"]),
    ("bimorph_tip", {"rod_modes": "-1"}, ["rod_modes [-]", "[0, 8]"]),
    ("mak_rod", {"lower_gap": "1e-6"}, ["lower_gap [m]", "rod"]),
    ("bimorph_tip", {"colour": "1"}, ["unknown beam parameter 'colour'"]),
    ("bimorph_tip", {"gap": "abc"}, ["gap [m]", "not a number"]),
    ("bimorph_tip", {"n_modes": "three"}, ["n_modes [-]", "not a number"]),
    ("bimorph_tip", {"rod_length": "abc"}, ["rod_length [m]", "not a number"]),
]
IDS = ["contact_beyond_tip", "n_modes_9", "rod_modes_negative", "lower_gap_with_rod",
       "unknown_name", "string_gap", "string_n_modes", "string_rod_length"]


def _one_line_error(capsys, words):
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, (word, err)
    return err


@pytest.mark.parametrize("command", ["beam-scene", "beam-sweep"])
@pytest.mark.parametrize("preset, overrides, words", BAD, ids=IDS)
def test_bad_input_exits_2_with_one_line_naming_parameter_and_unit(
        command, preset, overrides, words, tmp_path, capsys):
    argv = [command, "--preset", preset]
    for name, value in overrides.items():
        argv += ["--set", f"{name}={value}"]
    if command == "beam-sweep":
        argv += ["--axis", "frequency=140,150", "--output", str(tmp_path / "s.nc")]
    assert main(argv) == 2
    _one_line_error(capsys, words)
    assert not (tmp_path / "s.nc").exists()


def _typed(overrides: dict) -> dict:
    """The overrides as a Python caller gives them: numbers as numbers, except the one
    meant to be a string."""
    out = {}
    for name, value in overrides.items():
        try:
            out[name] = int(value) if value.lstrip("-").isdigit() else float(value)
        except ValueError:
            out[name] = value
    return out


@pytest.mark.parametrize("preset, overrides, words", BAD, ids=IDS)
def test_bad_input_raises_parameter_error_through_the_api(preset, overrides, words):
    typed = _typed(overrides)
    for call in (lambda: resolve_beam_parameters(preset, **typed),
                 lambda: beam_scene(preset, **typed),
                 lambda: beam_sweep({"frequency": [140.0, 150.0]}, preset, **typed)):
        with pytest.raises(ParameterError) as error:
            call()
        message = str(error.value)
        assert "\n" not in message
        for word in words:  # the same words as the command line's
            assert word in message, (word, message)


def test_bad_values_on_a_sweep_axis_are_refused_through_the_api():
    with pytest.raises(ParameterError, match=r"n_modes \[-\]"):
        beam_sweep({"frequency": [150.0], "n_modes": [1, 9]})
    with pytest.raises(ParameterError, match="colour"):
        beam_sweep({"colour": [1.0]})
    with pytest.raises(ParameterError, match="frequency"):
        beam_sweep({"gap": [1e-6]}, directions="up")


@pytest.mark.parametrize("axis, words", [
    ("frequency=1:2", ["--axis", "START:STOP:COUNT"]),
    ("frequency=100:200:x", ["--axis frequency", "COUNT"]),
    ("frequency=-1,150", ["frequency [Hz]", "(0, inf)"]),
    ("n_modes=1,9", ["n_modes [-]", "[1, 8]"]),
    ("connection=series", ["--axis connection", "one of series, parallel"]),
    ("colour=1,2", ["unknown beam parameter 'colour'"]),
    ("gap", ["--axis 'gap'"]),
])
def test_bad_axes_exit_2_with_one_line(axis, words, tmp_path, capsys):
    assert main(["beam-sweep", "--axis", axis, "--output", str(tmp_path / "s.nc")]) == 2
    _one_line_error(capsys, words)


def test_a_direction_without_a_frequency_axis_exits_2(tmp_path, capsys):
    assert main(["beam-sweep", "--axis", "gap=1e-6,2e-6", "--direction", "up",
                 "--output", str(tmp_path / "s.nc")]) == 2
    _one_line_error(capsys, ["--direction", "frequency"])


def _cf_complete(ds: xr.Dataset) -> None:
    for name, var in ds.variables.items():
        assert var.attrs.get("units"), name
        assert var.attrs.get("long_name"), name


def test_sweep_dataset_is_cf_says_beam_and_has_a_mode_dimension(tmp_path):
    ds = beam_sweep({"frequency": [150.0, 170.0]}, n_modes=3)
    assert ds.attrs["model"] == "beam"
    _cf_complete(ds)
    assert ds["modal_amplitude"].dims == ("frequency", "mode")
    assert ds.sizes["mode"] == 3 and list(ds["mode"].values) == [1, 2, 3]
    assert np.isfinite(ds["modal_amplitude"].values).all()
    assert (ds["status"] == 0).all()
    # a rigid stop: the rod face's metric is absent, not NaN
    assert "stop_face_max" not in ds
    for name in ("root_strain_max", "root_stress_piezo", "root_stress_substrate",
                 "contact_displacement_max", "power", "x_max", "error_estimate"):
        assert name in ds and np.isfinite(ds[name].values).all(), name
    # the round trip through netCDF keeps every unit and long name
    path = tmp_path / "sweep.nc"
    ds.to_netcdf(path)
    with xr.open_dataset(path) as back:
        assert back.attrs["model"] == "beam"
        _cf_complete(back)
        for name, var in ds.variables.items():
            assert back[name].attrs["units"] == var.attrs["units"], name
        np.testing.assert_array_equal(back["power"].values, ds["power"].values)


def test_a_rod_stop_has_the_rod_face_metric():
    ds = beam_sweep({"frequency": [140.0]}, "mak_rod", n_modes=1, rod_modes=1)
    assert ds.attrs["model"] == "beam"
    _cf_complete(ds)
    assert "stop_face_max" in ds
    assert ds["stop_face_max"].attrs["units"] == "m"
    assert np.isfinite(ds["stop_face_max"].values).all()
    assert ds.sizes["mode"] == 1


#: Across the bimorph_tip preset's hysteresis band at gap 1 um (one mode): sweeping up
#: the orbit stays on the impacting branch to about 250 Hz, sweeping down from 280 Hz it
#: stays off the stop to about 225 Hz (measured: at 230 and 240 Hz the up sweep's power is
#: about ten times the down sweep's). Steps of 10 Hz: a coarser step (280 to 240 Hz) can
#: throw the down sweep onto the impacting branch.
BAND = dict(frequency=np.linspace(200.0, 280.0, 9))
INSIDE, OUTSIDE = [230.0, 240.0], [200.0, 280.0]


def _power_and_error(ds, direction, frequency):
    point = ds.sel(direction=direction, frequency=frequency)
    power = float(point["power"])
    return power, float(point["error_estimate"]) * abs(power)


def test_up_and_down_sweeps_differ_across_the_hysteresis_band():
    ds = beam_sweep(BAND, "bimorph_tip", directions=("up", "down"), n_modes=1, gap=1e-6)
    assert list(ds["direction"].values) == ["up", "down"]
    _cf_complete(ds)
    assert (ds["status"] == 0).all()
    for f in INSIDE:
        up, up_error = _power_and_error(ds, "up", f)
        down, down_error = _power_and_error(ds, "down", f)
        assert abs(up - down) > 10 * (up_error + down_error), f
        assert up > 3 * down, f  # the up sweep still on the impacting branch
        assert float(ds.sel(direction="up", frequency=f)["impacts_per_period"]) >= 1
        assert float(ds.sel(direction="down", frequency=f)["impacts_per_period"]) == 0
    for f in OUTSIDE:  # one orbit only: both sweeps find it
        up, up_error = _power_and_error(ds, "up", f)
        down, down_error = _power_and_error(ds, "down", f)
        assert abs(up - down) <= 10 * (up_error + down_error) + 1e-8 * abs(up), f


def test_cli_sweep_writes_the_dataset_with_progress(tmp_path, capsys):
    path = tmp_path / "sweep.nc"
    argv = ["beam-sweep", "--axis", "frequency=200:280:5", "--direction", "both",
            "--set", "n_modes=1", "--out", str(path)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert err.count("up ") == 5 and err.count("down ") == 5  # a line per frequency step
    # each but the last says what is left, at the rate so far
    steps = [line for line in err.splitlines() if " sweep, " in line]
    assert all("left" in line for line in steps[:-1]) and "left" not in steps[-1]
    assert str(path) in err.splitlines()[-1]
    with xr.open_dataset(path) as ds:
        assert ds.attrs["model"] == "beam"
        _cf_complete(ds)
        np.testing.assert_allclose(ds["frequency"].values, [200, 220, 240, 260, 280])
        assert list(ds["direction"].values) == ["up", "down"]
        assert ds["power"].dims == ("direction", "frequency")
        assert "stop_face_max" not in ds
    figure = tmp_path / "response.png"  # power, x_max/x_min and root strain, up and down
    assert main(["plot", str(path), "--output", str(figure)]) == 0
    assert figure.stat().st_size > 10_000


def test_cli_sweep_over_two_axes_without_direction(tmp_path, capsys):
    path = tmp_path / "grid.nc"
    assert main(["beam-sweep", "--axis", "frequency=150,170", "--axis", "gap=1e-6:2e-6:2",
                 "--set", "n_modes=2", "--output", str(path), "--quiet"]) == 0
    err = capsys.readouterr().err  # (at most the note of a first compilation)
    assert all(line.startswith("harvester-sweep: compiling") for line in err.splitlines())
    with xr.open_dataset(path) as ds:
        assert ds["power"].dims == ("frequency", "gap")
        assert ds["gap"].attrs["units"] == "m"
        assert ds["modal_amplitude"].dims == ("frequency", "gap", "mode")
    figure = tmp_path / "grid.png"  # maps of the power and the root strain
    assert main(["plot", str(path), "--output", str(figure)]) == 0
    assert figure.stat().st_size > 10_000


def test_cli_scene_prints_its_outputs_with_units_and_writes_the_history(tmp_path, capsys):
    path = tmp_path / "scene.nc"
    assert main(["beam-scene", "--set", "n_modes=2", "--periods", "1",
                 "--output", str(path)]) == 0
    out = capsys.readouterr().out
    for word in ("root_strain_max", "root_stress_piezo", "Pa", "modal_amplitude[1]",
                 "modal_amplitude[2]", "m kg0.5", "\u00b5m", "settled"):
        assert word in out, word
    rows = [line.split()[0] for line in out.splitlines() if line.startswith("  ")]
    assert "root_strain_max" in rows and "stop_face_max" not in rows  # a rigid stop
    with xr.open_dataset(path) as ds:
        assert ds.attrs["model"] == "beam"
        assert ds["time"].attrs["units"] == "s"
        assert ds["tip_displacement"].attrs["units"] == "m"
        assert "stop_face" not in ds
        # one forcing period recorded (140 Hz)
        assert float(ds["time"].max()) == pytest.approx(1 / 140, rel=0.02)
        # the recorded orbit's peak is the reported metric
        assert float(ds["tip_displacement"].max()) <= float(ds["x_max"]) * (1 + 1e-6)
    # plot draws the beam's orbit as the paper's Fig. 3 with the root strain
    figure = tmp_path / "scene.png"
    assert main(["plot", str(path), "--output", str(figure)]) == 0
    assert figure.stat().st_size > 10_000


def test_cli_scene_json_with_a_rod(capsys):
    assert main(["beam-scene", "--preset", "mak_rod", "--set", "n_modes=1",
                 "--set", "rod_modes=1", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["status"] == "settled"
    assert len(record["modal_amplitude"]) == 1
    assert record["stop_face_max"] is not None and record["stop_face_max"] >= 0
    for name in ("power", "root_strain_max", "x_max", "contact_displacement_max"):
        assert isinstance(record[name], float), name


def test_parameters_lists_every_beam_parameter(capsys):
    assert main(["parameters", "--model", "beam"]) == 0
    out = capsys.readouterr().out
    first = [line.split()[0] for line in out.splitlines() if line.strip()]
    for name in BEAM_PARAMETERS:
        assert first.count(name) == 2, name  # its description, then its preset values
    for preset in BEAM_PARAMETER_PRESETS:
        assert preset in out
    assert "rod_modes" in out and "a finite number in (0, inf)" in out


def test_parameters_of_the_tip_mass_model_are_unchanged(capsys):
    assert main(["parameters"]) == 0
    default = capsys.readouterr().out
    assert main(["parameters", "--model", "tip_mass"]) == 0
    assert capsys.readouterr().out == default
    first = {line.split()[0] for line in default.splitlines() if line.strip()}
    assert set(PARAMETERS) <= first
    assert "rod_modes" not in first


def test_cli_branch_and_basins_write_their_datasets_and_plots(tmp_path, capsys):
    branch, basins = tmp_path / "branch.nc", tmp_path / "basins.nc"
    assert main(["beam-continue", "frequency", "200", "240", "--set", "n_modes=1",
                 "--step", "0.05", "--out", str(branch)]) == 0
    assert main(["beam-basins", "--set", "n_modes=1", "--set", "frequency=240",
                 "--samples", "8", "--out", str(basins)]) == 0
    err = capsys.readouterr().err
    assert "branch points" in err and "attractor(s) from 8 starts" in err
    with xr.open_dataset(branch) as ds:
        assert ds.attrs["model"] == "beam" and ds.attrs["parameter"] == "frequency"
        _cf_complete(ds)
    with xr.open_dataset(basins) as ds:
        assert float(ds["basin_fraction"].sum()) == pytest.approx(1.0)
        _cf_complete(ds)
    for path in (branch, basins):
        figure = path.with_suffix(".png")
        assert main(["plot", str(path), "--output", str(figure)]) == 0
        assert figure.stat().st_size > 10_000
    assert main(["beam-continue", "n_modes", "1", "2", "--out", str(branch)]) == 2
    _one_line_error(capsys, ["parameter", "n_modes"])
