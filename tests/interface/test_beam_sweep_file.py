"""Beam sweeps from sweep files (model = "beam"), in chunks kept as they finish: a run
stopped after some chunks and resumed, here or on Dask, writes the uninterrupted run's
file bit for bit, which is also the in-memory beam_sweep's of the same grid; a Dask run
that loses a chunk keeps the others; a bad beam sweep file is one line, exit 2. One-mode
and two-mode points on small grids."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from harvester_sweep import beam_cluster, chunk_store, cli
from harvester_sweep.beam_cluster import run_beam_file
from harvester_sweep.beam_runs import beam_sweep
from harvester_sweep.cluster import ClusterError
from harvester_sweep.parameters import ParameterError
from harvester_sweep.sweep import run_sweep
from harvester_sweep.sweep_file import load_sweep
from tests.helpers import assert_same_bits

FREQUENCIES = [230.0, 240.0, 250.0, 260.0]
GAPS = [1e-6, 2e-6, 3e-6]
#: Three lines along frequency each way, two lines a chunk: chunks [up 0-1], [up 2],
#: [down 0-1], [down 2] (a chunk never holds lines of two directions).
SWEPT = {"model": "beam", "preset": "bimorph_tip", "parameters": {"n_modes": 1},
         "grid": {"gap": GAPS, "frequency": FREQUENCIES},
         "sweep": {"directions": ["up", "down"], "chunk_size": 8}}
TOML = """model = "beam"
preset = "bimorph_tip"
[parameters]
n_modes = 1
[grid]
gap = [1e-6, 2e-6, 3e-6]
frequency = { start = 230, stop = 260, num = 4 }
[sweep]
directions = ["up", "down"]
chunk_size = 8
"""


class Interrupted(Exception):
    pass


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """SWEPT run without a fault, as written to its file."""
    path = tmp_path_factory.mktemp("whole") / "whole.nc"
    run_beam_file(SWEPT, path)
    with xr.open_dataset(path) as ds:
        return ds.load()


def _stopped_after(chunks: int, out, monkeypatch) -> None:
    """Run SWEPT into ``out`` and stop it, as if killed, once ``chunks`` chunks are on
    disk."""
    save = chunk_store.ChunkStore.save
    saved = []

    def save_then_stop(self, chunk, result):
        save(self, chunk, result)
        saved.append(chunk)
        if len(saved) == chunks:
            raise Interrupted

    monkeypatch.setattr(chunk_store.ChunkStore, "save", save_then_stop)
    with pytest.raises(Interrupted):
        run_beam_file(SWEPT, out)
    monkeypatch.undo()


def test_the_chunks_cover_the_grid_once_each_within_one_direction():
    spec = load_sweep(SWEPT, model="beam")
    lines = [list(spec.chunk_lines(c)) for c in range(spec.n_chunks)]
    assert lines == [[0, 1], [2], [3, 4], [5]]  # lines 0-2 up, 3-5 down
    points = load_sweep({**SWEPT, "sweep": {"chunk_size": 4}}, model="beam")
    assert [len(points.chunk_lines(c)) for c in range(points.n_chunks)] == [4, 4, 4]


def test_the_file_is_the_in_memory_sweep_bit_for_bit(whole):
    # beam_sweep solves the whole grid at once, each line's steps together: another
    # path through the same solver
    memory = beam_sweep({"gap": GAPS, "frequency": FREQUENCIES}, "bimorph_tip",
                        directions=("up", "down"), n_modes=1)
    assert_same_bits(whole, memory)
    assert whole.attrs["model"] == "beam" and "stop_face_max" not in whole
    # the lines were continued: the hysteresis band shows
    assert not np.array_equal(whole["power"].sel(direction="up"),
                              whole["power"].sel(direction="down"))


def test_resume_after_an_interruption_gives_the_uninterrupted_file(whole, tmp_path,
                                                                   monkeypatch):
    out = tmp_path / "part.nc"
    _stopped_after(1, out, monkeypatch)
    assert not out.exists()
    assert len(list((tmp_path / "part.nc.partial").glob("chunk_*.npz"))) == 1
    with pytest.raises(ParameterError, match="--resume"):
        run_beam_file(SWEPT, out)  # never overwritten silently

    computed = []
    solve = beam_cluster.beam_chunk
    monkeypatch.setattr(beam_cluster, "beam_chunk",
                        lambda spec, chunk, *a: computed.append(chunk) or solve(spec, chunk, *a))
    resumed = run_beam_file(SWEPT, out, resume=True)
    assert computed == [1, 2, 3]
    assert not (tmp_path / "part.nc.partial").exists()
    assert_same_bits(resumed, whole)
    with xr.open_dataset(out) as written:
        assert_same_bits(written, whole)


def test_a_full_disk_while_writing_the_file_keeps_the_chunks(whole, tmp_path, monkeypatch):
    import errno

    from harvester_sweep import datasets

    def full(ds, path):
        raise OSError(errno.ENOSPC, "No space left on device")

    out = tmp_path / "full.nc"
    monkeypatch.setattr(datasets, "write_netcdf", full)
    with pytest.raises(chunk_store.StoreError, match="the 4 finished chunks are kept"):
        run_beam_file(SWEPT, out)
    monkeypatch.undo()
    computed = []
    solve = beam_cluster.beam_chunk
    monkeypatch.setattr(beam_cluster, "beam_chunk",
                        lambda spec, chunk, *a: computed.append(chunk) or solve(spec, chunk, *a))
    assert_same_bits(run_beam_file(SWEPT, out, resume=True), whole)
    assert computed == []  # nothing solved again


def test_a_partial_result_is_resumed_by_the_same_sweep_only(tmp_path, monkeypatch):
    out = tmp_path / "part.nc"
    _stopped_after(1, out, monkeypatch)
    other = {**SWEPT, "parameters": {"n_modes": 2}}
    with pytest.raises(ParameterError, match="another sweep"):
        run_beam_file(other, out, resume=True)
    assert (tmp_path / "part.nc.partial").exists()


def test_a_resume_of_a_finished_beam_file_runs_nothing(whole, tmp_path, monkeypatch):
    """As the tip-mass sweep's (test_sweep): the finished file is this sweep's result, known
    by the sweep's digest it now holds; another sweep's resume is refused."""
    out = tmp_path / "done.nc"
    run_beam_file(SWEPT, out)
    monkeypatch.setattr(beam_cluster, "beam_chunk", lambda *a, **k: pytest.fail("computed"))
    assert_same_bits(run_beam_file(SWEPT, out, resume=True), whole)
    with pytest.raises(ParameterError, match="another sweep's finished result"):
        run_beam_file({**SWEPT, "parameters": {"n_modes": 2}}, out, resume=True)


@pytest.fixture(scope="module")
def scheduler():
    """An in-process cluster of one single-threaded worker: its address."""
    pytest.importorskip("dask.distributed")
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as cluster:
        yield cluster.scheduler_address


def test_a_run_stopped_here_is_finished_on_dask_bit_for_bit(whole, tmp_path, monkeypatch,
                                                            scheduler):
    out = tmp_path / "part.nc"
    _stopped_after(2, out, monkeypatch)
    calls = []
    resumed = run_beam_file(SWEPT, out, resume=True, scheduler=scheduler,
                            progress=lambda *a: calls.append(a))
    assert sorted(c[:2] for c in calls) == [(1, 2), (2, 2)]  # the two chunks left
    assert_same_bits(resumed, whole)


def test_a_dask_run_that_loses_a_chunk_keeps_the_others_for_resume(whole, tmp_path,
                                                                   monkeypatch, scheduler):
    from types import SimpleNamespace

    from distributed import Future, KilledWorker

    result = Future.result
    answered = []

    def third_dies(self, *args, **kwargs):
        answered.append(self)
        if len(answered) == 3:
            raise KilledWorker("the task", SimpleNamespace(address="tcp://10.0.0.1:1"), 3)
        return result(self, *args, **kwargs)

    out = tmp_path / "lost.nc"
    monkeypatch.setattr(Future, "result", third_dies)
    with pytest.raises(ClusterError) as caught:
        run_beam_file(SWEPT, out, scheduler=scheduler)
    monkeypatch.undo()
    text = str(caught.value)
    assert "\n" not in text and "KilledWorker" in text and "--resume" in text, text
    assert "the 3 finished chunks are kept" in text, text
    assert len(list((tmp_path / "lost.nc.partial").glob("chunk_*.json"))) == 3
    assert_same_bits(run_beam_file(SWEPT, out, resume=True), whole)


def test_lines_along_a_first_axis_are_put_back_in_the_files_order():
    # frequency before gap: each chunk's lines (along frequency) go back across the grid
    grid = {"frequency": FREQUENCIES, "gap": GAPS}
    ds = run_beam_file({"model": "beam", "parameters": {"n_modes": 1}, "grid": grid,
                        "sweep": {"directions": ["down"], "chunk_size": 4}})
    assert ds["power"].dims == ("direction", "frequency", "gap")
    xr.testing.assert_identical(ds, beam_sweep(grid, "bimorph_tip", "down", n_modes=1))


def test_an_unswept_grid_in_chunks_of_points_from_a_file_is_beam_sweeps(tmp_path):
    # n_modes on an axis: a chunk of one mode, one of two, their outputs over the modes
    # and the multipliers padded alike when the chunks are put together
    grid = {"n_modes": [1, 2], "frequency": [230.0, 250.0, 270.0]}
    ds = run_beam_file({"model": "beam", "grid": grid, "sweep": {"chunk_size": 3}})
    xr.testing.assert_identical(ds, beam_sweep(grid, "bimorph_tip"))
    assert ds.sizes["mode"] == 2 and np.isnan(ds["modal_amplitude"].sel(n_modes=1,
                                                                        mode=2)).all()
    one_mode = ds.sel(n_modes=1).isel(multiplier=slice(3, None))  # (a state of 3)
    assert np.isnan(one_mode["floquet_multipliers_imag"]).all()


def test_the_cli_runs_a_file_stopped_by_ctrl_c_and_resumed(whole, tmp_path, capsys,
                                                          monkeypatch):
    path = tmp_path / "fr.toml"
    path.write_text(TOML)
    out = tmp_path / "fr.nc"
    save = chunk_store.ChunkStore.save

    def save_then_ctrl_c(self, chunk, result):
        save(self, chunk, result)
        raise KeyboardInterrupt

    monkeypatch.setattr(chunk_store.ChunkStore, "save", save_then_ctrl_c)
    assert cli.main(["beam-sweep", str(path), "--output", str(out)]) == 130
    monkeypatch.undo()
    err = capsys.readouterr().err
    assert "--resume" in err and "Traceback" not in err
    assert "harvester-sweep: 24 points\n" in err  # said before the work
    assert cli.main(["beam-sweep", str(path), "--output", str(out), "--resume"]) == 0
    err = capsys.readouterr().err
    assert "harvester-sweep: 24 points (16 still to run)\n" in err
    assert err.count("up ") == 4 and err.count("down ") == 8  # a line per step of each line
    with xr.open_dataset(out) as written:
        assert_same_bits(written, whole)


def test_the_example_file_is_a_valid_beam_sweep():
    from pathlib import Path

    spec = load_sweep(Path(__file__).parents[2] / "examples" / "beam_frequency_response.toml",
                      model="beam")
    assert spec.model == "beam" and spec.continuation


#: Bad beam sweep files: (the TOML after `model = "beam"`, or a whole file; the words of
#: the one line).
BAD = [
    ('[parameters]\nn_modes = 9\n[grid]\nfrequency = [230.0]\n', ["n_modes [-]", "[1, 8]"]),
    ('[parameters]\ncolour = 1\n[grid]\nfrequency = [230.0]\n',
     ["unknown beam parameter 'colour'"]),
    ('[grid]\nn_modes = [1, 9]\n', ["grid.n_modes [-] = 9", "[1, 8]"]),
    ('[grid]\nfrequency = { start = -1, stop = 300, num = 3 }\n',
     ["grid.frequency [Hz]", "(0, inf)"]),
    ('[grid]\nconnection = ["series"]\n', ["grid.connection", "set it in [parameters]"]),
    ('[grid]\ncontact_position = [0.01, 0.05]\n',
     ["at the grid point", "contact_position [m] = 0.05"]),
    ('[grid]\nfrequency = [230.0]\n[sweep]\noutputs = ["power"]\n',
     ["sweep.outputs", "not for the beam model"]),
    ('[grid]\ngap = [1e-6]\n[sweep]\ndirections = ["up"]\n',
     ["sweep.directions", "frequency"]),
    ('preset = "paper"\n[grid]\nfrequency = [230.0]\n', ["preset 'paper'", "bimorph_tip"]),
    ('[grid]\nfrequency = [230.0]\n[sweep]\nchunk_size = 0\n', ["sweep.chunk_size [-] = 0"]),
]
IDS = ["n_modes_9", "unknown_name", "axis_value", "range_below", "choice_axis",
       "contact_beyond_length", "tip_mass_option", "direction_without_frequency",
       "tip_mass_preset", "chunk_size"]


@pytest.mark.parametrize("text, words", BAD, ids=IDS)
def test_a_bad_beam_sweep_file_exits_2_in_one_line(text, words, tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text('model = "beam"\n' + text)
    out = tmp_path / "bad.nc"
    assert cli.main(["beam-sweep", str(path), "--output", str(out)]) == 2
    err = capsys.readouterr().err
    # (one line, and before the note of a first compilation: nothing else is printed)
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, (word, err)
    assert not out.exists() and not (tmp_path / "bad.nc.partial").exists()


@pytest.mark.parametrize("argv, words", [
    (["beam-sweep", "{beam}", "--axis", "gap=1e-6"], ["--axis", "not both"]),
    (["beam-sweep", "{beam}", "--set", "n_modes=2"], ["--set", "not both"]),
    (["beam-sweep"], ["give a sweep file", "--axis"]),
    (["beam-sweep", "{tip}"], ['model = "tip_mass"', "harvester-sweep run"]),
    (["beam-sweep", "{odd}"], ["model = 'beem'", '"tip_mass", "beam"']),
    (["run", "{odd}"], ["model = 'beem'", '"tip_mass", "beam"']),
], ids=["file_and_axis", "file_and_set", "nothing", "tip_mass_file", "unknown_model",
        "unknown_model_to_run"])
def test_a_sweep_file_given_to_the_wrong_command_exits_2_in_one_line(argv, words, tmp_path,
                                                                     capsys):
    files = {"beam": 'model = "beam"\n[grid]\nfrequency = [230.0]\n',
             "tip": '[grid]\nfrequency = [230.0]\n',
             "odd": 'model = "beem"\n[grid]\nfrequency = [230.0]\n'}
    for name, text in files.items():
        (tmp_path / f"{name}.toml").write_text(text)
    argv = [a.format(**{n: str(tmp_path / f"{n}.toml") for n in files}) for a in argv]
    assert cli.main(argv + ["--output", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, (word, err)


def test_run_runs_a_beam_file_as_beam_sweep_does(tmp_path):
    """`harvester-sweep run` takes a sweep file of either model: a beam file's dataset is
    beam-sweep's, bit for bit, and run_sweep's in Python too."""
    path = tmp_path / "s.toml"
    path.write_text('model = "beam"\n[parameters]\nn_modes = 1\n[grid]\n'
                    'frequency = [230.0, 240.0]\n')
    by_run, by_beam = tmp_path / "run.nc", tmp_path / "beam.nc"
    assert cli.main(["run", str(path), "--output", str(by_run), "--quiet"]) == 0
    assert cli.main(["beam-sweep", str(path), "--output", str(by_beam), "--quiet"]) == 0
    with xr.open_dataset(by_run) as a, xr.open_dataset(by_beam) as b:
        assert a.attrs["model"] == "beam"
        xr.testing.assert_identical(a, b)
        assert b.attrs.pop("sweep_sha256")  # (a file's sweep, by which a resume knows it)
        xr.testing.assert_identical(run_sweep(str(path), progress=False), b.load())


def test_beam_sweep_reads_and_checks_its_file_once(tmp_path, monkeypatch):
    from harvester_sweep import sweep_file

    path = tmp_path / "s.toml"
    path.write_text('model = "beam"\n[parameters]\nn_modes = 1\n[grid]\n'
                    'frequency = [230.0, 240.0]\n')
    reads, read = [], sweep_file.read_toml
    monkeypatch.setattr(sweep_file, "read_toml",
                        lambda *a, **k: reads.append(a) or read(*a, **k))
    assert cli.main(["beam-sweep", str(path), "--output", str(tmp_path / "s.nc"),
                     "--quiet"]) == 0
    assert len(reads) == 1, reads


def test_an_axis_sweep_on_the_command_line_is_kept_for_resume_too(whole, tmp_path, capsys,
                                                                  monkeypatch):
    out = tmp_path / "axes.nc"
    argv = ["beam-sweep", "--axis", "gap=1e-6,2e-6,3e-6", "--axis", "frequency=230:260:4",
            "--direction", "both", "--set", "n_modes=1", "--quiet", "--output", str(out)]
    save = chunk_store.ChunkStore.save

    def save_then_ctrl_c(self, chunk, result):
        save(self, chunk, result)
        raise KeyboardInterrupt

    monkeypatch.setattr(chunk_store.ChunkStore, "save", save_then_ctrl_c)
    assert cli.main(argv) == 130
    monkeypatch.undo()
    assert "--resume" in capsys.readouterr().err
    assert cli.main(argv + ["--resume"]) == 0
    with xr.open_dataset(out) as written:  # (the default chunks: one a direction)
        assert_same_bits(written, whole)


def test_a_grid_corner_whose_modes_ask_too_many_steps_is_refused_before_any_work():
    # A micrometre beam at one end of a length axis: its first mode asks 3e7 grid steps a
    # period, beyond steps_per_period's range; found at the grid's corners, one line.
    sweep = {"model": "beam", "preset": "bimorph_tip", "parameters": {"n_modes": 1},
             "grid": {"length": [1e-6, 28.81e-3], "frequency": [130.0, 150.0]}}
    with pytest.raises(ParameterError) as info:
        load_sweep(sweep, model="beam")
    message = str(info.value)
    assert message.startswith("grid: at the grid point length = 1e-06, frequency = 130: too "
                              "stiff: the beam's mode 1") and "\n" not in message
