"""What a solve spends in the engine, and what in the periodic-orbit solver's Python.

The solver (``harvester_sweep.orbits``) calls the engine's ``run_points`` once a round and
decides, in Python between the calls, what each point runs next. ``EngineCalls`` records
the span of every call made within its ``with`` block, so that a benchmark can say how
much of a solve's wall time the engine took and how much the Python around it. Since
issue 47 the solver's rounds run compiled and call the engine from compiled code: no call is
seen for them (``spans`` stays empty), only for a checkout from before.
"""

from __future__ import annotations

import time


class EngineCalls:
    """Within ``with EngineCalls(engine) as calls``: ``calls.spans``, the (start, end)
    wall-clock times [s] of every ``engine.run_points`` call (``engine``: the
    ``harvester_sweep._engine`` module of the checkout measured)."""

    def __init__(self, engine):
        self.engine = engine
        self.spans: list[tuple[float, float]] = []

    def __enter__(self):
        self._run = run = self.engine.run_points

        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                return run(*args, **kwargs)
            finally:
                self.spans.append((start, time.perf_counter()))

        self.engine.run_points = timed
        return self

    def __exit__(self, *exc):
        self.engine.run_points = self._run

    @property
    def seconds(self) -> float:
        """Time in the engine's calls [s]."""
        return sum(end - start for start, end in self.spans)

    @property
    def between(self) -> float:
        """Time between the first call and the last that was not in a call [s]: the
        solver's Python between its rounds."""
        return sum(b[0] - a[1] for a, b in zip(self.spans, self.spans[1:]))
