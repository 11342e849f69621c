"""Sweeps: frequency responses with continuation, bifurcation samples, files, resume, errors."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
import xarray as xr

from harvester_sweep import chunk_store, chunks, cli, datasets, sweep
from harvester_sweep.outputs import RUN_OUTPUTS
from harvester_sweep.parameters import ParameterError, resolve_parameters
from harvester_sweep.scene import run_scene
from harvester_sweep.sweep import run_sweep
from harvester_sweep.sweep_file import load_sweep
from tests.helpers import FAST, assert_same_bits, phasor, spec


def test_up_sweep_stays_on_the_impacting_branch_and_down_sweep_on_the_linear_one():
    """Paper scene, gap 1 um: the stop hardens the response, so the up-sweep keeps striking
    well above 200 Hz while the down-sweep from 290 Hz stays off the stop (hysteresis)."""
    ds = run_sweep(spec({"frequency": [200, 215, 230, 245, 260, 275, 290]},
                        directions=["up", "down"]), progress=False)
    gap = resolve_parameters("paper")["gap"]
    assert (ds["status"] == 0).all()
    up, down = ds.sel(direction="up"), ds.sel(direction="down")
    band = [230.0, 245.0]
    assert (up["impacts_per_period"].sel(frequency=band) == 1).all()
    assert (up["x_max"].sel(frequency=band) > gap).all()
    assert (down["impacts_per_period"].sel(frequency=band) == 0).all()
    assert (down["x_max"].sel(frequency=band) < 0.9 * gap).all()
    assert (up["power"].sel(frequency=band) > 3 * down["power"].sel(frequency=band)).all()
    # Outside the band both directions reach the same orbit.
    for f in (200.0, 275.0):
        assert math.isclose(float(up["x_max"].sel(frequency=f)),
                            float(down["x_max"].sel(frequency=f)), rel_tol=1e-6)


def test_without_the_stop_the_response_is_the_closed_form_one():
    """hertz_stiffness = 0: the linear phasor solution, independent of the kernel, and no
    impacts where the motion passes the gap (there is no stop)."""
    ds = run_sweep(spec({"frequency": [120.0, 150.0, 190.0]},
                        {"hertz_stiffness": 0.0, "max_periods": 5000, "gap": 1e-6},
                        outputs=["power", "x_max", "impacts_per_period"]), progress=False)
    p = resolve_parameters("paper")
    assert (ds["status"] == 0).all()
    assert (ds["x_max"] > 1e-6).all() and (ds["impacts_per_period"] == 0).all()
    for f in ds["frequency"].values:
        X, V = phasor(**dict(p, frequency=f))
        point = ds.sel(frequency=f)
        assert math.isclose(float(point["x_max"]), abs(X), rel_tol=2e-3)
        assert math.isclose(float(point["power"]), abs(V) ** 2 / (2 * p["resistance"]),
                            rel_tol=2e-3)


def test_points_from_rest_are_the_scenes_of_their_grid_values():
    """Without directions each point runs from rest: the same numbers as ``scene``, at the
    right place of a 2-D grid (checks the axes are not swapped)."""
    ds = run_sweep(spec({"gap": [0.5e-6, 2e-6], "frequency": [140.0, 160.0, 180.0]}),
                   progress=False)
    assert ds["power"].dims == ("gap", "frequency")
    for gap in (0.5e-6, 2e-6):
        for f in (140.0, 180.0):
            scene = run_scene("paper", gap=gap, frequency=f, **FAST).metrics
            point = ds.sel(gap=gap, frequency=f)
            assert float(point["power"]) == scene["power"]
            assert int(point["periods_run"]) == scene["periods_run"]


def test_every_variable_has_cf_units_and_the_file_holds_the_run(tmp_path):
    out = tmp_path / "fr.nc"
    run_sweep(spec({"frequency": {"start": 130, "stop": 170, "num": 3},
                    "resistance": {"start": 1e3, "stop": 1e5, "num": 2, "scale": "log"}},
                   directions=["up"], outputs=["power", "approach_velocity", "strobe"],
                   samples=4), out, progress=False)
    assert not (tmp_path / "fr.nc.partial").exists()
    with xr.open_dataset(out) as ds:
        for name, var in ds.variables.items():  # (the direction's strings too)
            assert var.attrs.get("long_name") and var.attrs.get("units"), name
        assert ds["frequency"].attrs["units"] == "Hz"
        assert ds["resistance"].attrs["units"] == "Ohm"
        assert ds["resistance"].attrs["grid_spacing"] == "log"
        assert ds["status"].dtype == np.int8
        assert ds["status"].attrs["flag_meanings"] == "settled not_settled diverged too_stiff"
        assert list(ds["status"].attrs["flag_values"]) == [0, 1, 2, 3]
        assert ds["power"].dims == ("direction", "frequency", "resistance")
        assert ds["strobe_voltage"].dims == ("direction", "frequency", "resistance", "sample")
        # Fixed parameters, not the swept ones, are global attributes.
        assert ds.attrs["gap"] == 1e-6 and ds.attrs["gap_units"] == "m"
        assert ds.attrs["steps_per_period"] == 256
        assert "frequency" not in ds.attrs and "resistance" not in ds.attrs
        assert ds.attrs["source"].startswith("harvester_sweep ")
        assert ds.attrs["run_time"] > 0 and ds.attrs["run_time_units"] == "s"
        assert ds.attrs["history"][:2] == "20"


def test_outputs_select_what_is_computed_and_stored():
    grid = {"frequency": [140.0, 150.0]}
    ds = run_sweep(spec(grid, outputs=["power"]), progress=False)
    # error_estimate: on every point unless sweep.error_estimate says otherwise; the
    # periodic-orbit solver's outputs always
    assert set(ds.data_vars) == {"power", "status", "periods_run", "error_estimate",
                                 *RUN_OUTPUTS}
    assert "sample" not in ds.dims
    chunk = chunks.compute_chunk(load_sweep(spec(grid, outputs=["power"])), 0)
    assert chunk["strobe"].shape[2] == 0  # the kernel got S = 0: no strobe buffers

    ds = run_sweep(spec(grid, outputs=["x_max", "strobe"], samples=5), progress=False)
    assert set(ds.data_vars) == {"x_max", "orbit_period", "status", "periods_run",
                                 "strobe_displacement", "strobe_voltage", "error_estimate",
                                 *RUN_OUTPUTS}
    assert ds.sizes["sample"] == 5 and list(ds["sample"].values) == [-4, -3, -2, -1, 0]
    # Settled period-1 orbits: every stroboscopic sample is the same point y(nT).
    assert (ds["orbit_period"] == 1).all()
    x = ds["strobe_displacement"]
    assert float(abs(x - x.isel(sample=-1)).max()) < 1e-6 * float(ds["x_max"].max())


def test_result_does_not_depend_on_threads_or_chunking():
    grid = {"frequency": [150.0, 200.0, 250.0], "gap": [0.5e-6, 1e-6, 2e-6]}
    default = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = run_sweep(spec(grid, directions=["up", "down"], outputs=["power", "strobe"],
                             samples=3, chunk_size=3), progress=False)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = run_sweep(spec(grid, directions=["up", "down"], outputs=["power", "strobe"],
                             samples=3, chunk_size=1000), progress=False)
    finally:
        numba.set_num_threads(default)
    assert load_sweep(spec(grid, directions=["up"], chunk_size=3)).n_chunks == 3
    assert_same_bits(one, two)


def test_default_chunks_hold_enough_lines_for_the_lanes():
    """4096 points, or 128 whole lines under continuation (up to 2^17 points); a chunk_size
    given is kept."""
    fine = {"frequency": {"start": 100, "stop": 300, "num": 201},
            "gap": {"start": 1e-6, "stop": 2e-6, "num": 100}}
    swept = load_sweep(spec(fine, directions=["up", "down"]))
    assert swept.lines_per_chunk == 128 and swept.n_chunks == 2  # 200 lines
    assert load_sweep(spec(fine)).lines_per_chunk == 4096  # lines of one point
    assert load_sweep(spec(fine, directions=["up"], chunk_size=4096)).lines_per_chunk == 20
    long = {"frequency": {"start": 100, "stop": 300, "num": 2001}, "gap": [1e-6, 2e-6]}
    assert load_sweep(spec(long, directions=["up"])).lines_per_chunk == 2**17 // 2001  # memory


class Interrupted(Exception):
    pass


def _killed_after_one_chunk(sweep_dict, out, monkeypatch):
    """Run ``sweep_dict`` to ``out`` as if killed right after its first chunk reached the
    disk."""
    save = chunk_store.ChunkStore.save

    def save_then_stop(self, chunk, result):
        save(self, chunk, result)
        raise Interrupted

    monkeypatch.setattr(chunk_store.ChunkStore, "save", save_then_stop)
    with pytest.raises(Interrupted):
        run_sweep(sweep_dict, out, progress=False)
    monkeypatch.setattr(chunk_store.ChunkStore, "save", save)


def test_resume_after_an_interruption_gives_the_uninterrupted_file(tmp_path, monkeypatch):
    sweep_dict = spec({"frequency": [200.0, 230.0, 260.0], "gap": [1e-6, 2e-6]},
                      directions=["up", "down"], chunk_size=3)  # 4 chunks of one line
    whole = run_sweep(sweep_dict, tmp_path / "whole.nc", progress=False)

    out = tmp_path / "part.nc"
    _killed_after_one_chunk(sweep_dict, out, monkeypatch)
    assert not out.exists()
    assert len(list((tmp_path / "part.nc.partial").glob("chunk_*.npz"))) == 1

    with pytest.raises(ParameterError, match="--resume"):
        run_sweep(sweep_dict, out, progress=False)  # never overwritten silently

    computed = []
    compute = sweep.compute_chunk
    monkeypatch.setattr(sweep, "compute_chunk",
                        lambda s, chunk, *a, **k: computed.append(chunk) or compute(s, chunk,
                                                                                   *a, **k))
    resumed = run_sweep(sweep_dict, out, resume=True, progress=False)
    assert computed == [1, 2, 3]
    assert not (tmp_path / "part.nc.partial").exists()
    assert_same_bits(resumed, whole)
    with xr.open_dataset(out) as a, xr.open_dataset(tmp_path / "whole.nc") as b:
        assert_same_bits(a, b)


def test_a_partial_result_of_another_sweep_is_refused(tmp_path):
    out = tmp_path / "fr.nc"
    partial = tmp_path / "fr.nc.partial"
    partial.mkdir()
    (partial / "manifest.json").write_text('{"sweep_sha256": "0"}')
    with pytest.raises(ParameterError, match="another sweep"):
        run_sweep(spec({"frequency": [140.0]}), out, resume=True, progress=False)
    assert partial.exists()


def test_a_resume_of_a_finished_output_runs_nothing_and_replaces_no_other(tmp_path,
                                                                          monkeypatch):
    """A resume run once too often, after its sweep had finished, computed the whole sweep
    again; a resume of another sweep's finished file replaced it. The first now returns
    the file's result and computes nothing; the second, and a file that is no sweep's,
    are refused and left as they are."""
    sweep_dict = spec({"frequency": [140.0, 150.0]})
    out = tmp_path / "done.nc"
    whole = run_sweep(sweep_dict, out, progress=False)
    written = out.read_bytes()
    monkeypatch.setattr(sweep, "compute_chunk", lambda *a, **k: pytest.fail("computed"))
    assert_same_bits(run_sweep(sweep_dict, out, resume=True, progress=False), whole)
    other = spec({"frequency": [140.0, 160.0]})
    with pytest.raises(ParameterError, match="another sweep's finished result .* run "
                       "without --resume to replace it"):
        run_sweep(other, out, resume=True, progress=False)
    assert out.read_bytes() == written
    stray = tmp_path / "stray.nc"
    stray.write_text("not netCDF")
    with pytest.raises(ParameterError, match="no finished result of a sweep"):
        run_sweep(sweep_dict, stray, resume=True, progress=False)
    assert stray.read_text() == "not netCDF"


@pytest.mark.parametrize("resume", [False, True])
def test_a_partial_folder_without_a_manifest_is_in_the_way_either_way(tmp_path, resume):
    """An empty OUT.nc.partial/ (or a file of that name) holds nothing to resume: a plain
    run said "resume it", a resume "delete the folder"; both now say it is in the way."""
    for name, make in (("a.nc", lambda p: p.mkdir()), ("b.nc", lambda p: p.write_text(""))):
        make(tmp_path / f"{name}.partial")
        with pytest.raises(ParameterError, match=r"\.partial is in the way: it holds no "
                           "partial result .* nothing to resume; delete it"):
            run_sweep(spec({"frequency": [140.0]}), tmp_path / name, resume=resume,
                      progress=False)


def test_a_partial_result_of_another_orbit_solver_is_refused(tmp_path, monkeypatch):
    """A development install changes the orbit solver without changing the version or the
    engine: chunks it solved are not mixed with the new solver's."""
    from harvester_sweep import orbits

    sweep_dict = spec({"frequency": [140.0, 150.0]}, chunk_size=1)
    out = tmp_path / "part.nc"
    _killed_after_one_chunk(sweep_dict, out, monkeypatch)
    monkeypatch.setattr(orbits, "SOURCE_DIGEST", "0" * 64)
    with pytest.raises(ParameterError, match="another sweep"):
        run_sweep(sweep_dict, out, resume=True, progress=False)
    monkeypatch.undo()
    run_sweep(sweep_dict, out, resume=True, progress=False)  # (the same solver resumes it)
    assert out.exists()


def test_a_partial_result_with_another_grid_is_refused_by_the_cli(tmp_path, capsys,
                                                                  monkeypatch):
    first = tmp_path / "a.toml"
    first.write_text('[parameters]\nsteps_per_period = 256\nmax_periods = 2000\n'
                     '[grid]\nfrequency = [140.0, 150.0]\n[sweep]\nchunk_size = 1\n')
    out = tmp_path / "fr.nc"
    def killed_while_writing(ds, path):
        raise Interrupted

    monkeypatch.setattr(datasets, "write_netcdf", killed_while_writing)
    with pytest.raises(Interrupted):
        cli.main(["run", str(first), "--output", str(out), "--quiet"])
    monkeypatch.undo()
    second = tmp_path / "b.toml"
    second.write_text(first.read_text().replace("150.0", "160.0"))
    assert cli.main(["run", str(second), "--output", str(out), "--resume", "--quiet"]) == 2
    assert "another sweep" in capsys.readouterr().err
    assert cli.main(["run", str(first), "--output", str(out), "--resume", "--quiet"]) == 0


def test_a_diverged_point_is_flagged_and_the_others_finish():
    ds = run_sweep(spec({"hertz_stiffness": [9.03e8, 1e12], "frequency": [140.0, 150.0]},
                        {"max_periods": 300}, directions=["up"]), progress=False)
    status = ds["status"].sel(direction="up")
    assert (status.sel(hertz_stiffness=9.03e8) == 0).all()
    assert (status.sel(hertz_stiffness=1e12) == 2).all()
    assert np.isnan(ds["power"].sel(hertz_stiffness=1e12)).all()
    assert np.isfinite(ds["power"].sel(hertz_stiffness=9.03e8)).all()


BAD = [
    ({"grid": {"frequency": [140.0]}, "sweeps": {}}, "sweeps: unknown key"),
    ({"grid": {"frequency": [140.0]}, "sweep": {"direction": ["up"]}}, "sweep.direction: unknown"),
    ({"grid": {"frequncy": [140.0]}}, "grid.frequncy: unknown parameter"),
    ({"grid": {"contact_law": ["flores"]}}, "grid.contact_law: only numeric"),
    ({"grid": {"frequency": []}}, "grid.frequency: the list of values is empty"),
    # (a repeated value made a coordinate ds.sel could not pick a point of)
    ({"grid": {"frequency": [140.0, 150.0, 140.0]}},
     "grid.frequency: the value 140.0 [Hz] appears 2 times; an axis's values must differ"),
    ({"grid": {"frequency": {"start": 140, "stop": 140, "num": 5}}}, "appears 5 times"),
    # (they read "preset 'bimorph_tip' is unknown", "unknown parameter 'n_modes'")
    ({"preset": "bimorph_tip", "grid": {"frequency": [140.0]}},
     "preset 'bimorph_tip' is the beam model's: add model = \"beam\""),
    ({"parameters": {"n_modes": 2}, "grid": {"frequency": [140.0]}},
     "parameter 'n_modes' is the beam model's"),
    ({"grid": {"rod_modes": [1, 2]}}, "parameter 'rod_modes' is the beam model's"),
    ({"grid": {}}, "grid: give at least one"),
    ({"grid": {"frequency": {"start": 100, "stop": 200, "num": 0}}}, "grid.frequency.num"),
    ({"grid": {"frequency": {"start": 100, "stop": 200, "num": 2.5}}}, "grid.frequency.num"),
    ({"grid": {"frequency": {"start": 100, "stop": math.inf, "num": 3}}}, "grid.frequency.stop"),
    ({"grid": {"frequency": {"start": 100, "stop": 200}}}, "grid.frequency.num: missing"),
    ({"grid": {"frequency": {"start": 100, "stop": 200, "num": 3, "step": 1}}},
     "grid.frequency.step: unknown"),
    ({"grid": {"gap": {"start": 0, "stop": 1e-6, "num": 3, "scale": "log"}}},
     "grid.gap: scale = \"log\" needs start > 0"),
    ({"grid": {"gap": {"start": 1e-7, "stop": 1e-6, "num": 3, "scale": "ln"}}},
     "grid.gap.scale"),
    ({"grid": {"damping_ratio": [0.01, -0.1]}}, "grid.damping_ratio [-] = -0.1"),
    ({"grid": {"frequency": [140.0, math.nan]}}, "grid.frequency [Hz] = nan"),
    ({"grid": {"frequency": [140.0, "fast"]}}, "grid.frequency [Hz] = 'fast' is not a number"),
    ({"grid": {"max_periods": [256, 300.5]}}, "grid.max_periods [-] = 300.5"),
    ({"grid": {"frequency": [20.0, 140.0]}, "parameters": {"steps_per_period": 64}},
     "at the grid point frequency = 20"),
    ({"grid": {"gap": [1e-6]}, "parameters": {"gap": 2e-6}}, "grid.gap: gap is also set"),
    ({"grid": {"gap": [1e-6]}, "parameters": {"gapp": 2e-6}}, "unknown parameter 'gapp'"),
    ({"grid": {"gap": [1e-6]}, "sweep": {"directions": ["up"]}}, "sweep.directions: continuation"),
    ({"grid": {"frequency": [140.0]}, "sweep": {"directions": ["sideways"]}},
     "sweep.directions: 'sideways'"),
    ({"grid": {"frequency": [140.0]}, "sweep": {"outputs": ["energy"]}}, "sweep.outputs: 'energy'"),
    ({"grid": {"frequency": [140.0]}, "sweep": {"outputs": []}}, "sweep.outputs: must be"),
    ({"grid": {"frequency": [140.0]}, "sweep": {"samples": 8}}, "sweep.samples: stroboscopic"),
    ({"grid": {"frequency": [140.0]}, "sweep": {"outputs": ["strobe"], "samples": 0}},
     "sweep.samples [-] = 0"),
    ({"grid": {"frequency": [140.0]}, "sweep": {"chunk_size": 0}}, "sweep.chunk_size [-] = 0"),
    ({"grid": {"frequency": [140.0]}, "preset": "nope"}, "preset 'nope' is unknown"),
]


@pytest.mark.parametrize("bad, message", BAD, ids=[m for _, m in BAD])
def test_bad_sweeps_fail_before_any_work_naming_the_key(bad, message, monkeypatch):
    monkeypatch.setattr(sweep, "compute_chunk", None)  # any work would fail differently
    with pytest.raises(ParameterError) as error:
        run_sweep(bad, progress=False)
    assert message in str(error.value)


def test_the_cli_exits_2_on_a_bad_sweep_file_without_a_traceback(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text("[grid]\nfrequency = { start = 100, stop = 200, num = 0 }\n")
    assert cli.main(["run", str(path), "--output", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert "grid.frequency.num" in err and "Traceback" not in err
    path.write_text("[grid\n")
    assert cli.main(["run", str(path), "--output", str(tmp_path / "x.nc")]) == 2
    assert "not valid TOML" in capsys.readouterr().err
    assert cli.main(["run", str(tmp_path / "none.toml"), "--output", "x.nc"]) == 2
    assert cli.main(["run", str(path), "--output", str(tmp_path / "x.csv")]) == 2
    assert not list(tmp_path.glob("*.partial"))


def test_cli_run_and_plot(tmp_path):
    path = tmp_path / "sweep.toml"
    path.write_text('preset = "paper"\n[parameters]\nsteps_per_period = 256\n'
                    'max_periods = 2000\n[grid]\nfrequency = [140.0, 200.0, 240.0]\n'
                    '[sweep]\ndirections = ["up", "down"]\noutputs = ["power", "x_max", '
                    '"strobe"]\nsamples = 4\n')
    out, fig = tmp_path / "fr.nc", tmp_path / "fr.png"
    assert cli.main(["run", str(path), "--output", str(out), "--quiet"]) == 0
    assert cli.main(["plot", str(out), "--output", str(fig)]) == 0
    assert fig.stat().st_size > 10_000


def test_plot_draws_maps_of_two_axes_and_refuses_three(tmp_path):
    from harvester_sweep.plots import plot_sweep

    ds = run_sweep(spec({"frequency": [140.0, 160.0], "gap": [1e-6, 2e-6]},
                        directions=["up", "down"], outputs=["power"]), progress=False)
    plot_sweep(ds, tmp_path / "map.png")
    assert (tmp_path / "map.png").exists()
    three = ds.expand_dims(resistance=[1e4])
    with pytest.raises(ParameterError, match="3 grid axes"):
        plot_sweep(three)


def test_example_sweep_file_is_valid():
    from pathlib import Path

    example = Path(__file__).parents[2] / "examples" / "paper_frequency_response.toml"
    loaded = load_sweep(example)
    assert loaded.directions == ("up", "down") and loaded.fixed["gap"] == 1e-6
    assert loaded.grid["frequency"][[0, -1]].tolist() == [100.0, 300.0]


def test_error_estimate_on_a_sample_or_every_point_whatever_the_chunking():
    spec = {"preset": "paper", "grid": {"frequency": {"start": 120, "stop": 160, "num": 9},
                                         "gap": [1e-6, 3e-6]},
             "sweep": {"directions": ["up"], "outputs": ["power"]}}
    every = sweep.run_sweep({**spec, "sweep": {**spec["sweep"], "error_estimate": "all",
                                          "chunk_size": 9}}, progress=False)
    sampled = sweep.run_sweep(spec, progress=False)
    none = sweep.run_sweep({**spec, "sweep": {**spec["sweep"], "error_estimate": "none"}},
                     progress=False)
    assert "error_estimate" not in none
    assert every.error_estimate.attrs["units"] == "1"
    settled = every.status.values == 0
    assert np.all(np.isfinite(every.error_estimate.values[settled]))
    assert np.all(every.error_estimate.values[settled] < 1e-5)
    known = np.isfinite(sampled.error_estimate.values)
    assert 0 < known.sum() <= sampled.status.size
    np.testing.assert_array_equal(sampled.error_estimate.values[known],
                                  every.error_estimate.values[known])
