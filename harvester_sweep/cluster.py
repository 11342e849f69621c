"""Chunks of a sweep run on a Dask cluster: a local one of N worker processes, or a running
dask.distributed scheduler. Each chunk runs on a worker and comes back to this process to
be saved, so that resuming works the same as for a local run.
"""

from __future__ import annotations

import os

from .chunks import chunk_points, compute_chunk
from .parameters import ParameterError


def run_on_dask(spec, todo, store, bar, workers, scheduler) -> None:
    """Run the chunks ``todo`` on dask; results come back to this process to be saved."""
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise ParameterError("workers and scheduler need dask.distributed: "
                             "pip install 'harvester_sweep[cluster]'") from None
    cluster, threads = None, None
    if scheduler is None:
        # ":0": any free port, so that a dashboard already running elsewhere is no conflict.
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=":0")
        threads = threads_per_worker(workers)
    try:
        client = Client(cluster if cluster is not None else scheduler)
    except OSError as error:
        raise ParameterError(f"scheduler {scheduler!r}: cannot connect ({error})") from None
    try:
        futures = {client.submit(compute_chunk, spec, chunk, threads, pure=False): chunk
                   for chunk in todo}
        for future in as_completed(futures):
            chunk = futures[future]
            store.save(chunk, future.result())
            future.release()
            bar.update(chunk_points(spec, chunk))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def threads_per_worker(workers: int) -> int:
    """numba threads each of a LocalCluster's ``workers`` processes takes: they share the
    cores rather than oversubscribe them."""
    return max(1, (os.cpu_count() or 1) // workers)
