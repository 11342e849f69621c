"""The harvester-sweep command line: table, JSON, netCDF, plot and user errors."""

import json
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from harvester_sweep import PARAMETERS
from harvester_sweep.cli import main
from harvester_sweep.outputs import SCENE_OUTPUTS

JSON_KEYS = {"power", "v_rms", "v_peak", "power_peak", "x_max", "x_min", "contact_force_max",
             "impacts_per_period", "approach_velocity", "orbit_period", "converged",
             "periods_run", "steps_per_period", "run_time"}


def test_scene_json_has_every_metric(capsys):
    assert main(["scene", "--preset", "paper", "--json", "--set", "gap=1.5e-6"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert JSON_KEYS <= set(metrics)
    assert metrics["converged"] is True and metrics["status"] == "settled"
    assert isinstance(metrics["steps_per_period"], int) and metrics["steps_per_period"] >= 64


def test_scene_table_is_readable(capsys):
    assert main(["scene"]) == 0
    out = capsys.readouterr().out
    assert "100 nF is assumed" in out
    assert "approach_velocity" in out and "m/s" in out


def test_output_netcdf_and_plot(tmp_path, capsys):
    nc, png = tmp_path / "scene.nc", tmp_path / "scene.png"
    assert main(["scene", "--output", str(nc), "--plot", str(png), "--set", "resistance=2e4"]) == 0
    assert png.stat().st_size > 10_000
    with xr.open_dataset(nc) as ds:
        for name, var in ds.variables.items():
            assert var.attrs.get("units") and var.attrs.get("long_name"), name
        for name in PARAMETERS:
            assert name in ds.attrs, name
        assert ds.attrs["resistance"] == 2e4 and ds.attrs["resistance_units"] == "Ohm"
        assert set(SCENE_OUTPUTS) <= set(ds.data_vars)
        assert {"displacement", "velocity", "voltage", "instantaneous_power",
                "contact_force"} <= set(ds.data_vars)
        # The recorded series is the steady orbit: its peak is the metric.
        assert float(ds.voltage.max()) <= float(ds.v_peak) * (1 + 1e-9)
        assert np.all(ds.contact_force.values >= 0)


@pytest.mark.parametrize("argv, words", [
    (["scene", "--preset", "foo"], "invalid choice: 'foo'"),
    (["run", "sweep.toml"], "required: --output"),
    (["nosuch"], "invalid choice: 'nosuch'"),
])
def test_usage_errors_exit_2_with_one_line_naming_the_help(argv, words, capsys):
    """argparse printed its usage block above the error: three to four lines."""
    with pytest.raises(SystemExit) as exited:
        main(argv)
    err = capsys.readouterr().err
    assert exited.value.code == 2 and words in err and "--help" in err
    assert err.count("\n") == 1 and "usage:" not in err


@pytest.mark.parametrize("stop", ["-1e-6", "-1E-06", "-2.5e+0", "-0.5", "-3"])
def test_a_negative_number_in_exponent_form_is_a_value_not_an_option(stop):
    """`beam-continue gap 1e-6 -1e-6` (to a preloaded stop) said 'the following arguments
    are required: stop': argparse takes -1e-6 for an option, -0.5 for a value."""
    from harvester_sweep.cli import _parser

    args = _parser().parse_args(["beam-continue", "gap", "1e-6", stop, "--output", "x.nc"])
    assert float(args.stop) == float(stop)


@pytest.mark.parametrize("argv, words", [
    (["scene", "--set", "mass=-1"], "mass [kg]"),
    (["scene", "--set", "restitution=0"], "restitution [-]"),
    (["scene", "--set", "gap=inf"], "gap [m]"),
    (["scene", "--set", "frequency=abc"], "frequency [Hz]"),
    (["scene", "--set", "colour=red"], "unknown parameter 'colour'"),
    (["scene", "--set", "steps_per_period=17"], "steps_per_period [-]"),
])
def test_user_errors_exit_2_with_one_line(argv, words, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "Traceback" not in err


def test_divergence_is_reported_not_printed_as_numbers(capsys):
    # 20 steps per period pass the forcing check but cannot resolve the hard contact. (The
    # paper's contact, 0.27 ms, fits in the graded and quarter sub-steps next to its
    # switches at 0.36 ms a step: its power comes out within 0.3 % of 1024 steps.)
    assert main(["scene", "--json", "--set", "steps_per_period=20", "--set",
                 "hertz_stiffness=9.03e10", "--set", "restitution=0.5"]) == 3
    captured = capsys.readouterr()
    metrics = json.loads(captured.out)
    assert metrics["status"] == "diverged" and metrics["converged"] is False
    assert metrics["power"] is None and metrics["v_peak"] is None
    assert set(metrics["floquet_multipliers_real"] + metrics["floquet_multipliers_imag"]) \
        == {None}  # (the imaginary parts were 0)
    assert "diverged" in captured.err and "steps_per_period" in captured.err


def test_console_script_runs_without_traceback():
    ok = subprocess.run([sys.executable, "-m", "harvester_sweep.cli", "scene", "--json"],
                        capture_output=True, text=True)
    assert ok.returncode == 0 and json.loads(ok.stdout)["converged"]
    bad = subprocess.run([sys.executable, "-m", "harvester_sweep.cli", "scene", "--set",
                          "mass=0"], capture_output=True, text=True)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr and "mass [kg]" in bad.stderr


def test_a_step_beyond_the_stability_bound_warns_once_per_run(tmp_path, capsys):
    """An explicit step beyond the contact's stability bound at every point of a sweep: one
    warning naming a point's step and bound, and one line counting the others (each point
    used to give its own line)."""
    sweep = tmp_path / "stiff.toml"
    sweep.write_text('preset = "paper"\n[parameters]\nsteps_per_period = 256\n'
                     "max_periods = 300\nhertz_stiffness = 1e12\n[grid]\n"
                     "frequency = { start = 130, stop = 160, num = 8 }\n")
    assert main(["run", str(sweep), "--output", str(tmp_path / "stiff.nc")]) == 0
    err = capsys.readouterr().err
    assert err.count("estimated RK4 stability bound") == 1
    more = [line for line in err.splitlines() if "more parameter sets" in line]
    assert len(more) == 1 and int(more[0].split("and ")[1].split()[0]) >= 7


def test_points_that_do_not_settle_are_told_with_their_share_of_the_work(tmp_path, capsys):
    """A point that does not settle runs its whole max_periods: the warning counting them
    says what share of the sweep's RK4 steps they took (read here from the file), so that
    a designer sees what max_periods costs."""
    sweep = tmp_path / "short.toml"
    sweep.write_text('preset = "paper"\n[parameters]\nmax_periods = 12\n[grid]\n'
                     "gap = { start = 0.5e-6, stop = 1e-3, num = 2 }\n"
                     "frequency = { start = 120, stop = 160, num = 4 }\n")
    assert main(["run", str(sweep), "--output", str(tmp_path / "short.nc"), "--quiet"]) == 0
    with xr.open_dataset(tmp_path / "short.nc") as ds:
        steps, status = ds["rk4_steps"].values.astype(float), ds["status"].values
    unsettled = status == 1
    share = steps[unsettled].sum() / steps.sum()
    assert 0 < unsettled.sum() < status.size and share >= 0.1  # (what the case is for)
    line, = [line for line in capsys.readouterr().err.splitlines() if "not settled" in line]
    assert f"{unsettled.sum()} of {status.size} points not settled" in line
    assert f"they took {100 * share:.0f} % of the sweep's RK4 steps" in line
    assert "lower it to spend less on them" in line


S_CURVE = """preset = "paper"
[parameters]
gap = 1e-6
[continuation]
parameter = "frequency"
start = 300.0
stop = 210.0
"""


def test_continue_writes_the_branch_lists_its_bifurcations_and_plots_it(tmp_path, capsys):
    """From the linear orbit at 300 Hz down to 210 Hz: the grazing and both folds, a CF
    file, and the branch drawn over a sweep along the same axis."""
    spec, nc, png = tmp_path / "s.toml", tmp_path / "branch.nc", tmp_path / "branch.png"
    spec.write_text(S_CURVE)
    assert main(["continue", str(spec), "--output", str(nc)]) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if line.startswith("  ")]
    kinds = [row[0] for row in rows if row[0] in ("fold", "grazing")]
    assert kinds == ["grazing", "fold", "fold"], out
    with xr.open_dataset(nc) as ds:
        assert ds["frequency"].attrs["units"] == "Hz"
        flags = ds["bifurcation"].attrs
        assert flags["flag_meanings"].split() == ["none", "fold", "period_doubling",
                                                  "neimark_sacker", "grazing"]
        assert list(flags["flag_values"]) == [0, 1, 2, 3, 4]
        for name, var in ds.data_vars.items():
            assert "units" in var.attrs and "long_name" in var.attrs, name
        assert ds["frequency"].min() == pytest.approx(210.0)
    sweep = tmp_path / "sweep.nc"
    (tmp_path / "sweep.toml").write_text(
        'preset = "paper"\n[parameters]\ngap = 1e-6\nsteps_per_period = 512\n'
        '[grid]\nfrequency = { start = 240, stop = 300, num = 7 }\n'
        '[sweep]\ndirections = ["up", "down"]\noutputs = ["x_max", "power"]\n')
    assert main(["run", str(tmp_path / "sweep.toml"), "--output", str(sweep), "--quiet"]) == 0
    assert main(["plot", str(nc), "--over", str(sweep), "--output", str(png)]) == 0
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize("table, words", [
    ("start = 300.0", ["continuation.stop", "missing"]),
    ('start = 300.0\nstop = 240.0\nparameter = "contact_law"', ["continuation.parameter"]),
    ("start = 300.0\nstop = 240.0\nstep = 2.0", ["continuation.step", "(0, 1]"]),
    ("start = 300.0\nstop = -1.0", ["continuation.stop", "frequency", "Hz"]),
    ("start = 300.0\nstop = 240.0\nbudget = 3", ["continuation.budget", "unknown"]),
    ('start = 300.0\nstop = 240.0\nperiod_doubling = "follow"', ["period_doubling"]),
    ("start = 300.0\nstop = 240.0\nmin_step = 0.1\nmax_step = 0.01",  # (read backwards)
     ["continuation.min_step [-] = 0.1: must not exceed max_step = 0.01"]),
])
def test_bad_continuation_files_exit_2_with_one_line(tmp_path, table, words, capsys):
    _refused_in_one_line("continue", f"[continuation]\n{table}", words, tmp_path, capsys)


BASINS = """preset = "paper"
[parameters]
steps_per_period = 512
[grid]
frequency = [100.0, 245.0]
[basins]
samples = 32
shock = 0.03
"""


def test_basins_writes_the_map_summarises_it_and_plots_it(tmp_path, capsys):
    """A one-axis map and a one-point run: CF files, a summary on stdout, the figures."""
    spec, nc, png = tmp_path / "b.toml", tmp_path / "basins.nc", tmp_path / "basins.png"
    spec.write_text(BASINS)
    assert main(["basins", str(spec), "--output", str(nc), "--plot", str(png), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("2 point(s) x 32 starts (base shock"), out
    with xr.open_dataset(nc) as ds:
        assert ds["frequency"].attrs["units"] == "Hz" and ds.attrs["shock_units"] == "m/s"
        for name, var in ds.data_vars.items():
            assert "units" in var.attrs and "long_name" in var.attrs, name
        assert ds["basin_fraction"].dims == ("frequency", "attractor")
        assert float(ds["basin_fraction"].sel(frequency=100.0)[0]) == 1.0
    assert png.stat().st_size > 10_000
    spec.write_text(BASINS.replace("frequency = [100.0, 245.0]", "").replace(
        "shock = 0.03", "box = { x = 2e-6 }"))
    assert main(["basins", str(spec), "--output", str(nc), "--quiet"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()[2:]]
    assert rows and rows[0][0] == "1", rows  # the attractors, one a line
    assert main(["plot", str(nc), "--output", str(png)]) == 0


@pytest.mark.parametrize("table, words", [
    ("[basins]\nshock = -1.0", ["basins.shock [m/s] = -1.0"]),
    ("[basins]\nsamples = 0", ["basins.samples"]),
    ("[basins]\nwho = 1", ["basins.who", "unknown"]),
    ("[grid]\nstiffness = [1.0]", ["grid.stiffness", "unknown parameter"]),
    ("[grid]\nfrequency = [-5.0]", ["grid.frequency", "Hz"]),
    ("[basins]\nshock = 0.01\nbox = { x = 1e-6 }", ["box and shock"]),
])
def test_bad_basin_files_exit_2_with_one_line(tmp_path, table, words, capsys):
    _refused_in_one_line("basins", table, words, tmp_path, capsys)


def _refused_in_one_line(command, table, words, tmp_path, capsys):
    """``command`` on a paper-preset file with ``table`` exits 2 with one error line that
    holds every one of ``words``, and writes nothing."""
    spec = tmp_path / "s.toml"
    spec.write_text(f'preset = "paper"\n{table}\n')
    assert main([command, str(spec), "--output", str(tmp_path / "b.nc")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("harvester-sweep: error:"), err
    for word in words:
        assert word in err, err
    assert not (tmp_path / "b.nc").exists()
