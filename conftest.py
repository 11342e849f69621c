"""The test suite on several processes (pytest-xdist, as the README's test command runs it):
the workers first fill numba's on-disk cache between them.

On a cold cache most of a suite's time is numba compiling two machine codes that share
little: the tip-mass model's lane engine with the orbit solver, and the beam's modal
engine, each minutes on one core. Each worker compiles its share (worker k the parts
k, k + workers, ...) before any test, then waits until every part is in the cache, so that
no test compiles what another worker is compiling; the tests then load them. The cache is
safe for processes that compile at once (harvester_sweep.jit), so a worker that gives up
waiting only compiles again. Without xdist nothing is done here: the first test that needs
an engine compiles it. (With xdist, a run of a few tests compiles both engines first, when
the cache is cold.)
"""

from __future__ import annotations

import tempfile
import time
import warnings
from pathlib import Path

#: The longest a worker waits for the others' parts [s] (a part takes minutes cold).
WAIT = 1800.0


def _tip_mass() -> None:
    """The lane engine and the orbit solver (a scene's solve compiles both, as a sweep's
    does), and the record of the scene's orbit."""
    from harvester_sweep import run_scene

    run_scene(steps_per_period=256, max_periods=40).series(periods=1)


def _beam() -> None:
    """The modal engine: a beam scene settles, measures and records its point."""
    from harvester_sweep.beam_runs import beam_scene

    beam_scene("bimorph_tip", periods=1, n_modes=1, gap=1e-6, frequency=230.0)


PARTS = (_tip_mass, _beam)


def pytest_sessionstart(session):
    worker = getattr(session.config, "workerinput", None)
    if worker is None or worker["workercount"] < 2:
        return
    index, count = int(worker["workerid"].removeprefix("gw")), worker["workercount"]
    shared = Path(tempfile.gettempdir()) / f"harvester-sweep-compiled-{worker['testrunuid']}"
    shared.mkdir(exist_ok=True)
    for k in range(index, len(PARTS), count):
        try:
            PARTS[k]()
        except Exception as error:  # (it fails again, and is reported, in the tests that need it)
            warnings.warn(f"compiling {PARTS[k].__name__} before the tests failed: {error!r}")
        finally:
            (shared / str(k)).touch()
    deadline = time.monotonic() + WAIT
    while (not all((shared / str(k)).exists() for k in range(len(PARTS)))
           and time.monotonic() < deadline):
        time.sleep(1.0)
