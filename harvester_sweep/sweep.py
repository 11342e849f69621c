"""The sweep driver: a grid of parameter points run to steady state, into one xarray Dataset.

Work is split into lines and chunks (:mod:`harvester_sweep.chunks`): a chunk is a run of
whole lines, which go through one call of the engine; numba's threads share them, while a
Python thread sets up the next chunk (:func:`_run_here`). With an
output file, each finished chunk is saved in ``OUT.nc.partial/`` at once
(:mod:`harvester_sweep.chunk_store`), sealed with its checksum; a resumed run computes only
the chunks missing or damaged. The netCDF file is written aside and renamed when complete.
"""

from __future__ import annotations

import sys
from concurrent.futures import ThreadPoolExecutor

from tqdm import tqdm

from .chunk_store import ChunkStore, MemoryStore, load_computed, write_result
from .chunks import chunk_points, compute_chunk, prepare_chunk
from .parameters import ParameterError
from .run_estimate import announce, sweep_estimate
from .sweep_file import load_sweep


def run_sweep(sweep, output=None, *, resume: bool = False, progress: bool = True,
              workers: int | None = None, scheduler: str | None = None, yes: bool = False):
    """Run a sweep and return its dataset (also written to ``output`` when given).

    Parameters
    ----------
    sweep : str, pathlib.Path, dict or SweepSpec
        A TOML sweep file or a dict of the same shape (see :mod:`harvester_sweep.sweep_file`);
        a sweep of the beam (``model = "beam"``) is run by beam_cluster.run_beam_file.
    output : str or pathlib.Path, optional
        netCDF file to write. Finished chunks are kept in ``<output>.partial/`` until the
        file is complete.
    resume : bool
        Finish the partial result of an interrupted run of the same sweep. Without it, an
        existing partial result is refused rather than overwritten.
    progress : bool
        Print the sweep's size and estimated run time on stderr before it starts (the size
        alone for a grid below run_estimate.SAMPLED_GRID points), and show a progress bar
        there (only when stderr is a terminal).
    workers : int, optional
        Run the chunks on a dask LocalCluster of this many worker processes.
    scheduler : str, optional
        Run the chunks on the running dask.distributed scheduler at this address.
    yes : bool
        Start a sweep estimated to take longer than run_estimate.LONG_RUN_SECONDS (1 h);
        without it such a sweep is refused before any work (the command line's ``--yes``).

    Returns
    -------
    xarray.Dataset
        One dimension per grid axis (coordinates in the parameter's SI unit), ``direction``
        under continuation, ``sample`` for stroboscopic samples; see
        :func:`harvester_sweep.datasets.sweep_dataset`.

    Raises
    ------
    ParameterError
        Before any integration, for a bad sweep, a partial result of another sweep, an
        output another run is writing, or a long run without ``yes``.
    StoreError
        (a ParameterError) When the output or a chunk cannot be written (no permission, a
        full disk); the finished chunks are kept for ``resume``.
    cluster.ClusterError
        (a ParameterError) When dask cannot finish the chunks (workers that keep dying,
        none left); the finished chunks are kept for ``resume``.
    """
    spec = load_sweep(sweep, model=None)
    if spec.model == "beam":
        from .beam_cluster import run_beam_file

        return run_beam_file(spec, output, resume=resume, workers=workers,
                             scheduler=scheduler, announce=progress, yes=yes)
    if output is not None and not str(output).lower().endswith(".nc"):
        raise ParameterError(f"output = {str(output)!r}: the file name must end in .nc (the "
                             "file is netCDF)")
    from .cluster import check_cluster, sweep_threads

    workers = check_cluster(workers, scheduler)
    store = ChunkStore(output, spec, resume) if output is not None else MemoryStore()
    with store:  # (holds the output's lock until the file is written)
        if store.complete:
            return store.finished_result(progress)
        finished = [chunk for chunk in store.present() if store.has(chunk)]
        remaining = spec.n_points - sum(chunk_points(spec, chunk) for chunk in finished)
        announce(sweep_estimate(spec, remaining, sweep_threads(workers, scheduler)), yes,
                 progress, "make the grid coarser")
        finished = set(finished)
        todo = [chunk for chunk in range(spec.n_chunks) if chunk not in finished]
        done = spec.n_points - remaining
        with tqdm(total=spec.n_points, initial=done, unit="pt", desc="sweep", smoothing=0.1,
                  disable=not progress or not sys.stderr.isatty()) as bar:

            def compute(chunks):
                if workers is None and scheduler is None:
                    _run_here(spec, chunks, store, bar)
                else:
                    from .cluster import run_on_dask

                    run_on_dask(spec, chunks, store, bar, workers, scheduler)

            compute(todo)
            results = [load_computed(store, chunk, compute) for chunk in range(spec.n_chunks)]
        # (imported here: the command line starts faster without xarray)
        from .datasets import sweep_dataset

        ds = sweep_dataset(spec, results)
        if output is not None:
            write_result(store, ds, output)
    return ds


#: The GIL's switch interval while a sweep sets up its next chunk in a Python thread [s]
#: (Python's default is 5 ms): the most the solve's Python (its set-up and results, a
#: group's end, the progress told every 0.2 s) waits for the set-up to let go of the GIL.
GIL_HANDOFF = 1e-4


def _run_here(spec, chunks, store, bar) -> None:
    """Run ``chunks`` in this process one after another, each saved as it finishes, while
    a Python thread sets up the next one (chunks.prepare_chunk: its points resolved and
    packed, serial Python that would otherwise leave a core idle between engine calls;
    the orbit solver's rounds release the GIL)."""
    interval = sys.getswitchinterval()
    sys.setswitchinterval(GIL_HANDOFF)
    try:
        with ThreadPoolExecutor(max_workers=1, thread_name_prefix="chunk-set-up") as pool:
            prepared = prepare_chunk(spec, chunks[0]) if chunks else None
            for k, chunk in enumerate(chunks):
                ahead = (pool.submit(prepare_chunk, spec, chunks[k + 1])
                         if k + 1 < len(chunks) else None)
                # (what this raises leaves through the pool, which first waits for the
                # set-up under way: under a second)
                store.save(chunk, compute_chunk(spec, chunk, on_points=bar.update,
                                                prepared=prepared))
                if ahead is not None:
                    prepared = ahead.result()
    finally:
        sys.setswitchinterval(interval)
