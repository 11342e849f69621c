"""A chunk of a sweep: whole lines of points packed, run through the engine in one call,
and arranged back on the grid. The unit of work of a sweep, locally or on a Dask worker.

Under frequency continuation a line is the frequency axis at fixed values of the other
axes and one direction, each point starting from the previous point's final state (a
down line runs from its highest frequency); without continuation every point is a line
of one, run from rest. Lines never interact, so a point's result does not depend on the
chunking, the thread count or the machine that ran its chunk.
"""

from __future__ import annotations

import numpy as np

from .outputs import STROBES, metric_index
from .packing import pack_points
from .results import solve


def chunk_points(spec, chunk: int) -> int:
    """Number of points of chunk ``chunk`` of ``spec`` (a SweepSpec)."""
    first = chunk * spec.lines_per_chunk
    return (min(first + spec.lines_per_chunk, spec.n_lines) - first) * spec.line_length


def compute_chunk(spec, chunk: int, threads: int | None = None, on_points=None) -> dict:
    """Run the lines of one chunk.

    Parameters
    ----------
    spec : SweepSpec
    chunk : int
        Chunk index, 0 <= chunk < ``spec.n_chunks``.
    threads : int, optional
        numba threads to use (on a worker process sharing its machine with others).
    on_points : callable, optional
        Called with the number of points newly finished, as they finish (about every
        0.2 s); what it raises stops the chunk and is raised again.

    Returns
    -------
    dict
        ``metrics``: float64 (lines, points per line, len(spec.metrics)) in ascending
        frequency order; ``strobe``: float64 (lines, points per line, samples, 2) holding
        the samples of outputs.STROBES, x [m] and V [V]; ``error_estimate``: float64 (lines,
        points per line) [-]; each of outputs.RUN_OUTPUTS (lines, points per line, its own
        dimensions); ``run_time``: solve time [s].
    """
    import numba

    if threads is not None:
        numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
    first = chunk * spec.lines_per_chunk
    lines = range(first, min(first + spec.lines_per_chunk, spec.n_lines))
    n, length = len(lines), spec.line_length
    # Line-major, each line in the order it runs (a down line from its highest frequency):
    # point (i, k) continues from point (i, k - 1).
    reverse = np.zeros(n, dtype=bool)
    continuation = spec.continuation
    # (Python numbers and indices, looked up once: this loop takes ~20 us a point)
    index = [axis.tolist() for axis in np.unravel_index(np.asarray(lines), spec.line_shape)]
    if continuation:
        reverse[:] = [spec.directions[d] == "down" for d in index.pop(0)]
    axes = [(a, spec.grid[a].tolist()) for a in spec.line_axes]
    frequencies = spec.grid["frequency"].tolist() if continuation else []
    points = []
    for i in range(n):
        values = {a: grid[j[i]] for (a, grid), j in zip(axes, index)}
        for step in range(length):
            if continuation:
                values["frequency"] = frequencies[length - 1 - step if reverse[i] else step]
            points.append(spec.point_parameters(values))
    # Each from rest: a line's first point, and a point after one that diverged.
    packed = pack_points(points)
    successors = np.arange(1, n * length + 1).reshape(n, length)
    successors[:, -1] = -1
    position = np.where(reverse[:, None], length - 1 - np.arange(length)[None, :],
                        np.arange(length)[None, :])
    estimated = spec.estimated(np.asarray(lines)[:, None] * length + position)
    results = solve(packed, successors.ravel(), estimated.ravel(), spec.samples, on_points)

    def arranged(values):  # on the grid: down lines ran from the highest frequency
        values = values.reshape((n, length) + values.shape[1:])
        values[reverse] = values[reverse, ::-1]
        return np.ascontiguousarray(values)

    columns = [metric_index(name) for name in spec.metrics]
    strobe = results.strobes[..., list(STROBES.values())]
    run = {name: arranged(values) for name, values in results.run_outputs().items()}
    return {"metrics": arranged(results.metrics[:, columns]),
            "strobe": arranged(strobe),
            "error_estimate": arranged(results.errors),
            **run,
            "run_time": np.float64(results.run_time)}
