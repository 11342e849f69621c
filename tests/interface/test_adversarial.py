"""Faults and bad input found by trying the tool as an adversarial user would (issue 46):
workers that keep dying, bad addresses and types from Python, files the tool did not
write, Ctrl-C outside a sweep, grids too large to count, and the files a run cannot write.
Each ends in one line (exit 2, or 130 for Ctrl-C) and keeps the finished work."""

from __future__ import annotations

import errno
import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from harvester_sweep import chunk_store, cli, cluster, datasets
from harvester_sweep.parameters import ParameterError
from harvester_sweep.sweep import run_sweep
from harvester_sweep.sweep_file import load_sweep
from tests.helpers import assert_same_bits, spec

SWEEP = spec({"frequency": [200.0, 230.0, 260.0], "gap": [1e-6, 2e-6]},
             directions=["up", "down"], chunk_size=3)  # 4 chunks of one line


@pytest.fixture(scope="module")
def whole():
    """The sweep run without a fault, in memory."""
    return run_sweep(SWEEP, progress=False)


def _one_line(capsys) -> str:
    err = [line for line in capsys.readouterr().err.splitlines()
           if "compiling the RK4 kernel" not in line]  # (said when the cache is cold)
    assert len(err) == 1, err
    return err[0]


# -- 1: dask workers that keep dying, or none left ---------------------------------------

def test_workers_that_keep_dying_end_in_one_line_and_keep_the_finished_chunks(
        tmp_path, monkeypatch, whole):
    dask = pytest.importorskip("dask")
    pytest.importorskip("dask.distributed")
    compute = cluster.compute_chunk
    out = tmp_path / "fr.nc"
    sealed = tmp_path / "fr.nc.partial" / "chunk_000000.json"

    def dies_after_chunk_0(spec, chunk, *args):  # (a closure: sent to the worker by value)
        if chunk != 0:
            # Once chunk 0 is saved (a result still held by a worker dies with it); the
            # chunks run in the order they were given, so this waits only for chunk 0.
            deadline = time.monotonic() + 120
            while not sealed.exists() and time.monotonic() < deadline:
                time.sleep(0.05)
            os._exit(1)  # as a worker killed by the kernel's OOM killer or kill -9
        return compute(spec, chunk, *args)

    monkeypatch.setattr(cluster, "compute_chunk", dies_after_chunk_0)
    # (dask gives up on a task after it killed this many workers more: 0 keeps it short)
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        with pytest.raises(ParameterError) as raised:  # (cluster.ClusterError: one line)
            run_sweep(SWEEP, out, workers=1, progress=False)
    message = str(raised.value)
    assert len(message.splitlines()) == 1
    assert "3 of 4 chunks did not come back" in message and "kept dying" in message
    assert "the 1 finished chunks are kept" in message and "--resume" in message
    assert not out.exists()
    monkeypatch.undo()
    assert_same_bits(run_sweep(SWEEP, out, resume=True, progress=False), whole)


def test_a_cluster_with_no_worker_left_is_given_up_not_waited_on_for_ever(tmp_path,
                                                                          monkeypatch):
    pytest.importorskip("dask.distributed")
    from dask.distributed import LocalCluster

    monkeypatch.setattr(cluster, "NO_WORKERS_SECONDS", 0.5, raising=False)
    outcome = {}

    def run(address):
        try:
            run_sweep(SWEEP, tmp_path / "fr.nc", scheduler=address, progress=False)
        except BaseException as error:  # noqa: BLE001 (handed to the test's thread)
            outcome["error"] = error

    with LocalCluster(n_workers=0, processes=False, dashboard_address=":0") as empty:
        # (in a thread: before the fix the run waits for ever, and the test must end)
        thread = threading.Thread(target=run, args=(empty.scheduler_address,), daemon=True)
        thread.start()
        thread.join(timeout=120)
    assert not thread.is_alive(), "the run still waits for a worker"
    error = outcome.get("error")
    assert isinstance(error, cluster.ClusterError), error
    assert "no dask worker was left" in str(error) and "no chunk was finished" in str(error)
    assert not (tmp_path / "fr.nc.partial").exists()


# -- 7: a scheduler address that is none -------------------------------------------------

@pytest.mark.parametrize("address", ["notanaddress", "tcp://host-without-port"])
def test_a_scheduler_that_is_no_address_is_one_line_before_any_work(address, tmp_path, capsys):
    pytest.importorskip("dask.distributed")
    (tmp_path / "fr.toml").write_text("[grid]\nfrequency = [140.0]\n")
    argv = ["run", str(tmp_path / "fr.toml"), "--output", str(tmp_path / "x.nc"), "--quiet",
            "--scheduler", address]
    assert cli.main(argv) == 2
    line = _one_line(capsys)
    assert f"scheduler = '{address}'" in line and "not the address" in line
    assert not list(tmp_path.glob("x.nc*"))


# -- 11: Python's arguments of the wrong type --------------------------------------------

@pytest.mark.parametrize("workers", ["2", 1.5, 0, True, [2]])
def test_workers_that_are_no_count_raise_parameter_error(workers):
    with pytest.raises(ParameterError, match=r"workers \[-\] = .*: must be an integer >= 1"):
        run_sweep(SWEEP, workers=workers, progress=False)


def test_a_scheduler_that_is_not_text_raises_parameter_error():
    with pytest.raises(ParameterError, match="scheduler = 8786: must be the address"):
        run_sweep(SWEEP, scheduler=8786, progress=False)


class _Taken(Exception):
    """Raised in place of the work: what came before it was accepted."""


def test_numpy_scalars_are_numbers_to_continue_branch(monkeypatch):
    from harvester_sweep import continuation, continue_branch

    taken = []
    monkeypatch.setattr(continuation, "_continue",
                        lambda spec: taken.append(spec) or (_ for _ in ()).throw(_Taken))
    with pytest.raises(_Taken):
        continue_branch("paper", "frequency", np.float64(150.0), np.float32(160.0),
                        step=np.float32(0.01), min_step=np.float64(1e-6),
                        max_step=np.float32(0.05), max_points=np.int64(100))
    (spec_,) = taken
    assert spec_.max_points == 100 and type(spec_.max_points) is int
    assert spec_.step == pytest.approx(0.01) and type(spec_.step) is float
    with pytest.raises(ParameterError, match=r"max_points \[-\] = .*must be an integer"):
        continue_branch("paper", "frequency", 150.0, 160.0, max_points=np.float64(100.5))


def test_numpy_scalars_are_numbers_to_basin_fractions(monkeypatch):
    from harvester_sweep import basin_fractions, basins

    taken = []
    monkeypatch.setattr(basins, "_solve",
                        lambda spec, *a: taken.append(spec) or (_ for _ in ()).throw(_Taken))
    with pytest.raises(_Taken):
        basin_fractions(samples=np.int64(4), seed=np.uint8(3), steps_per_period=256)
    assert (taken[0].samples, taken[0].seed) == (4, 3)
    with pytest.raises(ParameterError, match=r"samples \[-\] = .*must be an integer"):
        basin_fractions(samples=np.float32(4.5))


def test_a_basin_grid_given_as_a_list_is_a_parameter_error():
    from harvester_sweep import basin_map

    with pytest.raises(ParameterError, match="grid: must be a table"):
        basin_map([("gap", [1e-6])], "paper", samples=4)


# -- 12: a full disk at the final write, a 2-D axis, a file name not .nc -----------------

def test_a_full_disk_at_the_final_write_says_so_when_netcdf_does_not(tmp_path, capsys,
                                                                     monkeypatch):
    (tmp_path / "fr.toml").write_text("[parameters]\nsteps_per_period = 256\n"
                                      "[grid]\nfrequency = [200.0, 230.0]\n")
    out = tmp_path / "fr.nc"

    def hdf_error(ds, path):  # what netCDF4 makes of HDF5's ENOSPC (datasets.write_netcdf)
        raise OSError("NetCDF: HDF error")

    monkeypatch.setattr(datasets, "write_netcdf", hdf_error)
    monkeypatch.setattr(chunk_store.shutil, "disk_usage",
                        lambda path: type("usage", (), {"free": 0})())
    assert cli.main(["run", str(tmp_path / "fr.toml"), "--output", str(out), "--quiet"]) == 2
    line = _one_line(capsys)
    assert "NetCDF: HDF error" in line and "the disk is full: 0 B free" in line, line
    assert "--resume" in line
    assert len(list((tmp_path / "fr.nc.partial").glob("chunk_*.json"))) == 1


def test_a_full_disk_under_a_branch_names_the_free_space(tmp_path, capsys, monkeypatch):
    def hdf_error(ds, path):
        raise OSError("NetCDF: HDF error")

    monkeypatch.setattr(datasets, "write_netcdf", hdf_error)
    monkeypatch.setattr(chunk_store.shutil, "disk_usage",
                        lambda path: type("usage", (), {"free": 0})())
    with pytest.raises(ParameterError, match="HDF error .*0 B free on the disk"):
        with cli._writing(str(tmp_path / "b.nc")):
            datasets.write_netcdf(None, tmp_path / "b.nc")


def test_a_two_dimensional_array_as_an_axis_is_refused_not_flattened():
    grid = {"frequency": np.array([[200.0, 210.0], [220.0, 230.0]])}
    with pytest.raises(ParameterError, match=r"grid.frequency: an array of shape \(2, 2\)"):
        load_sweep(spec(grid))
    assert load_sweep(spec({"frequency": np.array([200.0, 210.0])})).n_points == 2


@pytest.mark.parametrize("model, name, values", [("tip_mass", "steps_per_period", [512, 1024]),
                                                  ("beam", "contact_step", [1e-6, 2e-6])])
def test_an_axis_that_is_also_an_output_is_refused_before_any_work(model, name, values):
    """Each point's steps_per_period (and the beam's contact_step) is an output, refined
    where its estimate asks: a grid axis of that name was accepted, every point solved, and
    then the dataset could not be made (its variable and its coordinate clash), nor on a
    resume."""
    source = {"model": model, "grid": {name: values, "frequency": [220.0]}}
    with pytest.raises(ParameterError, match=f"grid.{name}: {name} is also an output"):
        load_sweep(source, model=model)


@pytest.mark.parametrize("name", ["x.txt", "x.nc.bak", "x"])
def test_run_sweep_refuses_an_output_that_is_not_nc(name, tmp_path):
    with pytest.raises(ParameterError, match=r"must end in \.nc"):
        run_sweep(SWEEP, tmp_path / name, progress=False)
    assert list(tmp_path.iterdir()) == []


def test_the_system_reason_is_kept_where_it_is_given(tmp_path):
    error = OSError(errno.EACCES, os.strerror(errno.EACCES))
    assert chunk_store.write_failure(tmp_path / "x.nc", error, 10) == os.strerror(errno.EACCES)


def test_a_reason_given_beside_a_full_disk_names_the_free_space(tmp_path, monkeypatch):
    """HDF5 writing to a full tmpfs raised "Permission denied" in a folder it could write."""
    monkeypatch.setattr(chunk_store.shutil, "disk_usage",
                        lambda path: type("usage", (), {"free": 0})())
    error = OSError(errno.EACCES, os.strerror(errno.EACCES))
    assert chunk_store.write_failure(tmp_path / "x.nc", error, 10) == (
        f"{os.strerror(errno.EACCES)} (the disk is full: 0 B free for about 10 B of data)")


# -- 3: 'continue' and 'basins' take the output's lock and check its folder first --------

CONTINUATION = "[continuation]\nstart = 150.0\nstop = 160.0\n"
BASINS = "[parameters]\nsteps_per_period = 256\n[basins]\nsamples = 2\n"


def _not_computed(*args, **kwargs):
    raise AssertionError("the work began")


def _analysis(command, tmp_path, monkeypatch):
    """The spec file of ``command`` and its driver replaced by one that must not run."""
    from harvester_sweep import basins, continuation

    monkeypatch.setattr(continuation, "continue_branch", _not_computed)
    monkeypatch.setattr(basins, "basin_map", _not_computed)
    toml = tmp_path / f"{command}.toml"
    toml.write_text(CONTINUATION if command == "continue" else BASINS)
    return toml


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc")
def test_a_folder_where_no_file_can_be_made_is_not_taken_for_another_run():
    """/proc takes no new file, not even root's: filelock times out there rather than
    raise, which read as another run holding the output's lock."""
    with pytest.raises(chunk_store.StoreError, match="cannot write in the folder /proc"):
        chunk_store.lock_output("/proc/x.nc")


@pytest.mark.parametrize("command", ["continue", "basins"])
def test_a_second_run_on_the_same_output_is_refused_before_the_work(command, tmp_path, capsys,
                                                                     monkeypatch):
    from filelock import FileLock

    toml = _analysis(command, tmp_path, monkeypatch)
    out = tmp_path / "out.nc"
    with FileLock(tmp_path / ".out.nc.lock", timeout=0):  # as 'run' holds it
        assert cli.main([command, str(toml), "--output", str(out)]) == 2
    assert "another run is writing this output" in _one_line(capsys)
    assert not out.exists()


@pytest.mark.parametrize("command", ["continue", "basins"])
def test_a_folder_that_cannot_be_written_is_found_before_the_work(command, tmp_path, capsys,
                                                                   monkeypatch):
    toml = _analysis(command, tmp_path, monkeypatch)
    closed = tmp_path / "closed"
    closed.mkdir()
    _refuse_writes_in(closed, monkeypatch)
    rc = cli.main([command, str(toml), "--output", str(closed / "out.nc")])
    monkeypatch.undo()
    assert rc == 2 and "cannot write in the folder" in _one_line(capsys)
    assert list(closed.iterdir()) == []


def test_a_plot_folder_that_cannot_be_written_is_found_before_the_work(tmp_path, capsys,
                                                                        monkeypatch):
    toml = _analysis("continue", tmp_path, monkeypatch)
    closed = tmp_path / "closed"
    closed.mkdir()
    _refuse_writes_in(closed, monkeypatch)
    rc = cli.main(["continue", str(toml), "--output", str(tmp_path / "b.nc"), "--plot",
                   str(closed / "b.png")])
    monkeypatch.undo()
    assert rc == 2 and "cannot write in the folder" in _one_line(capsys)


def _refuse_writes_in(folder: Path, monkeypatch) -> None:
    """Creating a file in ``folder`` fails as the OS fails it for a user who may not write
    there (root writes through permissions, so they are not used)."""
    def refused(path, *args, _real=os.open, **kwargs):
        if Path(os.fsdecode(path)).parent == folder:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))
        return _real(path, *args, **kwargs)

    monkeypatch.setattr(os, "open", refused)


# -- 6: plot on a netCDF file the tool did not write --------------------------------------

@pytest.mark.parametrize("dims", [("x",), ("x", "y"), ("time",), ("point",), ("attractor",),
                                  ()])
def test_plot_refuses_a_file_another_tool_wrote_in_one_line(dims, tmp_path, capsys):
    path = tmp_path / "foreign.nc"
    xr.Dataset({"a": (dims, np.ones((2,) * len(dims)))}).to_netcdf(path)
    assert cli.main(["plot", str(path), "--output", str(tmp_path / "p.png")]) == 2
    line = _one_line(capsys)
    assert "not a file written by harvester-sweep" in line and "title" in line
    assert not (tmp_path / "p.png").exists()


def test_plot_names_a_variable_removed_from_a_file_of_the_tool(tmp_path, capsys):
    from harvester_sweep import run_scene

    path = tmp_path / "scene.nc"
    run_scene("paper", steps_per_period=256).to_netcdf(path)
    with xr.open_dataset(path) as ds:
        cut = ds.load().drop_vars("displacement")
    cut.to_netcdf(tmp_path / "cut.nc")
    assert cli.main(["plot", str(tmp_path / "cut.nc"), "--output", str(tmp_path / "p.png")]) == 2
    assert "No variable named 'displacement'" in _one_line(capsys)
    assert cli.main(["plot", str(path), "--output", str(tmp_path / "p.png")]) == 0


# -- 8: Ctrl-C outside a sweep ------------------------------------------------------------

def _interrupt(*args, **kwargs):
    raise KeyboardInterrupt


@pytest.mark.parametrize("command", ["scene", "continue", "basins"])
def test_ctrl_c_exits_130_in_one_line(command, tmp_path, capsys, monkeypatch):
    from harvester_sweep import basins, continuation, scene

    for module, name in ((scene, "run_scene"), (continuation, "continue_branch"),
                         (basins, "basin_map")):
        monkeypatch.setattr(module, name, _interrupt)
    argv = [command] if command == "scene" else [
        command, str(_spec_file(command, tmp_path)), "--output", str(tmp_path / "out.nc")]
    try:
        rc = cli.main(argv)
    except KeyboardInterrupt:  # (else pytest itself would stop here)
        pytest.fail("Ctrl-C ended in a KeyboardInterrupt traceback")
    assert rc == 130
    assert _one_line(capsys) == "harvester-sweep: interrupted before any file was written"
    assert not (tmp_path / "out.nc").exists()


def test_ctrl_c_after_the_file_says_it_was_written(tmp_path, capsys, monkeypatch):
    from harvester_sweep import scene

    monkeypatch.setattr(scene.SceneResult, "plot", _interrupt)
    out = tmp_path / "s.nc"
    argv = ["scene", "--set", "steps_per_period=256", "--output", str(out), "--plot",
            str(tmp_path / "s.png")]
    try:
        rc = cli.main(argv)
    except KeyboardInterrupt:
        pytest.fail("Ctrl-C ended in a KeyboardInterrupt traceback")
    assert rc == 130 and out.exists()
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == f"harvester-sweep: interrupted after writing {out}"


def _spec_file(command: str, tmp_path: Path) -> Path:
    toml = tmp_path / f"{command}.toml"
    toml.write_text(CONTINUATION if command == "continue" else BASINS)
    return toml


# -- 4: grids too large to count, counted before any axis is made ------------------------

def test_a_grid_beyond_a_64_bit_count_is_refused_before_any_axis_is_made(monkeypatch):
    from harvester_sweep import sweep_file

    monkeypatch.setattr(sweep_file, "_range", _not_computed)  # (no axis may be made)
    axis = {"start": 1.0, "stop": 2.0, "num": 10**7}
    grid = {"frequency": {**axis, "start": 100.0, "stop": 300.0},
            "gap": {**axis, "start": 1e-6, "stop": 2e-6}, "resistance": axis}
    with pytest.raises(ParameterError, match=r"grid: 10,000,000 x 10,000,000 x 10,000,000 = "
                                             r"1e\+21 points, more than the 1e\+12"):
        load_sweep({"grid": grid})


def test_a_grid_of_a_billion_points_is_refused_without_checking_each_value(monkeypatch):
    from harvester_sweep.parameters import Parameter

    checked = []
    check = Parameter.check
    monkeypatch.setattr(Parameter, "check", lambda self, value: checked.append(value)
                        or check(self, value))
    grid = {"frequency": {"start": 100.0, "stop": 300.0, "num": 10**7},
            "gap": {"start": 1e-6, "stop": 2e-6, "num": 100}}
    with pytest.raises(ParameterError, match="1,000,000,000 points.*yes=True"):
        run_sweep({"grid": grid}, progress=False)
    assert len(checked) < 1000  # (one by one, 10,000,100 values were checked)


def test_a_value_out_of_range_inside_a_range_table_is_still_named():
    grid = {"max_periods": {"start": 100, "stop": 101, "num": 3}}  # 100.5: no integer
    with pytest.raises(ParameterError, match=r"grid.max_periods \[-\] = 100.5"):
        load_sweep({"grid": grid})
    grid = {"frequency": {"start": 300.0, "stop": -100.0, "num": 5}}  # 0 and -100: not > 0
    with pytest.raises(ParameterError, match=r"grid.frequency \[Hz\] = (0.0|-100.0): must be"):
        load_sweep({"grid": grid})
    grid = {"gap": {"start": -1e308, "stop": 1e308, "num": 3}}  # the middle one overflows
    with pytest.raises(ParameterError, match=r"grid.gap \[m\] = (nan|inf)"):
        load_sweep({"grid": grid})


def test_a_long_axis_enters_the_sweep_identity_by_its_checksum():
    values = np.linspace(100.0, 300.0, 5000)
    one = load_sweep(spec({"frequency": values}))
    other = load_sweep(spec({"frequency": np.where(values == 200.0, 200.0 + 1e-9, values)
                             if 200.0 in values else values + np.eye(1, 5000, 2500)[0]}))
    assert one.digest() != other.digest()
    assert one.digest() == load_sweep(spec({"frequency": list(values)})).digest()


# -- 5: a basin map says its size and asks for --yes as a sweep does ---------------------

BIG_MAP = ("[grid]\nfrequency = { start = 200, stop = 260, num = 3000 }\n"
           "gap = { start = 1e-6, stop = 3e-6, num = 3000 }\n[basins]\nsamples = 100\n")


def test_a_basin_map_of_days_asks_for_yes_before_resolving_its_points(tmp_path, capsys,
                                                                       monkeypatch):
    from harvester_sweep import basins

    resolved = []
    resolve = basins.resolve_parameters

    def counted(*args, **kwargs):  # (9e6 points resolved one by one took minutes)
        resolved.append(1)
        if len(resolved) > 10_000:
            raise AssertionError("every point of the grid is being resolved")
        return resolve(*args, **kwargs)

    monkeypatch.setattr(basins, "resolve_parameters", counted)
    monkeypatch.setattr(basins, "solve", _not_computed)
    (tmp_path / "big.toml").write_text(BIG_MAP)
    out = tmp_path / "big.nc"
    assert cli.main(["basins", str(tmp_path / "big.toml"), "--output", str(out)]) == 2
    line = _one_line(capsys)
    assert "9,000,000 points x 100 starts" in line and "--yes" in line, line
    assert len(resolved) < 1000 and not out.exists()


def test_a_basin_map_beyond_an_hour_starts_with_yes_and_says_its_size(tmp_path, capsys,
                                                                      monkeypatch):
    from harvester_sweep import basins

    monkeypatch.setattr(basins, "solve", _interrupt)  # (past the gate: stopped there)
    (tmp_path / "long.toml").write_text(
        "[parameters]\nsteps_per_period = 1048576\n[grid]\nfrequency = [200.0, 230.0, 260.0]\n"
        "[basins]\nsamples = 1000000\n")  # (2.5e14 steps: beyond an hour on 128 threads)
    argv = ["basins", str(tmp_path / "long.toml"), "--output", str(tmp_path / "b.nc")]
    try:
        assert cli.main(argv) == 2
        assert "--yes" in _one_line(capsys)
        assert cli.main(argv + ["--yes"]) == 130
    except KeyboardInterrupt:  # (else pytest itself would stop here)
        pytest.fail("the work began without --yes, and Ctrl-C ended in a traceback")
    err = [line for line in capsys.readouterr().err.splitlines()
           if "compiling the RK4 kernel" not in line]  # (said when the cache is cold)
    assert err[0].startswith("harvester-sweep: 3 points x 1,000,000 starts, about "), err


def test_basin_fractions_python_refuses_a_run_of_hours_without_yes(monkeypatch):
    from harvester_sweep import basin_fractions, basins

    monkeypatch.setattr(basins, "solve", _not_computed)
    with pytest.raises(ParameterError, match="yes=True"):
        basin_fractions(samples=1_000_000, steps_per_period=2**20)


# -- 10: a continuation to an absurd stop --------------------------------------------------

def test_a_branch_stops_where_the_period_map_is_the_identity_and_flags_no_far_grazing():
    from harvester_sweep import continue_branch

    # At 1e18 Hz a forcing period is 1e-18 s: nothing moves within it, the period map is
    # the identity to rounding and any state passes for an orbit.
    ds = continue_branch("paper", "frequency", 150.0, 1e20)
    assert "identity to rounding" in ds.attrs["ends"], ds.attrs["ends"]
    # the paper's fastest time scale is far above a microsecond: 1e12 Hz is beyond it
    assert float(ds["frequency"].max()) < 1e12
    gap = float(ds.attrs["gap"])  # (1e-6 m: the paper's Table 1)
    grazing = list(ds["bifurcation"].attrs["flag_meanings"].split()).index("grazing")
    for i in np.flatnonzero(ds["bifurcation"].values == grazing):
        assert abs(float(ds["x_max"][i]) - gap) < 1e-3 * gap, float(ds["x_max"][i])


# -- an integer option takes what the parameter table takes: 8, 8.0 and numpy's 8 ---------

def test_a_sweep_files_counts_take_whole_floats_as_its_parameters_do():
    def sweep(num, samples, chunk_size):
        return load_sweep({"parameters": {"max_periods": 400.0},  # (a parameter's int)
                           "grid": {"frequency": {"start": 200.0, "stop": 260.0, "num": num}},
                           "sweep": {"outputs": ["power", "strobe"], "samples": samples,
                                     "chunk_size": chunk_size}})

    as_int, as_float = sweep(3, 8, 2), sweep(3.0, 8.0, np.float32(2.0))
    assert (as_float.samples, as_float.chunk_size) == (as_int.samples, as_int.chunk_size) == (8, 2)
    assert type(as_float.samples) is int and type(as_float.chunk_size) is int
    np.testing.assert_array_equal(as_float.grid["frequency"], [200.0, 230.0, 260.0])
    for bad in (dict(num=2.5), dict(samples=8.5), dict(chunk_size=True)):
        with pytest.raises(ParameterError, match=r"(num|samples|chunk_size) \[-\] = .*must be "
                                                 r"an integer"):
            sweep(**{"num": 3, "samples": 8, "chunk_size": 2, **bad})


def test_the_beam_commands_take_numpy_counts(monkeypatch):
    from harvester_sweep import beam_basins
    from harvester_sweep.beam_continuation import check_branch

    taken = check_branch("frequency", 100.0, 120.0, np.float32(0.05), np.int64(40))
    assert taken == 40 and type(taken) is int
    assert check_branch("frequency", 100.0, 120.0, 0.05, 40.0) == 40
    with pytest.raises(ParameterError, match=r"max_points \[-\] = 40.5: must be an integer"):
        check_branch("frequency", 100.0, 120.0, 0.05, 40.5)
    monkeypatch.setattr(beam_basins, "resolve_beam_parameters",
                        lambda *a, **k: (_ for _ in ()).throw(_Taken))
    with pytest.raises(_Taken):  # (the draws' options were accepted)
        beam_basins.beam_basins(samples=np.int64(4), seed=np.uint16(3), box=np.float32(1.5))
    with pytest.raises(ParameterError, match=r"box \[-\] = True: must be a finite number"):
        beam_basins.beam_basins(samples=4, box=True)
