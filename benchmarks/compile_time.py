"""numba's compile time: a first run's, and a test suite's by function and by test.

    python -m benchmarks.compile_time [--output FILE]
    python -m pytest -p benchmarks.compile_time tests      # a suite's, on a cold cache
    python -m pytest -p benchmarks.compile_time -n 2 --dist loadfile tests   # (its workers')

The command compiles, each in a new process with an empty numba cache of its own (a
temporary ``NUMBA_CACHE_DIR``), what a first run compiles: the lane engine
(``period_map.compile_engine``) then the orbit solver (``orbits.compile_solver``), as a
first sweep does; and a first beam scene (``beam_scene``, one mode), which compiles the
modal engine. It reports their times and every package function compiled more than once
in them: numba compiles a function once for each signature, and a constant argument is a
signature of its own (docs/engine.md, "One compile per function").

As a pytest plugin it listens to numba's ``numba:compile`` events, fired only when a
function is compiled (not when it is loaded from the cache), books each to the test that
triggered it, and prints the compile time by entry point and by test at the end. On a warm
cache it prints nothing but what a test compiles uncached.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile
import time

from numba.core import event

PACKAGE = "harvester_sweep"
_ROWS: list = []  # (depth, module.qualname, seconds, test) of each compile
_TEST = [None]


class _Compiles(event.Listener):
    """Books every compile: its depth (0 for one called from Python, callees below),
    function, time and test."""

    def __init__(self):
        self._started = []

    def on_start(self, ev):
        self._started.append(time.perf_counter())

    def on_end(self, ev):
        took = time.perf_counter() - self._started.pop()
        function = ev.data["dispatcher"].py_func
        _ROWS.append((len(self._started), f"{function.__module__}.{function.__qualname__}",
                      took, _TEST[0]))


event.register("numba:compile", _Compiles())


def _repeated() -> dict:
    """The package's functions compiled more than once: name -> times."""
    counts = collections.Counter(name for _, name, _, _ in _ROWS
                                 if name.startswith(PACKAGE + "."))
    return {name: n for name, n in counts.items() if n > 1}


def _first_run(which: str) -> dict:
    """In this process: compile what a first run of ``which`` compiles; its times [s]."""
    began = time.perf_counter()
    if which == "tip_mass":
        from harvester_sweep import orbits, period_map

        period_map.compile_engine()
        engine = time.perf_counter()
        orbits.compile_solver()
        times = {"engine": engine - began, "solver": time.perf_counter() - engine}
    else:
        from harvester_sweep.beam_runs import beam_scene

        beam_scene("bimorph_tip", periods=1, n_modes=1, gap=1e-6, frequency=230.0)
        times = {"beam scene": time.perf_counter() - began}
    return {"times": times, "repeated": _repeated()}


def _measured(which: str) -> dict:
    """_first_run in a new process with an empty numba cache of its own."""
    with tempfile.TemporaryDirectory() as cache:
        out = subprocess.run(
            [sys.executable, "-m", "benchmarks.compile_time", "--first-run", which],
            env={**os.environ, "NUMBA_CACHE_DIR": cache}, capture_output=True, text=True,
            check=True).stdout
    return json.loads(out.splitlines()[-1])


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", help="write the markdown table here too")
    parser.add_argument("--first-run", choices=("tip_mass", "beam"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.first_run:  # (the child process of _measured)
        print(json.dumps(_first_run(args.first_run)))
        return
    from benchmarks.variants import provenance, report

    lines = ["# A first run's compile time", "", provenance(),
             "Command: python -m benchmarks.compile_time", "",
             "| first run | compile time | functions compiled more than once (times) |",
             "| --- | --- | --- |"]
    for which in ("tip_mass", "beam"):
        result = _measured(which)
        times = ", ".join(f"{what} {seconds:.1f} s" for what, seconds in result["times"].items())
        repeated = ", ".join(f"`{name.removeprefix(PACKAGE + '.')}` ({n})"
                             for name, n in result["repeated"].items())
        lines.append(f"| {which} | {times} | {repeated or 'none'} |")
    report(lines, args.output)


# -- as a pytest plugin ------------------------------------------------------------------

def pytest_runtest_setup(item):
    _TEST[0] = item.nodeid


def pytest_sessionfinish(session):
    # (an xdist worker: its compiles to the controller, which prints them all)
    if hasattr(session.config, "workeroutput"):
        session.config.workeroutput["numba_compiles"] = json.dumps(_ROWS)


def pytest_testnodedown(node, error):
    rows = getattr(node, "workeroutput", {}).get("numba_compiles")
    if rows:
        _ROWS.extend(tuple(row) for row in json.loads(rows))


def pytest_terminal_summary(terminalreporter):
    top = [row for row in _ROWS if row[0] == 0]
    if not top:
        return
    write = terminalreporter.write_line
    by_function, by_test = collections.defaultdict(list), collections.Counter()
    for _, name, seconds, test in top:
        by_function[name].append(seconds)
        by_test[test] += seconds
    write(f"numba compile: {sum(r[2] for r in top):.1f} s in {len(top)} compiles called "
          "from Python (their callees included)")
    for name, times in sorted(by_function.items(), key=lambda kv: -sum(kv[1]))[:15]:
        write(f"  {sum(times):7.1f} s  {len(times)}x  {name}")
    write("by test:")
    for test, seconds in by_test.most_common(10):
        write(f"  {seconds:7.1f} s  {test}")
    if _repeated():
        write(f"compiled more than once: {_repeated()}")


if __name__ == "__main__":
    main()
