"""The command line's tables and help as a designer reads them (issue 44): whole preset
values, aligned columns, lengths in um, a derived contact stiffness said where it is
derived, a description for every command, and the dataset's `direction` named."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from harvester_sweep import PARAMETERS, PRESETS, continuation, plots, resolve_parameters
from harvester_sweep.cli import _note_derived_stiffness, main
from harvester_sweep.plots import _LOCATED, plot_sweep

UM = "\u00b5m"


def _column_starts(lines, word):
    return {line.index(word) for line in lines}


def test_parameters_prints_every_preset_value_in_aligned_columns(capsys):
    assert main(["parameters"]) == 0
    out = capsys.readouterr().out
    assert "..." not in out
    first, second = out.split("\n\n")
    rows = first.splitlines()
    header = rows[0]
    for column in ("unit", "allowed", "description"):
        start = header.index(column)  # every row's cell starts under its header
        assert all(row[start - 1] == " " and row[start] != " " for row in rows[1:]), column
    values = second.splitlines()
    assert values[0].split() == ["preset", "values", "unit", *PRESETS]
    listed = {line.split()[0]: line.split()[2:] for line in values[1:]}
    assert set(listed) == set(PARAMETERS)
    assert listed["coupling"] == [f"{p['coupling']:g}" for p in PRESETS.values()]
    assert listed["lower_gap"] == ["unset"] * len(PRESETS)
    starts = [values[0].index(name) for name in PRESETS]
    for line in values[1:]:
        assert all(line[s - 1] == " " and line[s] != " " for s in starts), line


def test_the_scene_table_aligns_long_names_and_shows_lengths_in_um(capsys):
    assert main(["scene", "--set", "stop_mass=1e-2"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    k_h = resolve_parameters("paper", stop_mass=1e-2)["hertz_stiffness"]
    assert (f"  note: hertz_stiffness = {k_h:.3g} N/m^1.5 (derived from stop_mass = 10 g, "
            "copper tip on steel stop)") in lines
    assert f"gap = 1 {UM}" in lines[0] and "resistance = 10 kOhm" in lines[0]
    table = lines[lines.index("") + 1:]
    header = table[0]
    value_end = header.index("value") + len("value")
    # every value ends under "value", the long names (impacts_per_period_lower,
    # floquet_multipliers_real) and the multipliers' lists included
    assert all(row[value_end - 1] != " " and (row + "  ")[value_end:value_end + 2] == "  "
               for row in table[1:]), table
    units = {row.split()[0]: row[value_end + 2:].split(" ")[0] for row in table[1:]}
    assert units["x_max"] == UM and units["power"] == "W"
    x_max = float([row for row in table if row.split()[0] == "x_max"][0].split()[1])
    assert 0.5 < x_max < 2.0  # (um, not 1e-06)
    assert main(["scene"]) == 0
    assert "derived" not in capsys.readouterr().out


def test_runs_say_where_stop_mass_sets_the_contact_stiffness(capsys):
    _note_derived_stiffness("paper", {"stop_mass": 5e-3}, ["frequency"])
    k_h = resolve_parameters("paper", stop_mass=5e-3)["hertz_stiffness"]
    assert f"hertz_stiffness = {k_h:.3g} N/m^1.5 (derived from stop_mass = 5 g" in \
        capsys.readouterr().err
    _note_derived_stiffness("paper", {}, {"stop_mass": np.array([1e-3, 2e-3])})
    assert "derived at each point" in capsys.readouterr().err
    _note_derived_stiffness("paper", {"gap": 2e-6}, ["frequency"])
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("command, words", [
    ("scene", "from rest to its steady state"),
    ("parameters", "each preset's value of every parameter"),
])
def test_scene_and_parameters_describe_themselves_in_help(command, words, capsys):
    with pytest.raises(SystemExit) as stop:
        main([command, "--help"])
    assert stop.value.code == 0
    assert words in " ".join(capsys.readouterr().out.split())


def test_plot_takes_the_users_scale(tmp_path, capsys, monkeypatch):
    """--linear and --log on the command line reach the figure; a contradiction or an axis
    the figure does not have is refused in one line."""
    sweep = tmp_path / "r.toml"
    sweep.write_text('preset = "paper"\n[parameters]\nsteps_per_period = 256\n'
                     "max_periods = 300\n[grid]\nresistance = { start = 1e3, stop = 1e6, "
                     'num = 3, scale = "log" }\n[sweep]\n'
                     'outputs = ["power", "x_max"]\n')
    nc, png = tmp_path / "r.nc", tmp_path / "r.png"
    assert main(["run", str(sweep), "--output", str(nc), "--quiet"]) == 0
    with xr.open_dataset(nc) as ds:
        assert ds["resistance"].attrs["grid_spacing"] == "log"
    drawn = []

    def kept(*args, **kwargs):  # the command's own figure, to read its axes
        drawn.append(plot_sweep(*args, **kwargs))
        return drawn[-1]

    monkeypatch.setattr(plots, "plot_sweep", kept)
    for flags, scale in (([], "log"), (["--linear", "resistance"], "linear")):
        assert main(["plot", str(nc), "--output", str(png), *flags]) == 0
        assert png.stat().st_size > 10_000
        assert drawn[-1].axes[-1].get_xscale() == scale
    capsys.readouterr()
    assert main(["plot", str(nc), "--output", str(png), "--log", "resistance", "--linear",
                 "resistance"]) == 2
    assert "both name resistance" in capsys.readouterr().err
    assert main(["plot", str(nc), "--output", str(png), "--log", "gap"]) == 2
    err = capsys.readouterr().err
    assert "gap" in err and err.count("\n") == 1 and "Traceback" not in err


def test_the_direction_coordinate_has_a_long_name(tmp_path):
    from harvester_sweep.datasets import write_netcdf
    from harvester_sweep.sweep import run_sweep

    ds = run_sweep({"preset": "paper", "parameters": {"steps_per_period": 256,
                                                      "max_periods": 300},
                    "grid": {"frequency": [200.0, 240.0]},
                    "sweep": {"directions": ["up", "down"], "outputs": ["power"]}},
                   progress=False)
    write_netcdf(ds, tmp_path / "d.nc")
    with xr.open_dataset(tmp_path / "d.nc") as back:
        assert "frequency continuation" in back["direction"].attrs["long_name"]


def test_what_the_figures_call_located_continuation_reaches():
    """plots (a layer below continuation) counts a bracket as located to its own precision:
    continuation's must be finer, or every bifurcation would read "not located"."""
    assert continuation.LOCATE < _LOCATED
