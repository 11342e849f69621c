"""Chunks of a sweep run on a Dask cluster: a local one of N worker processes, or a running
dask.distributed scheduler. Each chunk runs on a worker and comes back to this process to
be saved, so that resuming works the same as for a local run.
"""

from __future__ import annotations

import os
import time

from .chunks import chunk_points, compute_chunk
from .parameters import ParameterError, value_text, whole_number

#: Seconds the run waits with no worker on the cluster before it gives up [s]. A local
#: worker that dies is started again by its nanny within seconds; a cluster with none for
#: this long has lost them for good (their nannies killed too), and tasks would wait for
#: ever.
NO_WORKERS_SECONDS = 120.0
#: How often the run looks at the cluster while no chunk finishes [s].
POLL_SECONDS = 1.0


class ClusterError(ParameterError):
    """The dask cluster cannot finish the chunks (its workers keep dying, or none is
    left); the finished chunks are kept for ``resume``."""


def check_cluster(workers, scheduler):
    """Refuse, in one line, ``workers`` and ``scheduler`` together, a worker count that is
    not a whole number >= 1 or an address dask cannot parse; returns the worker count."""
    if workers is not None and scheduler is not None:
        raise ParameterError("give workers or scheduler, not both")
    if workers is not None:
        workers = whole_number("workers", workers, 1)
    if scheduler is not None:
        check_scheduler(scheduler)
    return workers


def check_scheduler(scheduler) -> None:
    """Refuse, before any work, a scheduler address dask cannot parse (one line)."""
    if not isinstance(scheduler, str):
        raise ParameterError(f"scheduler = {value_text(scheduler)}: must be the address of a "
                             "dask scheduler, e.g. tcp://127.0.0.1:8786")
    try:
        from distributed.comm.addressing import parse_address, parse_host_port
    except ImportError:
        return  # (said by run_on_dask, which needs it)
    try:
        protocol, location = parse_address(scheduler, strict=False)
        if protocol in ("tcp", "tls"):
            parse_host_port(location)
    except (ValueError, TypeError) as error:
        raise ParameterError(f"scheduler = {scheduler!r}: not the address of a dask scheduler "
                             f"({error}); e.g. tcp://127.0.0.1:8786") from None


def run_on_dask(spec, todo, store, bar, workers, scheduler) -> None:
    """Run the chunks ``todo`` on dask; results come back to this process to be saved.

    Raises
    ------
    ClusterError
        When a chunk's workers kept dying (dask's ``KilledWorker``), the connection to the
        scheduler was lost, or no worker was left for NO_WORKERS_SECONDS; every chunk that
        finished before is saved first.
    """
    client, cluster = connect(workers, scheduler)
    from dask.distributed import wait
    from distributed import KilledWorker

    threads = threads_per_worker(workers) if cluster is not None else None
    lost = {}  # chunk -> why it did not come back
    try:
        futures = {client.submit(compute_chunk, spec, chunk, threads, pure=False): chunk
                   for chunk in todo}
        pending, alone_since = set(futures), None
        while pending:
            try:
                done, pending = wait(pending, timeout=POLL_SECONDS,
                                     return_when="FIRST_COMPLETED")
            except TimeoutError:  # (none finished within POLL_SECONDS)
                done = set()
            for future in done:
                chunk = futures[future]
                try:
                    result = future.result()
                except KilledWorker:
                    lost[chunk] = "the workers running it kept dying (dask's KilledWorker)"
                    continue
                except (OSError, TimeoutError) as error:  # (CommClosedError among them)
                    lost[chunk] = f"the connection to the scheduler was lost ({error})"
                    continue
                store.save(chunk, result)
                future.release()
                bar.update(chunk_points(spec, chunk))
            if done or not pending:
                alone_since = None
            elif _workers(client) > 0:
                alone_since = None
            elif alone_since is None:
                alone_since = time.monotonic()
            elif time.monotonic() - alone_since > NO_WORKERS_SECONDS:
                lost.update({futures[f]: f"no dask worker was left for "
                             f"{NO_WORKERS_SECONDS:g} s" for f in pending})
                break
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    if lost:
        first = min(lost)
        raise ClusterError(f"{len(lost)} of {len(todo)} chunks did not come back from dask "
                           f"(chunk {first}: {lost[first]}); {store.kept_text()}")


def connect(workers, scheduler) -> tuple:
    """A dask client: on a new local cluster of ``workers`` processes (one thread each)
    where ``scheduler`` is None, else on the scheduler at that address. Returns (client,
    the local cluster or None); the caller closes both.

    Raises
    ------
    ParameterError
        Without dask.distributed, or when the scheduler cannot be reached (one line).
    """
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise ParameterError("workers and scheduler need dask.distributed: "
                             "pip install 'harvester_sweep[cluster]'") from None
    cluster = None
    if scheduler is None:
        # ":0": any free port, so that a dashboard already running elsewhere is no conflict.
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=":0")
    try:
        client = Client(cluster if cluster is not None else scheduler)
    except (OSError, ValueError, TypeError) as error:
        if cluster is not None:
            cluster.close()
        raise ParameterError(f"scheduler {scheduler!r}: cannot connect ({error})") from None
    return client, cluster


def _workers(client) -> int:
    """Workers the scheduler knows now; 0 when it cannot be asked."""
    try:
        return len(client.nthreads())
    except (OSError, TimeoutError):
        return 0


def sweep_threads(workers: int | None, scheduler: str | None) -> int:
    """Threads the sweep will run on: this process's numba threads, a LocalCluster's
    cores, or 1 for a remote scheduler (its size is not known before connecting)."""
    if scheduler is not None:
        return 1
    if workers is not None:
        return workers * threads_per_worker(workers)
    import numba

    return numba.get_num_threads()


def threads_per_worker(workers: int) -> int:
    """numba threads each of a LocalCluster's ``workers`` processes takes: they share the
    cores rather than oversubscribe them."""
    return max(1, (os.cpu_count() or 1) // workers)
