"""Each analysis checks its input once: the command line hands the spec its reader checked
to the analysis, which takes it as it is; each default is written in one place; a sweep's
run-time estimate measures its rate, a refused point's says the one nominal rate."""

from __future__ import annotations

import inspect
import re

import pytest

from harvester_sweep import (
    basin_file,
    basin_map,
    basins,
    branch_file,
    continuation,
    continue_branch,
    datasets,
    run_scene,
    scene,
    sweep_file,
    timescales,
)
from harvester_sweep import cli as cli_module
from harvester_sweep.cli import main
from harvester_sweep.packing import refusal
from harvester_sweep.parameters import (
    DEFAULT_PRESET,
    ParameterError,
    StabilityWarning,
    resolve_parameters,
)
from harvester_sweep.run_estimate import estimate


class _Stop(Exception):
    """Raised in place of the integration: these tests look at what comes before it."""


def _counting(monkeypatch, function, *modules):
    """Replace ``function`` (by its name) in each of ``modules`` that binds it by a wrapper
    that counts its calls; the list of the calls' arguments."""
    calls = []

    def counted(*args, **kwargs):
        calls.append((args, kwargs))
        return function(*args, **kwargs)

    for module in modules:
        monkeypatch.setattr(module, function.__name__, counted, raising=False)
    return calls


def test_run_reads_and_checks_the_sweep_file_once(tmp_path, monkeypatch):
    sweep = tmp_path / "s.toml"
    sweep.write_text('preset = "paper"\n[parameters]\nsteps_per_period = 512\n'
                     '[grid]\nfrequency = [140.0, 150.0]\n[sweep]\noutputs = ["power"]\n')
    reads = _counting(monkeypatch, sweep_file.read_toml, sweep_file)
    assert main(["run", str(sweep), "--output", str(tmp_path / "s.nc"), "--quiet"]) == 0
    assert len(reads) == 1, reads


def test_continue_checks_its_file_once(tmp_path, monkeypatch):
    spec = tmp_path / "c.toml"
    spec.write_text('[parameters]\ngap = 1e-6\n[continuation]\nstart = 300.0\nstop = 210.0\n')
    checks = _counting(monkeypatch, continuation.check_continuation, continuation, branch_file)
    taken = []

    def stop(spec):
        taken.append(spec)
        raise _Stop

    monkeypatch.setattr(continuation, "_continue", stop)
    with pytest.raises(_Stop):
        main(["continue", str(spec), "--output", str(tmp_path / "c.nc")])
    assert len(checks) == 1, checks
    # the problem continued is the file's, its first point the parameters at the start
    (problem,) = taken
    assert (problem.parameter, problem.start, problem.stop) == ("frequency", 300.0, 210.0)
    assert problem.base == resolve_parameters("paper", gap=1e-6, frequency=300.0,
                                              steps_per_period=problem.steps)


def test_a_branch_dataset_takes_its_parameters_from_the_spec(monkeypatch):
    """The branch's dataset writes the fixed parameters its checked spec holds, without
    resolving them again."""
    spec = branch_file.load_continuation({
        "parameters": {"gap": 1.0, "steps_per_period": 256},  # (stop out of reach: quick)
        "continuation": {"start": 140.0, "stop": 141.0, "max_points": 3}})
    again = _counting(monkeypatch, resolve_parameters, datasets)
    ds = continue_branch(spec)
    assert again == []
    fixed = dict(spec.base)
    fixed.pop("frequency")
    for name, value in fixed.items():
        written = ds.attrs[name]
        assert written == (str(value).lower() if value is None or isinstance(value, bool)
                           else value), name


def test_basins_checks_its_file_once(tmp_path, monkeypatch):
    spec = tmp_path / "b.toml"
    spec.write_text('[parameters]\nsteps_per_period = 512\n[grid]\n'
                    'frequency = [100.0, 245.0]\n[basins]\nsamples = 8\n')
    axes = _counting(monkeypatch, sweep_file.axis, basins, basin_file)
    taken = []

    def stop(spec, *args):  # (the points solved, as the spec resolves them)
        taken.append([spec.point(i) for i in range(spec.n_points)])
        raise _Stop

    monkeypatch.setattr(basins, "_solve", stop)
    with pytest.raises(_Stop):
        main(["basins", str(spec), "--output", str(tmp_path / "b.nc"), "--quiet"])
    assert len(axes) == 1, axes  # one grid axis, read once
    assert taken == [[resolve_parameters("paper", steps_per_period=512, frequency=f)
                      for f in (100.0, 245.0)]]


def test_scene_checks_its_input_once(monkeypatch, capsys):
    """The command line checks a scene's values once and hands them over: the parameters
    are resolved once, and an explicit step beyond the contact's stability bound warns once,
    not once per check."""
    calls = _counting(monkeypatch, resolve_parameters, scene, cli_module)
    taken = []

    def stop(packed, **options):
        taken.append(packed)
        raise _Stop

    monkeypatch.setattr(scene, "solve", stop)
    argv = ["scene", "--set", "steps_per_period=256", "--set", "hertz_stiffness=1e12",
            "--set", "gap=2e-6"]
    with pytest.raises(_Stop):
        main(argv)
    assert len(calls) == 1, calls
    err = capsys.readouterr().err
    assert err.count("estimated RK4 stability bound") == 1 and "more parameter sets" not in err
    # the point run is the one checked
    (packed,) = taken
    with pytest.warns(StabilityWarning):
        expected = scene.pack_points([resolve_parameters("paper", steps_per_period=256,
                                                         hertz_stiffness=1e12, gap=2e-6)])
    assert (packed.rows == expected.rows).all() and (packed.states == expected.states).all()


def test_a_file_and_a_call_take_the_same_defaults():
    """An option left out of a file has the value it has when left out of the call."""
    branch = branch_file.load_continuation({"continuation": {"start": 300.0, "stop": 250.0}})
    call = inspect.signature(continue_branch).parameters
    assert branch.preset == call["preset"].default
    assert branch.parameter == call["parameter"].default
    for name in ("step", "min_step", "max_step", "max_points"):
        assert getattr(branch, name) == call[name].default, name
    assert branch.switch == (call["period_doubling"].default == "switch")
    grid = basin_file.load_basins({})
    call = inspect.signature(basin_map).parameters
    for name in ("preset", "samples", "seed", "box", "shock"):
        assert getattr(grid, name) == call[name].default, name
    # one default preset: a sweep file, the scene's and the command line's
    assert sweep_file.load_sweep({"grid": {"frequency": [140.0]}}).preset \
        == inspect.signature(run_scene).parameters["preset"].default \
        == cli_module._parser().parse_args(["scene"]).preset \
        == DEFAULT_PRESET == branch.preset == grid.preset


def test_a_checked_spec_is_taken_whole_or_refused():
    """Beside a checked spec, any other argument would be ignored: it is refused."""
    branch = branch_file.load_continuation({"continuation": {"start": 300.0, "stop": 250.0}})
    for kwargs in ({"gap": 2e-6}, {"max_points": 10}, {"parameter": "gap"}):
        with pytest.raises(ParameterError, match="ContinuationSpec is the whole problem"):
            continue_branch(branch, **kwargs)
    grid = basin_file.load_basins({"grid": {"frequency": [100.0]}})
    for kwargs in ({"samples": 5}, {"steps_per_period": 512}, {"preset": "strong_coupling"}):
        with pytest.raises(ParameterError, match="BasinSpec is the whole problem"):
            basin_map(grid, **kwargs)
    with pytest.raises(ParameterError, match="SceneSpec is the whole problem"):
        run_scene(scene.check_scene(gap=2e-6), gap=3e-6)


def test_a_sweep_measures_its_rate_and_a_refused_point_says_the_nominal_one(monkeypatch):
    """A sweep's estimate runs on the rate it measures on this machine, never on the
    nominal rate (issue 44: that one was 15 to 70 times off on the examples); a refused
    point, which nothing runs, says its time at the nominal rate, the one place it is
    written (timescales.STEPS_PER_SECOND)."""
    spec = sweep_file.load_sweep({"grid": {"frequency": [140.0, 150.0]}})
    stiff = resolve_parameters("paper", contact_damping=1.07e11, max_steps_per_period=100_000)

    def seconds():
        said = re.search(r"about ([\d.]+) s per point", refusal(stiff))
        return estimate(spec, spec.n_points, 1), float(said.group(1))

    sweep_before, point_before = seconds()
    monkeypatch.setattr(timescales, "STEPS_PER_SECOND", timescales.STEPS_PER_SECOND / 1000)
    sweep_after, point_after = seconds()
    # (the sweep's sample is measured once per process: the same numbers unless the
    # nominal rate entered them)
    assert sweep_after == sweep_before
    assert point_after == pytest.approx(1000 * point_before, rel=0.05)  # (two figures)
