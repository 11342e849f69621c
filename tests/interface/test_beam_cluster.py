"""The beam's sweeps on Dask (harvester_sweep.beam_cluster): the same bits as the local run
for an unswept grid (chunks of points, their mode counts differing) and a swept one (chunks
of whole lines, up and down), progress per chunk, the command line's --workers and
--scheduler, and failures in one line. One- and two-mode points on small grids."""

from __future__ import annotations

import socket

import numpy as np
import pytest
import xarray as xr

from harvester_sweep.beam_cluster import run_beam_sweep
from harvester_sweep.beam_runs import beam_sweep
from harvester_sweep.cli import main
from harvester_sweep.cluster import ClusterError
from harvester_sweep.parameters import ParameterError

pytest.importorskip("dask.distributed")

FREQUENCIES = [230.0, 240.0, 250.0, 260.0]
#: Three lines along frequency: with two lines a chunk, each direction is two chunks.
SWEPT = {"gap": [1e-6, 2e-6, 3e-6], "frequency": FREQUENCIES}


@pytest.fixture(scope="module")
def scheduler():
    """An in-process cluster of one single-threaded worker: its address."""
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as cluster:
        yield cluster.scheduler_address


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_an_unswept_grid_in_chunks_of_points_is_the_local_run_bit_for_bit(scheduler):
    # n_modes on an axis: chunks of one and of two modes, modal_amplitude padded alike
    axes = {"n_modes": [1, 2], "frequency": [230.0, 250.0, 270.0]}
    local = beam_sweep(axes, "bimorph_tip")
    calls = []
    dask = run_beam_sweep(axes, "bimorph_tip", scheduler=scheduler, chunk_size=2,
                          progress=lambda *a: calls.append(a))
    xr.testing.assert_identical(local, dask)
    assert [c[:2] for c in calls] == [(1, 3), (2, 3), (3, 3)]


def test_a_swept_grid_in_chunks_of_lines_is_the_local_run_bit_for_bit(scheduler):
    local = beam_sweep(SWEPT, "bimorph_tip", directions=("up", "down"), n_modes=1)
    calls = []
    dask = run_beam_sweep(SWEPT, "bimorph_tip", ("up", "down"), scheduler=scheduler,
                          chunk_size=2, progress=lambda *a: calls.append(a), n_modes=1)
    xr.testing.assert_identical(local, dask)
    # hysteresis kept: the lines were continued, not solved from rest point by point
    assert not local["power"].sel(direction="up").identical(
        local["power"].sel(direction="down"))
    assert [c[:2] for c in calls] == [(k, 4) for k in range(1, 5)]  # one per chunk
    assert sorted(c[2].split(":")[1].split(" sweep")[0].strip() for c in calls) == [
        "down", "down", "up", "up"]


def test_the_cli_on_local_workers_writes_the_local_dataset(tmp_path, capsys):
    out = tmp_path / "w.nc"
    argv = ["beam-sweep", "--axis", "gap=1e-6,2e-6", "--axis", "frequency=230:260:4",
            "--direction", "up", "--set", "n_modes=1", "--workers", "2", "--out", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    assert "1/" in err and "chunk" in err  # progress lines per chunk
    local = beam_sweep({"gap": [1e-6, 2e-6], "frequency": np.linspace(230, 260, 4)},
                       "bimorph_tip", directions=("up",), n_modes=1)
    with xr.open_dataset(out) as written:
        for name in local.data_vars:
            assert written[name].values.tobytes() == local[name].values.tobytes(), name


@pytest.mark.parametrize("where, words", [
    (["--scheduler", "tcp://127.0.0.1:notaport"], ["not the address of a dask scheduler"]),
    (["--scheduler", "unreachable"], ["cannot connect"]),
    (["--workers", "0"], ["workers [-] = 0", "integer >= 1"]),
], ids=["malformed_address", "unreachable_address", "no_workers"])
def test_a_bad_scheduler_or_worker_count_exits_2_in_one_line(where, words, tmp_path, capsys):
    import dask

    if where[1] == "unreachable":
        where = ["--scheduler", f"tcp://127.0.0.1:{_free_port()}"]
    out = tmp_path / "s.nc"
    argv = ["beam-sweep", "--axis", "frequency=230,240", "--set", "n_modes=1", "--quiet",
            *where, "--out", str(out)]
    with dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
        assert main(argv) == 2
    # (past the note of a first compilation: an unreachable scheduler is found only when
    # the run connects, after the engine is ready)
    err = "".join(line + "\n" for line in capsys.readouterr().err.splitlines()
                  if not line.startswith("harvester-sweep: compiling"))
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, (word, err)
    assert not out.exists()


def test_bad_input_is_refused_before_any_cluster_is_reached():
    with pytest.raises(ParameterError, match=r"n_modes \[-\]"):
        run_beam_sweep({"frequency": [230.0]}, "bimorph_tip", n_modes=9,
                       scheduler=f"tcp://127.0.0.1:{_free_port()}")
    with pytest.raises(ParameterError, match="not both"):
        run_beam_sweep({"frequency": [230.0]}, workers=1, scheduler="tcp://127.0.0.1:1")


def test_a_chunk_whose_workers_keep_dying_is_a_cluster_error_in_one_line(scheduler,
                                                                         monkeypatch):
    from types import SimpleNamespace

    from distributed import Future, KilledWorker

    def dying(self, *args, **kwargs):
        # what the client raises once a task's workers died allowed_failures times (made
        # here: raised inside a task, dask's serialization of the exception drops its
        # last worker, and its message then fails to format)
        raise KilledWorker("the task", SimpleNamespace(address="tcp://10.0.0.1:1"), 3)

    monkeypatch.setattr(Future, "result", dying)
    with pytest.raises(ClusterError) as caught:
        run_beam_sweep({"frequency": FREQUENCIES}, scheduler=scheduler, chunk_size=2,
                       n_modes=1)
    text = str(caught.value)
    assert "\n" not in text and "KilledWorker" in text and "of 2" in text, text
