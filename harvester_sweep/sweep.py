"""The sweep driver: a grid of parameter points run to steady state, into one xarray Dataset.

Work is split into *lines* and *chunks*. Under frequency continuation (``sweep.directions``)
a line is the frequency axis at fixed values of the other axes and one direction: each point
starts from the previous point's final state. Without continuation every point is a line of
one point, run from rest. A chunk is a run of whole lines, which go through one call of
:func:`lanes.run_points`: numba's threads share them, and a lane walks a line from point to
point with no wait for the other lines. Lines never interact, so a point's result does not
depend on the chunking, the thread count or the machine that ran its chunk.

With an output file, each finished chunk is saved in ``OUT.nc.partial/`` at once; a resumed
run computes only the missing chunks. The netCDF file is written aside and renamed when
complete.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from tqdm import tqdm

from . import kernel, lanes
from .parameters import (
    PARAMETERS,
    PRESET_NOTES,
    ParameterError,
    StabilityWarning,
    TooStiffError,
    resolve_parameters,
)
from .stepping import halving_error
from .sweep_file import SweepSpec, load_sweep

_INTEGER_METRICS = ("orbit_period", "periods_run")


def run_sweep(sweep, output=None, *, resume: bool = False, progress: bool = True,
              workers: int | None = None, scheduler: str | None = None):
    """Run a sweep and return its dataset (also written to ``output`` when given).

    Parameters
    ----------
    sweep : str, pathlib.Path, dict or SweepSpec
        A TOML sweep file or a dict of the same shape (see :mod:`harvester_sweep.sweep_file`).
    output : str or pathlib.Path, optional
        netCDF file to write. Finished chunks are kept in ``<output>.partial/`` until the
        file is complete.
    resume : bool
        Finish the partial result of an interrupted run of the same sweep. Without it, an
        existing partial result is refused rather than overwritten.
    progress : bool
        Show a progress bar on stderr (only when stderr is a terminal).
    workers : int, optional
        Run the chunks on a dask LocalCluster of this many worker processes.
    scheduler : str, optional
        Run the chunks on the running dask.distributed scheduler at this address.

    Returns
    -------
    xarray.Dataset
        One dimension per grid axis (coordinates in the parameter's SI unit), ``direction``
        under continuation, ``sample`` for stroboscopic samples; see :func:`sweep_dataset`.

    Raises
    ------
    ParameterError
        Before any integration, for a bad sweep or a partial result of another sweep.
    """
    spec = load_sweep(sweep)
    if workers is not None and scheduler is not None:
        raise ParameterError("give workers or scheduler, not both")
    if workers is not None and workers < 1:
        raise ParameterError(f"workers = {workers!r}: must be an integer >= 1")
    store = _ChunkStore(output, spec, resume) if output is not None else _MemoryStore()
    todo = [chunk for chunk in range(spec.n_chunks) if not store.has(chunk)]
    done = spec.n_points - sum(_chunk_points(spec, chunk) for chunk in todo)
    with tqdm(total=spec.n_points, initial=done, unit="pt", desc="sweep", smoothing=0.1,
              disable=not progress or not sys.stderr.isatty()) as bar:
        if workers is None and scheduler is None:
            for chunk in todo:
                store.save(chunk, compute_chunk(spec, chunk, on_points=bar.update))
        else:
            _run_on_dask(spec, todo, store, bar, workers, scheduler)
    ds = sweep_dataset(spec, [store.load(chunk) for chunk in range(spec.n_chunks)])
    if output is not None:
        from .datasets import write_netcdf

        write_netcdf(ds, output)
        store.remove()
    return ds


def compute_chunk(spec: SweepSpec, chunk: int, threads: int | None = None,
                  on_points=None) -> dict:
    """Run the lines of one chunk; the unit of work of a sweep (also on dask workers).

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
        x [m] and V [V]; ``run_time``: integration time [s].
    """
    import numba

    if threads is not None:
        numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
    first = chunk * spec.lines_per_chunk
    lines = range(first, min(first + spec.lines_per_chunk, spec.n_lines))
    n, length = len(lines), spec.line_length
    # Line-major arrays, each line in the order it runs (a down line from its highest
    # frequency): point (i, k) continues from point (i, k - 1).
    rows = np.empty((n, length, kernel.NP))
    states = np.empty((n, length, 4))
    reverse = np.zeros(n, dtype=bool)
    refused = np.zeros((n, length), dtype=bool)
    continuation = spec.continuation
    # (Python numbers and indices, looked up once: this loop takes ~20 us a point, ~3 % of a
    # 64 x 64 sweep at 1024 steps a period)
    index = [axis.tolist() for axis in np.unravel_index(np.asarray(lines), spec.line_shape)]
    if continuation:
        reverse[:] = [spec.directions[d] == "down" for d in index.pop(0)]
    axes = [(a, spec.grid[a].tolist()) for a in spec.line_axes]
    frequencies = spec.grid["frequency"].tolist() if continuation else []
    for i in range(n):
        values = {a: grid[j[i]] for (a, grid), j in zip(axes, index)}
        for step in range(length):
            if continuation:
                values["frequency"] = frequencies[length - 1 - step if reverse[i] else step]
            try:
                point = spec.point_parameters(values)
            except TooStiffError:
                # Refused before integration: a row of no period, which the kernel skips
                # (the line goes on from the state before it); flagged below.
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", StabilityWarning)
                    point = resolve_parameters(spec.preset, **{**spec.fixed, **values,
                                                               "steps_per_period": 64,
                                                               "max_periods": 1})
                point["max_periods"] = 0
                refused[i, step] = True
            rows[i, step] = kernel.pack_parameters(point)
        # From rest; also where the point before diverged. impact_velocity is constant
        # along a line.
        states[i] = kernel.initial_state(point)
    successors = np.arange(1, n * length + 1).reshape(n, length)
    successors[:, -1] = -1
    position = np.where(reverse[:, None], length - 1 - np.arange(length)[None, :],
                        np.arange(length)[None, :])
    estimated = spec.estimated(np.asarray(lines)[:, None] * length + position) & ~refused

    lanes.warm_up()  # compile or load from the on-disk cache outside the timing
    start = time.perf_counter()
    metrics = np.empty((n, length, kernel.NM))
    strobes = np.empty((n, length, spec.samples, 3))
    # (reshaped views: the kernel writes the final states into ``states``)
    lanes.run_points(rows.reshape(-1, kernel.NP), states.reshape(-1, 4),
                     metrics.reshape(-1, kernel.NM), strobes.reshape(n * length, spec.samples, 3),
                     successors.ravel(), on_points)
    metrics[refused] = np.nan
    metrics[refused, kernel.M_STATUS] = kernel.TOO_STIFF
    metrics[refused, kernel.M_PERIODS] = 0
    metrics[refused, kernel.M_ORBIT] = 0
    strobes[refused] = np.nan
    run_time = time.perf_counter() - start
    errors = _halving_errors(rows, states, metrics, estimated)

    metrics[reverse] = metrics[reverse, ::-1]  # down lines ran from the highest frequency
    strobes[reverse] = strobes[reverse, ::-1]
    errors[reverse] = errors[reverse, ::-1]
    columns = [kernel.METRIC_NAMES.index(name) for name in spec.metrics]
    return {"metrics": np.ascontiguousarray(metrics[..., columns]),
            "strobe": np.ascontiguousarray(strobes[..., [0, 2]]),
            "error_estimate": np.ascontiguousarray(errors),
            "run_time": np.float64(run_time)}


def _halving_errors(rows, finals, metrics, estimated) -> np.ndarray:
    """Step-halving error estimates [-] of the ``estimated`` points, NaN elsewhere: each is
    rerun at twice the steps per period from its own final state (all in one kernel call)."""
    errors = np.full(estimated.shape, np.nan)
    if estimated.any():
        halved = rows[estimated].copy()
        halved[:, kernel.P_N] *= 2
        fine = np.empty((len(halved), kernel.NM))
        lanes.run_points(halved, finals[estimated].copy(), fine,
                         np.empty((len(halved), 0, 3)))
        errors[estimated] = halving_error(metrics[estimated], fine)
    return errors


def sweep_dataset(spec: SweepSpec, chunks: list):
    """Assemble the outputs of every chunk (in order) into the sweep's Dataset.

    Variables: the metrics of ``spec.metrics`` (units of ``datasets.METRICS``), ``status``
    (int8 flags), ``strobe_displacement`` [m] and ``strobe_voltage`` [V] over ``sample``
    when stroboscopic samples were asked. Global attributes: the fixed parameters with their
    units, the sweep itself, the package version, the date and the integration time [s].
    """
    import xarray as xr  # imported here: the command line starts faster without it

    from .datasets import METRICS, STATUS_FLAGS, run_attributes

    metrics = np.concatenate([c["metrics"] for c in chunks])
    strobe = np.concatenate([c["strobe"] for c in chunks])
    shape = spec.line_shape + (spec.line_length,)
    dims = (("direction",) if spec.continuation else ()) + spec.line_axes + ("frequency",)
    order = (("direction",) if spec.continuation else ()) + tuple(spec.grid)
    if not spec.continuation:
        shape, dims = shape[:-1], dims[:-1]  # lines of one point

    def variable(values, units, long_name, extra=(), **attrs):
        da = xr.DataArray(values.reshape(shape + values.shape[2:]), dims=dims + extra,
                          attrs={"units": units, "long_name": long_name, **attrs})
        return da.transpose(*order, *extra)

    data = {}
    for k, name in enumerate(spec.metrics):
        values = metrics[..., k]
        if name == "status":
            data[name] = variable(values.astype(np.int8), "1", "outcome of the run",
                                  **STATUS_FLAGS)
        elif name in _INTEGER_METRICS:
            data[name] = variable(values.astype(np.int32), *METRICS[name])
        else:
            extra = {"comment": "NaN when the orbit has no impact"} \
                if name == "approach_velocity" else {}
            data[name] = variable(values, *METRICS[name], **extra)
    if spec.error_estimate != "none":
        errors = np.concatenate([c["error_estimate"] for c in chunks])
        data["error_estimate"] = variable(
            errors, *METRICS["error_estimate"],
            comment=f"points estimated: {spec.error_estimate}; NaN where not estimated or "
                    "not settled")
    if spec.samples:
        for col, name, units, what in ((0, "strobe_displacement", "m", "tip displacement x"),
                                       (1, "strobe_voltage", "V", "voltage across the load V")):
            data[name] = variable(strobe[..., col], units,
                                  f"{what} at the last forcing period boundaries y(nT)",
                                  extra=("sample",))

    coords = {}
    for name, values in spec.grid.items():
        unit = PARAMETERS[name].unit
        coords[name] = (name, values, {"units": unit, "long_name": PARAMETERS[name].description,
                                       "grid_spacing": spec.spacing[name]})
    if spec.continuation:
        coords["direction"] = ("direction", list(spec.directions), {
            "long_name": "direction of the frequency continuation: each point starts from the "
                         "final state of the previous frequency (up: increasing)"})
    if spec.samples:
        coords["sample"] = ("sample", np.arange(1 - spec.samples, 1), {
            "units": "1", "long_name": "forcing periods before the end of the run (0: last)"})

    fixed = {name: value for name, value in spec.point_parameters({}).items()
             if name not in spec.grid}
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(run_attributes(fixed, PRESET_NOTES.get(spec.preset, [])))
    ds.attrs.update({
        "title": "harvester_sweep sweep of steady states of a piezoelectric harvester with a "
                 "Hertz stop",
        "preset": spec.preset,
        "grid_axes": " ".join(spec.grid),
        "directions": " ".join(spec.directions) or "none (every point from rest)",
        "sweep": spec.canonical(),
        "sweep_sha256": spec.digest(),
        "run_time": float(sum(c["run_time"] for c in chunks)),
        "run_time_units": "s",
        "run_time_comment": "integration time summed over the chunks",
    })
    return ds


def _chunk_points(spec: SweepSpec, chunk: int) -> int:
    first = chunk * spec.lines_per_chunk
    return (min(first + spec.lines_per_chunk, spec.n_lines) - first) * spec.line_length


def _run_on_dask(spec, todo, store, bar, workers, scheduler) -> None:
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
        # Each worker process has its own numba pool: share the cores, don't oversubscribe.
        threads = max(1, (os.cpu_count() or 1) // workers)
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
            bar.update(_chunk_points(spec, chunk))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


class _MemoryStore:
    """Chunk results kept in memory (no output file)."""

    def __init__(self):
        self.chunks = {}

    def has(self, chunk):
        return chunk in self.chunks

    def save(self, chunk, result):
        self.chunks[chunk] = result

    def load(self, chunk):
        return self.chunks[chunk]


class _ChunkStore:
    """Chunk results saved as ``<output>.partial/chunk_NNNNNN.npz`` beside a manifest.

    The manifest holds the SHA-256 of the sweep; a partial result is resumed only by the
    very same sweep, since its chunks would not fit another grid or chunking.
    """

    def __init__(self, output, spec: SweepSpec, resume: bool):
        output = Path(output)
        if not output.parent.is_dir():
            raise ParameterError(f"{output}: the folder {output.parent} does not exist")
        self.dir = output.with_name(output.name + ".partial")
        self.spec = spec
        manifest = self.dir / "manifest.json"
        if self.dir.exists():
            if not resume:
                raise ParameterError(
                    f"{self.dir} holds the partial result of an interrupted run: resume it "
                    "(--resume) or delete it to start over")
            try:
                digest = json.loads(manifest.read_text())["sweep_sha256"]
            except (OSError, ValueError, KeyError):
                digest = None
            if digest != spec.digest():
                raise ParameterError(
                    f"{self.dir} holds a partial result of another sweep (its grid, "
                    "parameters, options, package version or kernel differ): it cannot be "
                    "resumed with this one; delete it to start over")

    def _path(self, chunk: int) -> Path:
        return self.dir / f"chunk_{chunk:06d}.npz"

    def has(self, chunk):
        return self._path(chunk).exists()

    def save(self, chunk, result):
        if not self.dir.exists():  # made with the first chunk: a run that fails earlier leaves none
            self.dir.mkdir()
            manifest = {"sweep_sha256": self.spec.digest(), "n_chunks": self.spec.n_chunks,
                        "sweep": json.loads(self.spec.canonical())}
            _write_atomic(self.dir / "manifest.json",
                          lambda handle: handle.write(json.dumps(manifest, indent=1).encode()))
        _write_atomic(self._path(chunk), lambda handle: np.savez(handle, **result))

    def load(self, chunk):
        with np.load(self._path(chunk)) as data:
            return {name: data[name] for name in data.files}

    def remove(self):
        shutil.rmtree(self.dir, ignore_errors=True)


def _write_atomic(path: Path, write) -> None:
    """Write a file under a temporary name, then rename it: a killed run leaves no half file."""
    tmp = path.with_name(f".{path.name}.tmp")
    with tmp.open("wb") as handle:
        write(handle)
    os.replace(tmp, path)
