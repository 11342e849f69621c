"""The beam's sweeps in chunks kept as they finish: a sweep file of ``model = "beam"`` (or
a grid given in Python) run in this process or on a Dask cluster (a local one of N worker
processes, or a running dask.distributed scheduler), each finished chunk saved at once in
``OUT.nc.partial/`` (chunk_store) so that an interrupted run, a lost worker or a full
disk loses only the chunks under way and ``resume`` computes the rest.

A chunk is points where no line is swept, whole lines of one direction where they are
(each line continued along frequency from the previous point's orbit stays in one chunk).
It is solved by chunks.beam_chunk with the functions beam_runs.beam_sweep uses, each
point alone, so the dataset is beam_sweep's bit for bit whatever the chunking, the worker
or the interruptions.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from .beam_parameters import DEFAULT_BEAM_PRESET, moving_stop
from .chunk_store import ChunkStore, MemoryStore, load_computed, write_result
from .chunks import beam_chunk, chunk_points
from .cluster import check_cluster, sweep_threads
from .parameters import ParameterError, whole_number
from .run_estimate import announce as announce_work
from .run_estimate import beam_estimate
from .sweep_file import load_sweep


def beam_source(axes: dict, preset: str | None = DEFAULT_BEAM_PRESET, directions=None,
                chunk_size: int | None = None, **fixed) -> dict:
    """The sweep file (as a dict) of a grid given as beam_runs.beam_sweep takes it:
    ``axes`` (name -> values, SI units), ``directions`` ("up", "down", both or None),
    ``chunk_size`` points per chunk of an unswept grid, lines per chunk of a swept one
    (None: the sweep file's default)."""
    directions = (directions,) if isinstance(directions, str) else directions
    sweep = {"directions": list(directions)} if directions else {}
    if chunk_size is not None:
        length = len(axes.get("frequency", ())) if directions else 1
        sweep["chunk_size"] = whole_number("chunk_size", chunk_size, 1) * max(length, 1)
    return {"model": "beam", "preset": preset or DEFAULT_BEAM_PRESET, "parameters": fixed,
            "grid": {name: np.asarray(values) for name, values in axes.items()},
            "sweep": sweep}


def run_beam_sweep(axes: dict, preset: str | None = DEFAULT_BEAM_PRESET, directions=None,
                   progress=None, *, workers: int | None = None, scheduler: str | None = None,
                   chunk_size: int | None = None, output=None, resume: bool = False,
                   yes: bool = False, **fixed):
    """:func:`beam_runs.beam_sweep` (the same arguments and dataset, the frequency axis
    ascending where lines are swept) run in chunks by :func:`run_beam_file`: kept in
    ``output`` as they finish, resumable, on Dask with ``workers`` or ``scheduler``.

    ``chunk_size``: points per chunk of an unswept grid, lines per chunk of a swept one
    (default: a sweep file's, sweep_file.DEFAULT_BEAM_CHUNK_SIZE points, at least
    DEFAULT_BEAM_CHUNK_LINES lines). ``yes``: start a run estimated beyond an hour (see
    run_beam_file).
    """
    return run_beam_file(beam_source(axes, preset, directions, chunk_size, **fixed), output,
                         resume=resume, progress=progress, workers=workers,
                         scheduler=scheduler, yes=yes)


def run_beam_file(sweep, output=None, *, resume: bool = False, progress=None,
                  workers: int | None = None, scheduler: str | None = None,
                  announce: bool = False, yes: bool = False):
    """Run a beam sweep and return its dataset (also written to ``output`` when given).

    Parameters
    ----------
    sweep : str, pathlib.Path, dict or SweepSpec
        A TOML sweep file with ``model = "beam"`` or a dict of the same shape (see
        :mod:`harvester_sweep.sweep_file`).
    output : str or pathlib.Path, optional
        netCDF file to write. Finished chunks are kept in ``<output>.partial/`` until the
        file is complete.
    resume : bool
        Finish the partial result of an interrupted run of the same sweep (its chunks
        checked by their seals). Without it, an existing partial result is refused rather
        than overwritten.
    progress : callable, optional
        ``progress(done, total, what)``: in this process after each frequency step of a
        chunk's lines (or each chunk of points), ``total`` the steps still to run; on Dask
        once per chunk that comes back, ``total`` the chunks still to run.
    workers : int, optional
        Run the chunks on a new local Dask cluster of this many worker processes.
    scheduler : str, optional
        Run them on the running dask.distributed scheduler at this address (e.g.
        ``"tcp://127.0.0.1:8786"``); its workers must have harvester_sweep installed.
    announce : bool
        Say the sweep's size and estimated run time on stderr before it starts (the size
        alone for a grid below run_estimate.BEAM_SAMPLED_GRID points; the command
        line's, unless ``--quiet``).
    yes : bool
        Start a sweep estimated to take longer than run_estimate.LONG_RUN_SECONDS (1 h);
        without it such a sweep is refused before any work (the command line's ``--yes``).

    Returns
    -------
    xarray.Dataset
        As :func:`beam_runs.beam_sweep`'s: one dimension per grid axis, ``direction``
        where lines are swept, ``mode``; ``model`` = "beam".

    Raises
    ------
    ParameterError
        Before anything is solved: a bad sweep, a partial result of another sweep, an
        output another run is writing, bad workers or scheduler, dask.distributed not
        installed or a scheduler that cannot be reached, a run estimated beyond an hour
        without ``yes``.
    chunk_store.StoreError
        (a ParameterError) When the output or a chunk cannot be written; the finished
        chunks are kept for ``resume``.
    cluster.ClusterError
        (a ParameterError) When dask cannot finish the chunks (workers that keep dying,
        the scheduler lost, none left); every chunk that came back is kept for ``resume``.
    """
    spec = load_sweep(sweep, model="beam")
    if output is not None and not str(output).lower().endswith(".nc"):
        raise ParameterError(f"output = {str(output)!r}: the file name must end in .nc (the "
                             "file is netCDF)")
    workers = check_cluster(workers, scheduler)
    store = ChunkStore(output, spec, resume) if output is not None else MemoryStore()
    with store:  # (holds the output's lock until the file is written)
        if store.complete:
            return store.finished_result(announce)
        finished = {chunk for chunk in store.present() if store.has(chunk)}
        todo = [chunk for chunk in range(spec.n_chunks) if chunk not in finished]
        remaining = sum(chunk_points(spec, chunk) for chunk in todo)
        # What the run is and how long it will take, said before any work; a run beyond
        # an hour is refused unless confirmed
        work = beam_estimate(spec, remaining, sweep_threads(workers, scheduler),
                             _sample_solve)
        announce_work(work, yes, announce, "make the grid coarser")

        def compute(chunks):
            if workers is None and scheduler is None:
                _run_here(spec, chunks, store, progress)
            else:
                from .cluster import run_on_dask

                told = _Told(store, spec, len(chunks), progress)
                run_on_dask(spec, chunks, told, SimpleNamespace(update=lambda n: None),
                            workers, scheduler)

        compute(todo)
        results = [load_computed(store, chunk, compute) for chunk in range(spec.n_chunks)]
        ds = beam_dataset(spec, results)
        if output is not None:
            write_result(store, ds, output)
    return ds


def beam_dataset(spec, results: list):
    """The dataset of a beam sweep ``spec`` from its chunks' results (in chunk order, as
    chunks.beam_chunk returns them): beam_runs.beam_sweep's, bit for bit."""
    from .beam_runs import _dataset

    axes = list(spec.grid)
    dirs = len(spec.directions) if spec.continuation else 1
    along = 1 + (axes.index("frequency") if spec.continuation else len(axes))
    solved = [{} for _ in range(dirs)]
    for name in (name for name in results[0] if name != "run_time"):
        values = _joined([r[name] for r in results])
        # (lines, points of a line, ...) -> the grid's axes in the file's order, a
        # direction first where lines are swept
        grid = values.reshape((dirs,) + tuple(len(spec.grid[a]) for a in spec.line_axes)
                              + (spec.line_length,) + values.shape[2:])
        grid = np.moveaxis(grid, 1 + len(spec.line_axes), along)
        grid = grid.reshape((dirs, spec.n_points // dirs) + values.shape[2:])
        for d in range(dirs):
            solved[d][name] = grid[d]
    first = spec.point_parameters(spec.values_at(0))  # (each axis's first value)
    # the stop moves at some point where it does at the grid's largest rod_modes (and a
    # stop on a spring is one at every point)
    corner = dict(spec.base, **{a: spec.grid[a].max() for a in spec.grid})
    return _dataset(solved, spec.grid, spec.directions, first, moving_stop(corner),
                    spec.preset)


def _joined(parts: list) -> np.ndarray:
    """Chunks' arrays of one output (lines, points of a line, width...) one after another,
    each padded with NaN to the widest (a chunk's points may have fewer modes or a smaller
    state than another's), as solve_beam pads the points of one call."""
    if parts[0].ndim > 2:
        width = max(p.shape[-1] for p in parts)
        parts = [np.concatenate([p, np.full(p.shape[:-1] + (width - p.shape[-1],), np.nan)],
                                axis=-1) for p in parts]
    return np.concatenate(parts)


def _run_here(spec, chunks, store, progress) -> None:
    """Solve ``chunks`` in this process, each saved as it finishes; ``progress`` told after
    each frequency step of a chunk's lines (each chunk of points)."""
    steps = spec.line_length if spec.continuation else 1
    total = steps * len(chunks)
    for k, chunk in enumerate(chunks):
        told = None
        if progress is not None:
            def told(done, _, what, chunk=chunk, base=k * steps):
                progress(base + done, total, f"chunk {chunk + 1}: {what}")
        store.save(chunk, beam_chunk(spec, chunk, told))


class _Told:
    """A chunk store that tells ``progress(done, total, what)`` of each chunk saved:
    cluster.run_on_dask saves each chunk as it comes back."""

    def __init__(self, store, spec, total: int, progress):
        self.store, self.spec, self.total, self.progress = store, spec, total, progress
        self.done = 0

    def save(self, chunk, result) -> None:
        self.store.save(chunk, result)
        self.done += 1
        if self.progress is not None:
            self.progress(self.done, self.total, f"chunk {chunk + 1}: {_what(self.spec, chunk)}")

    def kept_text(self) -> str:
        return self.store.kept_text()


def _sample_solve(points: list, starts) -> tuple:
    """A run-time estimate's sample solved as a sweep solves it: each point's periods_run
    [-] and end state."""
    from .beam_runs import solve_beam

    solved = solve_beam(points, starts)
    return solved.values["periods_run"], solved.ends


def _what(spec, chunk: int) -> str:
    """A chunk in words: its points, or its direction, lines and frequencies."""
    lines = spec.chunk_lines(chunk)
    if not spec.continuation:
        return f"{len(lines)} points"
    direction = spec.directions[lines[0] * len(spec.directions) // spec.n_lines]
    return f"{direction} sweep, {len(lines)} line(s) of {spec.line_length} frequencies"


__all__ = ["beam_dataset", "beam_source", "run_beam_file", "run_beam_sweep"]
