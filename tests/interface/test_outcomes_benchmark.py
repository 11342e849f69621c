"""benchmarks.outcomes counts what changed between two outputs of one sweep: built here
with known changes, its tables must say exactly those."""

from __future__ import annotations

import numpy as np
import xarray as xr

from benchmarks.outcomes import compare
from harvester_sweep._engine import STATUS


def _output(status, orbit, power, estimate, steps, run):
    dims = ("gap", "frequency")
    shape = (2, 3)
    values = {"status": status, "orbit_period": orbit, "power": power,
              "error_estimate": estimate, "rk4_steps": steps, "periods_run": run}
    return xr.Dataset({k: (dims, np.reshape(np.asarray(v, dtype=float), shape))
                       for k, v in values.items()})


def _row(lines, start):
    return next(line for line in lines if line.startswith(start))


def test_the_changes_built_in_are_the_ones_reported():
    s, n = STATUS.settled, STATUS.not_settled
    before = _output([s, s, s, n, n, s], [1, 2, 1, 0, 0, 1], [1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
                     [1e-6] * 6, [100, 200, 300, 1000, 1000, 400], [10, 20, 30, 1000, 1000, 40])
    # point 0: power moved by 1.5e-6 (beyond its estimate, within what the two results can
    # err at 16/15 of theirs, 2.13e-6), point 1 by 1e-7 (within its estimate), point 2 by
    # 1e-5 (beyond both); point 3 now settled; point 5 no longer; point 4 unchanged
    after = _output([s, s, s, s, n, n], [1, 2, 1, 1, 0, 0],
                    [1.0 + 1.5e-6, 2.0 * (1 + 1e-7), 3.0 * (1 + 1e-5), 4.0, 5.0, 6.0],
                    [1e-6] * 6, [100, 150, 300, 800, 1000, 1000], [10, 15, 30, 800, 1000, 1000])
    lines = compare(before, after)
    assert "settled before 4, after 4" in lines[0]
    assert _row(lines, "| settled -> not_settled |").split("|")[2].strip() == "1"
    assert _row(lines, "| not_settled -> settled |").split("|")[2].strip() == "1"
    assert "changed among the points settled in both: 0." in " ".join(lines)
    power = _row(lines, "| power |").split("|")
    assert float(power[2]) == 1e-5  # (printed to 3 digits)
    assert power[3].strip() == "2"
    assert power[4].strip() == "1"
    settled = _row(lines, "| settled |").split("|")
    assert float(settled[4]) == (100 + 150 + 300 + 1000) / (100 + 200 + 300 + 400)
    assert float(settled[5]) == (10 + 20 + 30 + 40) / 4
    assert float(settled[6]) == (10 + 15 + 30 + 1000) / 4
