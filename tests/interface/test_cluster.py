"""Sweeps on dask.distributed: a running scheduler and a LocalCluster give the local result."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
from pathlib import Path

import pytest

from harvester_sweep import cli
from harvester_sweep.sweep import run_sweep
from tests.helpers import assert_same_bits, spec

SWEEP = spec({"frequency": [200.0, 230.0, 260.0], "gap": [1e-6, 2e-6]},
             directions=["up", "down"], outputs=["power", "x_max", "strobe"], samples=3,
             chunk_size=3)  # 4 chunks of one frequency line


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _wait_for_worker(address: str, timeout: float = 60.0) -> None:
    from dask.distributed import Client

    with Client(address, timeout=timeout) as client:
        client.wait_for_workers(1, timeout=timeout)


@pytest.fixture(scope="module")
def scheduler(tmp_path_factory):
    """A ``dask scheduler`` and one single-threaded ``dask worker``, as separate processes."""
    pytest.importorskip("dask.distributed")
    dask = shutil.which("dask")
    if dask is None:
        pytest.skip("the dask command is not installed")
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    # The worker must import harvester_sweep even when it is not installed.
    root = str(Path(__file__).parents[2])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (root, os.environ.get("PYTHONPATH")) if p))
    tmp_path = tmp_path_factory.mktemp("dask")
    log = (tmp_path / "dask.log").open("w")
    processes = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port",
                                   str(port), "--no-dashboard"], stdout=log, stderr=log,
                                  env=env)]
    try:
        processes.append(subprocess.Popen(
            [dask, "worker", address, "--nworkers", "1", "--nthreads", "1", "--no-nanny",
             "--no-dashboard", "--local-directory", str(tmp_path / "worker")],
            stdout=log, stderr=log, env=env))
        _wait_for_worker(address)
        yield address
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in reversed(processes):
            try:
                process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        log.close()


def test_a_running_scheduler_gives_the_local_result(scheduler, tmp_path):
    local = run_sweep(SWEEP, progress=False)
    remote = run_sweep(SWEEP, tmp_path / "remote.nc", scheduler=scheduler, progress=False)
    assert_same_bits(local, remote)
    assert not (tmp_path / "remote.nc.partial").exists()


def test_the_cli_runs_on_a_scheduler_and_on_local_workers(scheduler, tmp_path, capsys):
    import xarray as xr

    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text(
        '[parameters]\nsteps_per_period = 256\nmax_periods = 2000\n'
        '[grid]\nfrequency = [200.0, 230.0, 260.0]\ngap = [1e-6, 2e-6]\n'
        '[sweep]\ndirections = ["up", "down"]\noutputs = ["power", "x_max"]\nchunk_size = 3\n')
    outs = {}
    for name, where in (("local", []), ("scheduler", ["--scheduler", scheduler]),
                        ("workers", ["--workers", "2"])):
        outs[name] = tmp_path / f"{name}.nc"
        argv = ["run", str(sweep_file), "--output", str(outs[name]), "--quiet", *where]
        assert cli.main(argv) == 0, capsys.readouterr().err
    with xr.open_dataset(outs["local"]) as local:
        for name in ("scheduler", "workers"):
            with xr.open_dataset(outs[name]) as other:
                assert_same_bits(local, other)


def test_an_unreachable_scheduler_is_a_clear_error(tmp_path, capsys):
    dask = pytest.importorskip("dask")
    pytest.importorskip("dask.distributed")

    address = f"tcp://127.0.0.1:{_free_port()}"
    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text('[grid]\nfrequency = [140.0]\n')
    argv = ["run", str(sweep_file), "--output", str(tmp_path / "x.nc"), "--quiet",
            "--scheduler", address]
    with dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
        assert cli.main(argv) == 2
    assert "cannot connect" in capsys.readouterr().err
    assert not (tmp_path / "x.nc.partial").exists()  # nothing to --resume
