"""The test suite on several processes (pytest-xdist, as the README's test command runs it):
the workers fill numba's on-disk cache between them, and no two compile the same engine.

On a cold cache most of a suite's time is numba compiling two machine codes that share
little: the tip-mass model's lane engine with the orbit solver, and the beam's modal
engine, each minutes on one core. Each worker compiles its share of them (PARTS, dealt
by WORKER) once the tests are collected and dealt out, and then runs its tests. A part
another worker is still compiling is waited for, not compiled again: in a worker that has
done its share, numba's compiling of a function of such a part waits until the part is in
the cache (and then loads it), and so does starting another process (a command-line test,
a Dask worker, a notebook's kernel, which jupyter_client starts with subprocess.Popen),
which would compile what it lacks. The cache is safe for processes that compile at once
(harvester_sweep.jit), so a worker that gives up waiting only compiles again. Without
xdist nothing is done here: the first test that needs an engine compiles it.

The tip-mass model's part is the longer: the lane engine, then the orbit solver, which
calls it. So the beam's worker first compiles the solver's set-up and per-point decisions,
which need no engine (orbits.compile_decisions), and worker 0, compiling the solver after
the engine, waits for them (FUNCTIONS) and loads them, even while it compiles its own part.

The files are dealt out so that waiting is rare (_Dealer): the beam's part compiles
sooner, and its worker runs the files that need nothing else (BEAM_FIRST) while worker 0
still compiles the tip-mass model's; worker 0 starts on the longest of the others
(LONGEST), and the files that take longest go before the rest, so that no worker ends
the run alone on a long one.
"""

from __future__ import annotations

import multiprocessing.process
import subprocess
import tempfile
import time
import warnings
from pathlib import Path

import pytest

#: The longest a worker waits for another's part [s] (a part takes minutes cold).
WAIT = 1800.0


def _tip_mass() -> None:
    """The lane engine and the orbit solver (a scene's solve compiles both, as a sweep's
    does), and the record of the scene's orbit. The engine first: with it compiled, the
    solver's compile starts no process for its decisions (orbits.compile_solver), which
    the other worker compiles (_decisions)."""
    from harvester_sweep import period_map, run_scene

    period_map.compile_engine()
    run_scene(steps_per_period=256, max_periods=40).series(periods=1)


def _beam() -> None:
    """The modal engine: a beam scene settles, measures and records its point."""
    from harvester_sweep.beam_runs import beam_scene

    beam_scene("bimorph_tip", periods=1, n_modes=1, gap=1e-6, frequency=230.0)


def _decisions() -> None:
    """The orbit solver's set-up and per-point decisions, apart from the engine."""
    from harvester_sweep.orbits import compile_decisions

    compile_decisions()


PARTS = (_tip_mass, _decisions, _beam)
#: The worker (modulo the worker count) that compiles each part, in the order of PARTS.
WORKER = (0, 1, 1)
#: Functions whose part is not their module's: those compile_decisions compiles. A worker
#: compiling its own part waits for these alone (they are the first part's callees).
FUNCTIONS = {f"harvester_sweep.orbits.{name}": 1
             for name in ("_set_up", "_start", "_newton", "_transient", "_estimate")}
#: The test files that need no part but the beam's (or none): the worker that compiles
#: the beam, the shorter part, runs them while the other still compiles the tip-mass
#: model's (:class:`_Dealer`). Last, those whose last tests compare with the tip-mass
#: model, and wait for it. A file misplaced here only waits.
BEAM_FIRST = (
    "tests/physics/test_beam_recontact.py", "tests/interface/test_beam_interface.py",
    "tests/interface/test_structure.py", "tests/physics/test_bimorph.py",
    "tests/interface/test_beam_estimate.py", "tests/physics/test_beam_basins.py",
    "tests/physics/test_rod.py", "tests/physics/test_beam.py",
    "tests/physics/test_beam_accuracy.py",
)
#: The other files that take longest, longest first, dealt out before the rest, so that
#: no worker ends the run alone on one of them.
LONGEST = (
    "tests/physics/test_branch_accuracy.py", "tests/physics/test_neimark_sacker_accuracy.py",
    "tests/physics/test_beam_continuation.py", "notebooks/04_design_maps.ipynb",
    "tests/interface/test_faults.py", "notebooks/07_beam_vs_tip_mass.ipynb",
    "tests/physics/test_extreme.py", "tests/interface/test_adversarial.py",
    "tests/interface/test_plots.py", "notebooks/05_s_curve.ipynb",
    "notebooks/03_bifurcations.ipynb", "tests/interface/test_cluster.py",
    "tests/physics/test_orbits.py", "tests/interface/test_cli.py",
    "notebooks/06_moving_stop.ipynb", "notebooks/01_paper_scene.ipynb",
    "tests/physics/test_continuation.py", "notebooks/02_frequency_response.ipynb",
    "tests/engine/test_cache.py", "tests/interface/test_beam_cluster.py",
)
#: The part that holds each module's compiled functions, by the first prefix of PARTS'
#: index that the module's name starts with; None: none, compiled where first needed (the
#: acceptance rules, a few small functions that both models' solvers call, so that a beam
#: test that needs one does not wait for the whole tip-mass part).
_OWNERS = (("harvester_sweep._engine.modal", 2), ("harvester_sweep.acceptance", None),
           ("harvester_sweep", 0))

_shared: list[Path] = []  # the folder of the run's markers, one file per part compiled
_finished: set[int] = set()


def _done(k: int) -> bool:
    if k not in _finished and (_shared[0] / str(k)).exists():
        _finished.add(k)
    return k in _finished


def _wait(parts) -> None:
    """Wait until every part of ``parts`` is compiled (or WAIT has passed)."""
    deadline = time.monotonic() + WAIT
    while not all(_done(k) for k in parts) and time.monotonic() < deadline:
        time.sleep(1.0)


def _name(function) -> str:
    return f"{getattr(function, '__module__', '')}.{getattr(function, '__qualname__', '')}"


def _part_of(function):
    """The part that holds ``function``'s compiled code, or None."""
    if _name(function) in FUNCTIONS:
        return FUNCTIONS[_name(function)]
    module = getattr(function, "__module__", "") or ""
    for prefix, k in _OWNERS:
        if module == prefix or module.startswith(prefix + "."):
            return k
    return None


_compiling_own = [True]  # (while this worker compiles its parts: wait for FUNCTIONS alone)
_mine: list[int] = []  # the parts this worker compiles


def _waiting_for_functions() -> None:
    """From now on in this worker: numba compiling a function of a part not yet compiled
    first waits for the part: only for FUNCTIONS' while the worker compiles its own parts
    (the others are its parts' callees, or compiled where they are first needed)."""
    from numba.core import sigutils
    from numba.core.dispatcher import Dispatcher

    compile_ = Dispatcher.compile

    def compile(self, sig):
        k = _part_of(self.py_func)
        waits = k is not None and k not in _mine and not _done(k)
        if waits and (not _compiling_own[0] or _name(self.py_func) in FUNCTIONS):
            args, _ = sigutils.normalize_signature(sig)
            if self.overloads.get(tuple(args)) is None:
                _wait([k])
        return compile_(self, sig)

    Dispatcher.compile = compile


def _waiting_for_parts() -> None:
    """From now on in this worker: numba compiling a function of a part not yet compiled,
    and starting a process, first wait for the parts (see the module's docstring)."""
    _compiling_own[0] = False
    popen_init, start = subprocess.Popen.__init__, multiprocessing.process.BaseProcess.start

    def init(self, *args, **kwargs):
        _wait(range(len(PARTS)))
        popen_init(self, *args, **kwargs)

    def start_(self):
        _wait(range(len(PARTS)))
        start(self)

    subprocess.Popen.__init__ = init
    multiprocessing.process.BaseProcess.start = start_


@pytest.hookimpl(trylast=True)
def pytest_collection_finish(session):
    # (after xdist has sent this worker's collection, so that the tests are dealt out while
    # the workers compile)
    worker = getattr(session.config, "workerinput", None)
    if worker is None or worker["workercount"] < 2:
        return
    index, count = int(worker["workerid"].removeprefix("gw")), worker["workercount"]
    _shared.append(Path(tempfile.gettempdir())
                   / f"harvester-sweep-compiled-{worker['testrunuid']}")
    _shared[0].mkdir(exist_ok=True)
    _mine.extend(k for k in range(len(PARTS)) if WORKER[k] % count == index)
    _waiting_for_functions()
    for k in _mine:
        try:
            PARTS[k]()
        except Exception as error:  # (it fails again, and is reported, in the tests that need it)
            warnings.warn(f"compiling {PARTS[k].__name__} before the tests failed: {error!r}")
        finally:
            (_shared[0] / str(k)).touch()
    _compiled_again()
    _waiting_for_parts()


def _compiled_again() -> None:
    """Warn where this worker's parts compiled a function of FUNCTIONS that another worker
    compiled for them: compile_decisions then gives it other types than the solver does."""
    import importlib

    for name, k in FUNCTIONS.items():
        module, function = name.rsplit(".", 1)
        if k not in _mine and sum(getattr(importlib.import_module(module), function)
                                  .stats.cache_misses.values()):
            warnings.warn(f"{name} was compiled again: compile_decisions does not give it "
                          "the types the solver calls it with")


def pytest_configure(config):
    # (the files in the order of pytest_collection_modifyitems, not xdist's, by test count)
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False


def pytest_collection_modifyitems(session, config, items):
    # (every worker collects the same order: xdist requires it)
    # (a file renamed or removed would silently lose its place in the order)
    gone = [path for path in BEAM_FIRST + LONGEST if not (config.rootpath / path).exists()]
    if gone:
        raise pytest.UsageError(f"conftest.py orders test files that do not exist: {gone}")
    rank = {path: k for k, path in enumerate(BEAM_FIRST + LONGEST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class _Dealer(LoadFileScheduling):
        """xdist's scheduling of whole files, each worker dealt first the files that need
        what it compiles: worker 0, which compiles the tip-mass model's part, the first
        file not in BEAM_FIRST (the longest), any other the first in BEAM_FIRST; each
        the first file left when there is none of its kind. Only the order changes: a
        file dealt to a worker before the part it needs is compiled waits for it."""

        def _assign_work_unit(self, node):
            tip_mass = node.workerinput["workerid"] == "gw0"
            for scope in self.workqueue:
                if (scope in BEAM_FIRST) != tip_mass:
                    self.workqueue.move_to_end(scope, last=False)
                    break
            super()._assign_work_unit(node)

    return _Dealer(config, log)
