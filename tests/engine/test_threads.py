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


def test_a_modal_call_counts_a_grid_step_as_its_state_size_in_lane_steps():
    """The modal engine's call runs on one thread where its work is short by the lane
    engine's SHORT_CALL, a grid step of a point of state size D counted as D of that
    engine's RK4 steps: 64 beam points of 11 states measured over a period each (tens of
    milliseconds of work, fewer grid steps than SHORT_CALL) take the threads; one point
    over one period does not."""
    from harvester_sweep import modal_map
    from harvester_sweep.beam_packing import first_steps, pack_beam
    from harvester_sweep.beam_parameters import resolve_beam_parameters
    from harvester_sweep.beam_runs import system_of

    p = resolve_beam_parameters("bimorph_tip")
    bs = system_of(p)
    pk = pack_beam(p, bs, *first_steps(p, bs))
    D = pk.dims[0]
    rrows = np.repeat(pk.rrow[None, :], 64, axis=0)
    steps = rrows[0, modal_map.RealFields(*modal_map.real_fields(0, 0, 0)).steps]
    assert 64 * steps < SHORT_CALL <= 64 * steps * D
    assert modal_map._threads(rrows, np.ones(64), D) == min(numba.get_num_threads(), 64)
    assert modal_map._threads(rrows[:1], np.ones(1), D) == 1
