"""Faults around a sweep's files (a damaged partial result, two runs on one output, a full
disk, a folder that cannot be written) and a sweep too long to start unasked. Each ends in
one line and keeps finished work."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import xarray as xr

from harvester_sweep import chunk_store, cli, datasets, sweep
from harvester_sweep.chunk_store import DamagedChunkWarning
from harvester_sweep.parameters import ParameterError
from harvester_sweep.run_estimate import estimate
from harvester_sweep.sweep import run_sweep
from harvester_sweep.sweep_file import load_sweep
from tests.helpers import assert_same_bits, spec

ROOT = Path(__file__).parents[2]  # subprocesses import this checkout, and share its cache
SWEEP = spec({"frequency": [200.0, 230.0, 260.0], "gap": [1e-6, 2e-6]},
             directions=["up", "down"], chunk_size=3)  # 4 chunks of one line
TOML = """[parameters]
steps_per_period = 256
max_periods = 2000
[grid]
frequency = [200.0, 230.0, 260.0]
gap = [1e-6, 2e-6]
[sweep]
directions = ["up", "down"]
chunk_size = 3
"""


class Interrupted(Exception):
    pass


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """The sweep run without a fault, as written to its file."""
    path = tmp_path_factory.mktemp("whole") / "whole.nc"
    run_sweep(SWEEP, path, progress=False)
    with xr.open_dataset(path) as ds:
        return ds.load()


def _interrupted_before_the_file(out: Path, monkeypatch) -> None:
    """Run SWEEP into ``out`` and stop it after every chunk is saved, before the file."""
    def killed_while_writing(ds, path):
        raise Interrupted

    monkeypatch.setattr(datasets, "write_netcdf", killed_while_writing)
    with pytest.raises(Interrupted):
        run_sweep(SWEEP, out, progress=False)
    monkeypatch.undo()


def _counting(monkeypatch) -> list:
    """The chunks computed from now on, in order."""
    computed = []
    compute = sweep.compute_chunk
    monkeypatch.setattr(sweep, "compute_chunk", lambda s, chunk, *a, **k: computed.append(chunk)
                        or compute(s, chunk, *a, **k))
    return computed


def _cut_short(path: Path) -> None:
    path.write_bytes(path.read_bytes()[:300])  # as a full disk leaves it


def _one_byte_changed(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x01
    path.write_bytes(bytes(data))


def _unsealed(path: Path) -> None:  # killed between the chunk and its seal
    path.with_suffix(".json").unlink()


def _sealed_for_another_sweep(path: Path) -> None:
    seal = path.with_suffix(".json")
    seal.write_text(json.dumps(dict(json.loads(seal.read_text()), sweep_sha256="0" * 64)))


def _copied_from_chunk_0(path: Path) -> None:
    """Chunk 0 and its seal copied over this chunk: both check out by their checksum."""
    for suffix in (".npz", ".json"):
        path.with_suffix(suffix).write_bytes(
            path.with_name(f"chunk_000000{suffix}").read_bytes())


@pytest.mark.parametrize("damage", [_cut_short, _one_byte_changed, _unsealed,
                                    _sealed_for_another_sweep, _copied_from_chunk_0])
def test_resume_computes_a_damaged_chunk_again_and_says_so(damage, whole, tmp_path,
                                                           monkeypatch):
    out = tmp_path / "fr.nc"
    _interrupted_before_the_file(out, monkeypatch)
    damage(tmp_path / "fr.nc.partial" / "chunk_000001.npz")
    computed = _counting(monkeypatch)
    with pytest.warns(DamagedChunkWarning, match="chunk_000001.npz is damaged"):
        resumed = run_sweep(SWEEP, out, resume=True, progress=False)
    assert computed == [1]
    assert_same_bits(resumed, whole)


def test_the_cli_reports_a_damaged_chunk_in_one_line(tmp_path, capsys, monkeypatch):
    (tmp_path / "fr.toml").write_text(TOML)
    out = tmp_path / "fr.nc"
    _interrupted_before_the_file(out, monkeypatch)
    _cut_short(tmp_path / "fr.nc.partial" / "chunk_000002.npz")
    capsys.readouterr()
    argv = ["run", str(tmp_path / "fr.toml"), "--output", str(out), "--resume", "--quiet"]
    assert cli.main(argv) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "chunk_000002.npz is damaged" in err[0] and "again" in err[0]
    assert out.exists() and not (tmp_path / "fr.nc.partial").exists()


def _cli(*args, **kwargs) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "harvester_sweep.cli", *map(str, args)],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            **kwargs)


def test_a_second_run_on_the_same_output_is_refused_and_a_killed_run_frees_it(tmp_path):
    run_sweep(SWEEP, progress=False)  # (the engine compiled, so the first run starts at once)
    # A point with no damping and no stop never settles: it runs out its budget of periods.
    # The second point's 3e7 periods (~1e9 steps) keep the first run on the output while
    # the second run starts.
    (tmp_path / "slow.toml").write_text(
        "[parameters]\nsteps_per_period = 32\ndamping_ratio = 0\ncoupling = 0\n"
        "hertz_stiffness = 0\n[grid]\nmax_periods = [1000, 30000000]\n"
        "[sweep]\nchunk_size = 1\n")
    (tmp_path / "other.toml").write_text(TOML)
    out = tmp_path / "fr.nc"
    first = _cli("run", tmp_path / "slow.toml", "--output", out, "--quiet")
    try:
        deadline = time.monotonic() + 600
        while not (tmp_path / "fr.nc.partial" / "chunk_000000.json").exists():
            assert first.poll() is None, first.communicate()
            assert time.monotonic() < deadline
            time.sleep(0.05)
        second = _cli("run", tmp_path / "slow.toml", "--output", out, "--resume", "--quiet")
        _, err = second.communicate(timeout=120)
        assert first.poll() is None  # (else the test proves nothing)
        assert second.returncode == 2 and len(err.splitlines()) == 1
        assert "another run is writing" in err
    finally:
        first.send_signal(signal.SIGKILL)
        first.communicate()
    # Killed, the first run holds nothing: the next run gets past the lock to the partial
    # result it left, which belongs to another sweep.
    third = _cli("run", tmp_path / "other.toml", "--output", out, "--resume", "--quiet")
    _, err = third.communicate(timeout=120)
    assert third.returncode == 2 and "another sweep" in err
    assert len(list((tmp_path / "fr.nc.partial").glob("chunk_*.json"))) == 1  # kept


def _file_size_limit(limit: int):
    """A child process whose files cannot grow beyond ``limit`` bytes: writes fail as on a
    full disk (EFBIG instead of ENOSPC)."""
    import resource

    def child():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # (an error, not a signal that kills)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return child


@pytest.mark.skipif(sys.platform == "win32", reason="RLIMIT_FSIZE is POSIX")
def test_a_full_disk_while_writing_the_file_keeps_the_chunks(tmp_path, whole):
    toml, out = tmp_path / "fr.toml", tmp_path / "fr.nc"
    toml.write_text(TOML)
    # Chunks of ~1.4 kB fit, the netCDF file of ~30 kB does not.
    full = _cli("run", toml, "--output", out, "--quiet", preexec_fn=_file_size_limit(8000))
    _, err = full.communicate(timeout=600)
    assert full.returncode == 2 and len(err.splitlines()) == 1, err
    assert f"cannot write {out}" in err and "--resume" in err
    assert not out.exists() and not list(tmp_path.glob(".fr.nc.part*"))
    assert len(list((tmp_path / "fr.nc.partial").glob("chunk_*.json"))) == 4
    assert cli.main(["run", str(toml), "--output", str(out), "--resume", "--quiet"]) == 0
    with xr.open_dataset(out) as resumed:
        assert_same_bits(resumed, whole)


def test_a_full_disk_while_saving_a_chunk_keeps_the_others(tmp_path, capsys, monkeypatch,
                                                           whole):
    toml, out = tmp_path / "fr.toml", tmp_path / "fr.nc"
    toml.write_text(TOML)
    write = chunk_store._write_atomic

    def disk_full_at_chunk_2(path, data):
        if path.name == "chunk_000002.npz":
            with (path.parent / f".{path.name}.tmp").open("wb") as handle:
                handle.write(data[:100])  # what fit
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        write(path, data)

    monkeypatch.setattr(chunk_store, "_write_atomic", disk_full_at_chunk_2)
    assert cli.main(["run", str(toml), "--output", str(out), "--quiet"]) == 2
    monkeypatch.undo()
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "No space left on device" in err[0] and "2 finished" in err[0]
    computed = _counting(monkeypatch)
    assert cli.main(["run", str(toml), "--output", str(out), "--resume", "--quiet"]) == 0
    assert computed == [2, 3]
    with xr.open_dataset(out) as resumed:
        assert_same_bits(resumed, whole)


def test_a_fault_setting_up_the_next_chunk_keeps_the_finished_ones(tmp_path, monkeypatch,
                                                                   whole):
    """The next chunk is set up in a thread while one runs (sweep._run_here): what goes
    wrong there reaches the caller once the running chunk is saved, and the GIL's switch
    interval, shortened meanwhile, is Python's again."""
    out, interval = tmp_path / "fr.nc", sys.getswitchinterval()
    prepare = sweep.prepare_chunk

    def fails_at_chunk_2(spec_, chunk):
        if chunk == 2:
            raise Interrupted
        return prepare(spec_, chunk)

    monkeypatch.setattr(sweep, "prepare_chunk", fails_at_chunk_2)
    with pytest.raises(Interrupted):
        run_sweep(SWEEP, out, progress=False)
    monkeypatch.undo()
    assert sys.getswitchinterval() == interval
    saved = sorted(path.name for path in (tmp_path / "fr.nc.partial").glob("chunk_*.npz"))
    assert saved == ["chunk_000000.npz", "chunk_000001.npz"]
    computed = _counting(monkeypatch)
    resumed = run_sweep(SWEEP, out, resume=True, progress=False)
    assert computed == [2, 3]
    assert_same_bits(resumed, whole)


def test_an_output_folder_that_cannot_be_written_is_one_line(tmp_path, capsys, monkeypatch):
    toml = tmp_path / "fr.toml"
    toml.write_text(TOML)
    closed = tmp_path / "closed"
    closed.mkdir()
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        _refuse_writes_in(closed, monkeypatch)  # (root writes through permissions)
    else:
        closed.chmod(0o555)
    try:
        rc = cli.main(["run", str(toml), "--output", str(closed / "fr.nc"), "--quiet"])
    finally:
        monkeypatch.undo()
        closed.chmod(0o755)
    err = capsys.readouterr().err.splitlines()
    assert rc == 2 and len(err) == 1 and "cannot write in the folder" in err[0], err
    assert list(closed.iterdir()) == []


def _refuse_writes_in(folder: Path, monkeypatch) -> None:
    """Creating a file or folder in ``folder`` fails as the OS fails it for a user who may
    not write there."""
    for name in ("open", "mkdir"):
        def refused(path, *args, _real=getattr(os, name), **kwargs):
            if Path(path).parent == folder:
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))
            return _real(path, *args, **kwargs)

        monkeypatch.setattr(os, name, refused)


HUGE = """[grid]
frequency = { start = 100, stop = 300, num = 100000 }
gap = { start = 0, stop = 1e-5, num = 100000 }
"""


def test_a_sweep_of_months_asks_for_yes_before_any_work(tmp_path):
    (tmp_path / "huge.toml").write_text(HUGE)
    out = tmp_path / "huge.nc"
    run = _cli("run", tmp_path / "huge.toml", "--output", out)
    _, err = run.communicate(timeout=120)  # (without the check, it runs for months)
    assert run.returncode == 2 and len(err.splitlines()) == 1, err
    assert "10,000,000,000 points" in err and " days on " in err and "--yes" in err
    assert not out.exists() and not (tmp_path / "huge.nc.partial").exists()
    with pytest.raises(ParameterError, match="yes=True"):
        run_sweep(tmp_path / "huge.toml", progress=False)


def test_the_estimate_counts_the_steps_the_sweep_takes(capsys):
    # Without the stop the solver runs one period of the motion, Newton and the error
    # estimate; with it, the motion until it comes near its orbit, which the estimate
    # bounds by the slowest decay without the stop (contact adds damping: an upper
    # estimate). The solver's own count of the steps it took is the independent measure.
    grid = {"frequency": [120.0, 150.0, 180.0], "damping_ratio": [0.005, 0.02]}
    sweep_dict = spec(grid, {"hertz_stiffness": 0.0, "max_periods": 10**6})
    work = estimate(load_sweep(sweep_dict), 6, threads=1)
    ds = run_sweep(sweep_dict, progress=True)
    # (a grid this small says its size alone: run_estimate.SAMPLED_GRID)
    said = [line for line in capsys.readouterr().err.splitlines() if "compiling" not in line]
    assert said[0] == "harvester-sweep: 6 points"
    assert 0.8 < work.steps / float(ds["rk4_steps"].sum()) < 1.25
    sweep_dict = spec({"frequency": [100.0, 130.0, 160.0, 200.0], "gap": [0.5e-6, 1e-6, 3e-6]},
                      {"steps_per_period": 512})
    work = estimate(load_sweep(sweep_dict), 12, threads=1)
    ds = run_sweep(sweep_dict, progress=False)
    # (a grid no larger than the estimate's sample is solved whole by it: its own steps)
    assert 1.0 <= work.steps / float(ds["rk4_steps"].sum()) < 3.0


@pytest.mark.parametrize("argv, words", [
    (["scene", "--output", "{file}/x.nc"], "does not exist"),   # (a file where a folder is
    (["scene", "--plot", "{file}/x.png"], "does not exist"),    # due: refused even to root)
    (["run", "{toml}", "--output", "{folder}"], "is a folder"),
    (["scene", "--output", "{folder}"], "is a folder"),
    pytest.param(["scene", "--json", "--output", "/proc/x.nc"], "cannot write",  # (found
                 marks=pytest.mark.skipif(not Path("/proc").is_dir(), reason="no /proc")),  # late)
    (["plot", "{toml}", "--output", "{tmp}/p.png"], "cannot read it as netCDF"),
])
def test_files_that_cannot_be_written_or_read_are_one_line(argv, words, tmp_path, capsys):
    (tmp_path / "fr.toml").write_text(TOML)
    (tmp_path / "file").write_text("")
    (tmp_path / "folder.nc").mkdir()
    names = {"file": tmp_path / "file", "toml": tmp_path / "fr.toml",
             "folder": tmp_path / "folder.nc", "tmp": tmp_path}
    assert cli.main([arg.format(**names) for arg in argv]) == 2
    err = [line for line in capsys.readouterr().err.splitlines()
           if "compiling the RK4 kernel" not in line]  # (said when the cache is cold)
    assert len(err) == 1 and words in err[0], err


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="no /proc: no folder that takes no file")
@pytest.mark.parametrize("argv, works", [
    (["scene", "--json", "--output", "/proc/x.nc"], ("scene", "run_scene")),
    (["scene", "--json", "--plot", "/proc/x.png"], ("scene", "run_scene")),
    (["beam-scene", "--set", "n_modes=1", "--output", "/proc/x.nc"],
     ("beam_runs", "beam_scene")),
    (["beam-continue", "frequency", "140", "150", "--set", "n_modes=1", "--output",
      "/proc/x.nc"], ("beam_continuation", "continue_beam_branch")),
    (["beam-basins", "--set", "n_modes=1", "--samples", "4", "--output", "/proc/x.nc"],
     ("beam_basins", "beam_basins")),
])
def test_a_folder_that_takes_no_file_is_refused_before_any_work(argv, works, monkeypatch,
                                                                capsys):
    # (/proc takes no new file, even from root; the work, were it started, fails the test)
    import importlib

    def work(*args, **kwargs):
        raise AssertionError("the work started before the output was checked")

    monkeypatch.setattr(importlib.import_module(f"harvester_sweep.{works[0]}"), works[1], work)
    assert cli.main(argv) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if "compiling" not in line]
    assert len(err) == 1 and "cannot write in the folder /proc" in err[0], err
