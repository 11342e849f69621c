"""A first compile of the orbit solver (orbits.compile_solver): where the engine is not yet
compiled and two cores may be used, a second process compiles the solver's decisions
meanwhile; it must import this checkout, and start only on a first compile."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from harvester_sweep import orbits

ROOT = Path(__file__).parents[2]  # the subprocess imports this checkout


class _Started:
    """subprocess.Popen's stand-in: notes what it was asked to start."""

    calls: list = []

    def __init__(self, args, env=None, **kwargs):
        _Started.calls.append((args, env))


def test_a_compiled_solver_starts_no_second_process(monkeypatch):
    orbits.compile_solver()  # (compiled, or loaded from the cache)
    monkeypatch.setattr(subprocess, "Popen", _Started)
    _Started.calls = []
    orbits.compile_solver()
    assert _Started.calls == []


def test_a_process_that_flushed_the_cache_starts_no_second_process_once_it_is_filled():
    """A process whose import found the source changed flushed the cache (the first processes
    of a fresh checkout do, finding no digest yet), and is told 'not warm' from then on;
    with the machine code back in the cache, its solves load it and start nothing (a
    process started for every solve cost each a new interpreter's wait)."""
    orbits.compile_solver()  # (the cache filled, or loaded)
    code = ("from harvester_sweep._engine import cache; cache._FLUSHED.append(True)"
            "; from harvester_sweep import orbits"
            "; print(orbits._first_compile(), orbits.solver_ready())")
    path = os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    done = subprocess.run([sys.executable, "-c", code], env={**os.environ, "PYTHONPATH": path},
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "False"], done.stdout


def test_one_core_starts_no_second_process(monkeypatch):
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0}, raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    monkeypatch.setattr(subprocess, "Popen", _Started)
    _Started.calls = []
    assert orbits._decisions_beside() is None and _Started.calls == []


def test_the_second_process_compiles_the_decisions_of_this_checkout(monkeypatch):
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    monkeypatch.setattr(subprocess, "Popen", _Started)
    _Started.calls = []
    assert isinstance(orbits._decisions_beside(), _Started)
    (args, env), = _Started.calls
    assert args[0] == sys.executable and args[-1].endswith("compile_decisions()")
    first = Path(env["PYTHONPATH"].split(os.pathsep)[0])
    assert first / "harvester_sweep" / "orbits.py" == Path(orbits.__file__).resolve()
