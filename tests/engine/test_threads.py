"""How many threads a call of the engine takes (issue 44: on a shared machine every thread
of a call waits for the slowest), and the OpenMP threads' wait policy."""

import os
import subprocess
import sys

import numba
import numpy as np

from harvester_sweep import packing, resolve_parameters
from harvester_sweep._engine import LANES, PARAM
from harvester_sweep._engine.scheduler import SHORT_CALL, call_threads


def _rows(n, periods):
    row = packing.pack_parameters(resolve_parameters("paper"))
    rows = np.repeat(row[None, :], n, axis=0)
    rows[:, PARAM.max_periods] = periods
    return rows


def test_a_short_call_runs_on_one_thread():
    rows = _rows(64, 1)  # 64 lines of one period: an orbit solver's round
    assert rows[:, PARAM.max_periods] @ rows[:, PARAM.steps] < SHORT_CALL
    assert call_threads(rows, 64) == 1


def test_a_long_call_takes_a_thread_per_group_of_lanes():
    rows = _rows(3 * LANES, 1000)
    assert call_threads(rows, 3 * LANES) == min(numba.get_num_threads(), 3)
    assert call_threads(rows[:LANES], LANES) == 1  # (one thread steps LANES points at once)


def test_openmp_threads_sleep_unless_the_user_says_otherwise():
    code = "import os, harvester_sweep; print(os.environ['OMP_WAIT_POLICY'])"
    for given, expected in ((None, "passive"), ("active", "active")):
        env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
        if given:
            env["OMP_WAIT_POLICY"] = given
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                             text=True, check=True).stdout.strip()
        assert out == expected
