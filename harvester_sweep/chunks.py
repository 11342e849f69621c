"""A chunk of a sweep: whole lines of points packed, run through the engine in one call,
and arranged back on the grid. The unit of work of a sweep, locally or on a Dask worker.

Under frequency continuation a line is the frequency axis at fixed values of the other
axes and one direction, each point starting from the previous point's final state (a
down line runs from its highest frequency); without continuation every point is a line
of one, run from rest. Lines never interact, so a point's result does not depend on the
chunking, the thread count or the machine that ran its chunk.

A chunk of a beam sweep (``spec.model == "beam"``) is solved by the beam's own solver
(:func:`beam_chunk`): its lines swept along frequency together, one step after another
(``beam_runs._swept``), or its points each from rest.
"""

from __future__ import annotations

import numpy as np

from .outputs import STROBES, metric_index
from .packing import pack_points
from .results import solve


def chunk_points(spec, chunk: int) -> int:
    """Number of points of chunk ``chunk`` of ``spec`` (a SweepSpec)."""
    return len(spec.chunk_lines(chunk)) * spec.line_length


def compute_chunk(spec, chunk: int, threads: int | None = None, on_points=None,
                  prepared: dict | None = None) -> dict:
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
    prepared : dict, optional
        ``prepare_chunk(spec, chunk)``, made beforehand (the sweep makes the next chunk's
        while this one runs); made here when not given.

    Returns
    -------
    dict
        ``metrics``: float64 (lines, points per line, len(spec.metrics)) in ascending
        frequency order; ``strobe``: float64 (lines, points per line, samples, 2) holding
        the samples of outputs.STROBES, x [m] and V [V]; ``error_estimate``: float64 (lines,
        points per line) [-]; each of outputs.RUN_OUTPUTS (lines, points per line, its own
        dimensions); ``run_time``: solve time [s]. A beam chunk's: see :func:`beam_chunk`.
    """
    import numba

    if threads is not None:
        numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
    if spec.model == "beam":
        length = spec.line_length if spec.continuation else 1
        return beam_chunk(spec, chunk, None if on_points is None
                          else lambda done, total, what: on_points(chunk_points(spec, chunk)
                                                                   // length))
    if prepared is None:
        prepared = prepare_chunk(spec, chunk)
    reverse = prepared["reverse"]
    n, length = len(reverse), spec.line_length
    results = solve(prepared["packed"], prepared["successors"], prepared["estimated"],
                    spec.samples, on_points)

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


def prepare_chunk(spec, chunk: int) -> dict:
    """What the engine needs to run the lines of chunk ``chunk`` of a tip-mass sweep
    ``spec``: its points resolved and packed (``packed``, line-major, each line in the
    order it runs), each point's successor on its line (``successors``, -1 at a line's
    end), which points take an error estimate (``estimated``), and which lines run down
    in frequency (``reverse``). Python only, no engine call: a sweep makes the next
    chunk's while the engine runs this one."""
    lines = spec.chunk_lines(chunk)
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
    successors = np.arange(1, n * length + 1).reshape(n, length)
    successors[:, -1] = -1
    position = np.where(reverse[:, None], length - 1 - np.arange(length)[None, :],
                        np.arange(length)[None, :])
    estimated = spec.estimated(np.asarray(lines)[:, None] * length + position)
    return {"packed": pack_points(points), "successors": successors.ravel(),
            "estimated": estimated.ravel(), "reverse": reverse}


def beam_chunk(spec, chunk: int, progress=None) -> dict:
    """Solve chunk ``chunk`` of a beam sweep ``spec``: each line swept along frequency in its
    direction, every point starting from the previous one's orbit, or each point (a line of
    one) from rest.

    ``progress(done, total, what)``, if given, is told after each frequency step of the
    chunk's lines (``total`` steps), or once for points. Returns each output of
    beam_runs.solve_beam (``BeamSolution.values``) as float64 (lines, points per line,
    and its own width: the modes, the multipliers, NaN beyond a point's own) in ascending
    frequency order along a line, and ``run_time``: solve time [s].
    """
    import time

    from .beam_runs import _swept, solve_beam

    lines = spec.chunk_lines(chunk)
    length = spec.line_length
    points = [spec.point_parameters(spec.values_at(line * length + k))
              for line in lines for k in range(length)]
    begun = time.perf_counter()
    if spec.continuation:
        direction = spec.directions[lines[0] * len(spec.directions) // spec.n_lines]
        solved = _swept(points, {"line": None, "frequency": spec.grid["frequency"]},
                        [len(lines), length], direction, progress)
    else:
        solved = solve_beam(points)
        if progress is not None:
            progress(1, 1, f"{len(points)} points")
    shape = (len(lines), length)
    return {**{name: np.asarray(values).reshape(shape + np.shape(values)[1:])
               for name, values in solved.values.items()},
            "run_time": np.float64(time.perf_counter() - begun)}
