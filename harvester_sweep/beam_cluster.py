"""The beam's sweeps on a Dask cluster: a local one of N worker processes, or a running
dask.distributed scheduler.

The grid is cut into chunks: of points where no line is swept, of whole lines along
frequency where they are (each chunk sweeps its own lines up or down, so that a line's
continuation stays in one task). A worker solves its chunk with the functions a local run
uses (``beam_runs.solve_beam``, ``beam_runs._swept``), each point alone, so the numbers
are the same bits as the local run's; the chunks come back to this process to be gathered
into the same dataset.
"""

from __future__ import annotations

import math
import numbers
import time
from concurrent.futures import CancelledError
from functools import partial

import numpy as np

from .beam_parameters import DEFAULT_BEAM_PRESET
from .beam_runs import BeamSolution, _swept, beam_sweep, solve_beam
from .cluster import (
    NO_WORKERS_SECONDS,
    POLL_SECONDS,
    ClusterError,
    _workers,
    check_scheduler,
    connect,
    threads_per_worker,
)
from .parameters import ParameterError, is_number, value_text

#: Chunks per worker thread when ``chunk_size`` is not given: a slow chunk (many contact
#: modes, a point that does not settle) evens out among the others [-].
CHUNKS_PER_THREAD = 4


def check_cluster(workers, scheduler):
    """Refuse, in one line, ``workers`` and ``scheduler`` together, a worker count that is
    not a whole number >= 1 or an address dask cannot parse; returns the worker count."""
    if workers is not None and scheduler is not None:
        raise ParameterError("give workers or scheduler, not both")
    if workers is not None:
        workers = _whole("workers", workers)
    if scheduler is not None:
        check_scheduler(scheduler)
    return workers


def run_beam_sweep(axes: dict, preset: str | None = DEFAULT_BEAM_PRESET, directions=None,
                   progress=None, *, workers: int | None = None, scheduler: str | None = None,
                   chunk_size: int | None = None, **fixed):
    """:func:`beam_runs.beam_sweep` (the same arguments and dataset), its grid run on Dask.

    Parameters
    ----------
    workers : int, optional
        Run the chunks on a new local Dask cluster of this many worker processes.
    scheduler : str, optional
        Run them on the running dask.distributed scheduler at this address
        (e.g. ``"tcp://127.0.0.1:8786"``); its workers must have harvester_sweep installed.
        With neither, the grid is solved in this process (``beam_sweep``).
    chunk_size : int, optional
        Points per chunk of an unswept grid, lines along frequency per chunk (of one
        direction) of a swept one; default: about CHUNKS_PER_THREAD chunks per worker
        thread.
    progress : callable, optional
        ``progress(done, total, what)`` once per finished chunk (``total`` chunks).

    Raises
    ------
    ParameterError
        Bad input (the grid's points, workers, scheduler, chunk_size), dask.distributed
        not installed, or a scheduler that cannot be reached: before anything is solved.
    cluster.ClusterError
        (a ParameterError) A chunk's workers kept dying, the connection to the scheduler
        was lost, or no worker was left for NO_WORKERS_SECONDS: one line, the sweep lost.
    """
    workers = check_cluster(workers, scheduler)
    if chunk_size is not None:
        chunk_size = _whole("chunk_size", chunk_size)
    if workers is None and scheduler is None:
        return beam_sweep(axes, preset, directions, progress, **fixed)
    solver = partial(solve_on_dask, workers=workers, scheduler=scheduler,
                     chunk_size=chunk_size)
    return beam_sweep(axes, preset, directions, progress, solver=solver, **fixed)


def _whole(name: str, value) -> int:
    if not is_number(value) or not isinstance(value, numbers.Integral) or value < 1:
        raise ParameterError(f"{name} [-] = {value_text(value)}: must be an integer >= 1")
    return int(value)


def solve_on_dask(points, axes, shape, directions=None, progress=None, *, workers=None,
                  scheduler=None, chunk_size=None) -> list:
    """``beam_runs.solve_grid`` on Dask (its arguments and result; see run_beam_sweep for
    the keywords): the chunks submitted at once, every direction's, and gathered as they
    finish."""
    client, cluster = connect(workers, scheduler)
    try:
        threads = threads_per_worker(workers) if cluster is not None else None
        size = chunk_size or _default_size(points, shape, axes, directions, client)
        tasks = _chunks(len(points), axes, shape, directions, size)
        results = _gather(client, points, axes.get("frequency"), tasks, threads, progress)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return [_assemble(len(points), [(ids, results[k]) for k, (d, ids) in enumerate(tasks)
                                     if d == direction])
            for direction in (directions or (None,))]


def _lines(axes, shape) -> np.ndarray:
    """The grid's lines along frequency: (lines, points of a line) indices of the points,
    as beam_runs._swept orders them."""
    f_axis = list(axes).index("frequency")
    grid = np.arange(math.prod(shape)).reshape(shape)
    return np.moveaxis(grid, f_axis, -1).reshape(-1, shape[f_axis])


def _default_size(points, shape, axes, directions, client) -> int:
    """Points (or lines) per chunk for about CHUNKS_PER_THREAD chunks per worker thread,
    the directions' chunks together."""
    threads = max(1, sum(client.nthreads().values()))
    if not directions:
        return max(1, math.ceil(len(points) / (CHUNKS_PER_THREAD * threads)))
    lines = len(_lines(axes, shape)) * len(directions)
    return max(1, math.ceil(lines / (CHUNKS_PER_THREAD * threads)))


def _chunks(n, axes, shape, directions, size) -> list:
    """The tasks: (direction or None, indices of its points: (points,) or (lines, line
    length))."""
    if not directions:
        return [(None, np.arange(a, min(a + size, n))) for a in range(0, n, size)]
    lines = _lines(axes, shape)
    return [(d, lines[a:a + size]) for d in directions for a in range(0, len(lines), size)]


def _solve_chunk(points, direction, frequencies, threads) -> BeamSolution:
    """One chunk on a worker: its points solved each from rest, or its lines (``points``
    line after line, each at the frequency axis's values ``frequencies``) swept in
    ``direction``; without the strobes (nor, swept, the end states)."""
    if threads is not None:
        import numba

        numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
    if direction is None:
        sol = solve_beam(points)
        return BeamSolution(sol.values, sol.ends, None)
    shape = [len(points) // len(frequencies), len(frequencies)]
    sol = _swept(points, {"line": None, "frequency": frequencies}, shape, direction)
    return BeamSolution(sol.values, None, None)


def _gather(client, points, frequencies, tasks, threads, progress) -> dict:
    """Each task's BeamSolution (task index -> solution), progress told per chunk; a
    chunk lost is a ClusterError at once (the others cancelled)."""
    from dask.distributed import wait
    from distributed import KilledWorker

    futures = {}
    for k, (direction, ids) in enumerate(tasks):
        chunk = [points[i] for i in np.ravel(ids)]
        futures[client.submit(_solve_chunk, chunk, direction, frequencies, threads,
                              pure=False)] = k
    results, pending, alone_since = {}, set(futures), None
    while pending:
        try:
            done, pending = wait(pending, timeout=POLL_SECONDS, return_when="FIRST_COMPLETED")
        except TimeoutError:  # (none finished within POLL_SECONDS)
            done = set()
        for future in done:
            k = futures[future]
            why = None
            try:
                results[k] = future.result()
            except KilledWorker:
                why = "the workers running it kept dying (dask's KilledWorker)"
            except CancelledError:
                why = "dask cancelled it (the scheduler restarted or forgot it)"
            except (OSError, TimeoutError) as error:  # (CommClosedError among them)
                why = f"the connection to the scheduler was lost ({error})"
            except ImportError as error:
                why = (f"a worker cannot import it ({error}): harvester_sweep must be "
                       "installed on every worker")
            if why is not None:
                client.cancel(list(pending))
                raise ClusterError(f"chunk {k + 1} of {len(tasks)} of the beam sweep did not "
                                   f"come back from dask: {why}; nothing was written")
            future.release()
            if progress is not None:
                direction, ids = tasks[k]
                what = (f"{ids.size} points" if direction is None else
                        f"{direction} sweep, {len(ids)} line(s) of {ids.shape[1]} frequencies")
                progress(len(results), len(tasks), f"chunk {k + 1}: {what}")
        if done or not pending or _workers(client) > 0:
            alone_since = None
        elif alone_since is None:
            alone_since = time.monotonic()
        elif time.monotonic() - alone_since > NO_WORKERS_SECONDS:
            client.cancel(list(pending))
            raise ClusterError(f"{len(pending)} of {len(tasks)} chunks of the beam sweep did "
                               f"not come back from dask: no dask worker was left for "
                               f"{NO_WORKERS_SECONDS:g} s; nothing was written")
    return results


def _assemble(n: int, parts: list) -> BeamSolution:
    """One direction's BeamSolution over the grid's ``n`` points from its chunks' ((point
    indices, BeamSolution) each); ``modal_amplitude`` NaN beyond a chunk's own modes, as
    solve_beam pads it."""
    values, ends = {}, [None] * n
    for ids, sol in parts:
        flat = np.ravel(ids)
        for name, v in sol.values.items():
            v = np.asarray(v)
            if name not in values:
                values[name] = np.full((n,) + v.shape[1:], np.nan)
            elif v.ndim > 1 and v.shape[1] > values[name].shape[1]:
                wider = np.full((n, v.shape[1]), np.nan)
                wider[:, :values[name].shape[1]] = values[name]
                values[name] = wider
            if v.ndim == 1:
                values[name][flat] = v
            else:
                values[name][flat, :v.shape[1]] = v
        for i, end in zip(flat, sol.ends if sol.ends is not None else ()):
            ends[i] = end
    return BeamSolution(values, ends, None)


__all__ = ["run_beam_sweep", "solve_on_dask"]
