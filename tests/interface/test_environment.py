"""A bad NUMBA_NUM_THREADS is bad input like any other: one line naming it (exit 2 from the
command line), not numba's traceback from inside its import."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

COMMAND = Path(sys.executable).parent / "harvester-sweep"  # (pip puts the script by python)


def _run(argv, threads):
    env = {**os.environ, "NUMBA_NUM_THREADS": threads}
    return subprocess.run(argv, env=env, capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("threads", ["0", "-2", "two", "2.0", ""])
def test_a_bad_thread_count_is_one_line_from_python(threads):
    done = _run([sys.executable, "-c", "import harvester_sweep"], threads)
    assert done.returncode != 0
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith(f"ValueError: NUMBA_NUM_THREADS [-] = {threads!r}: must be a whole "
                           "number >= 1"), done.stderr
    assert f"{os.sep}numba{os.sep}" not in done.stderr  # (raised before numba's import)


@pytest.mark.skipif(not COMMAND.exists(), reason="the command's script is not installed here")
def test_a_bad_thread_count_exits_2_in_one_line_from_the_command_line():
    done = _run([str(COMMAND), "parameters"], "0")
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr == ("harvester-sweep: error: NUMBA_NUM_THREADS [-] = '0': must be a "
                           f"whole number >= 1 (this machine has {os.cpu_count()} CPUs), or "
                           "unset for all of them\n")


def test_a_good_thread_count_runs():
    done = _run([sys.executable, "-c", "import numba, harvester_sweep; "
                 "print(numba.config.NUMBA_NUM_THREADS)"], "1")
    assert done.returncode == 0 and done.stdout.strip() == "1", done.stderr
