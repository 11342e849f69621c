"""Where a sweep keeps its finished chunks: in memory, or in ``OUT.nc.partial/`` beside the
output file, so that a killed run loses no finished work and ``--resume`` computes only
the chunks still missing.

On disk every chunk file has a seal beside it (``chunk_NNNNNN.json``: the SHA-256 of the
chunk file and of the sweep), written after the chunk: a resumed run uses only chunks whose
seal matches, and computes the others again (a file cut short by a full disk or a bad copy).
A lock file beside the output (``.OUT.nc.lock``) keeps a second run off the same output; the
operating system releases it when its run ends, however it ends.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import shutil
import sys
import warnings
from pathlib import Path

import numpy as np
from filelock import FileLock, Timeout

from .parameters import ParameterError


class StoreError(ParameterError):
    """The output or its partial result cannot be written (a folder without write
    permission, a full disk); the finished chunks are kept."""


class DamagedChunkWarning(UserWarning):
    """A kept chunk failed its check and is computed again."""


def lock_output(output) -> FileLock:
    """The lock of ``output`` (``.OUT.nc.lock`` beside it), acquired: one run at a time per
    output, whatever the command. Taking it also proves the folder writable before any
    work. Release it when the output is written (the OS does if the process dies).

    Raises
    ------
    ParameterError
        When another run holds it.
    StoreError
        When the folder cannot be written.
    """
    output = Path(output)
    lock = FileLock(output.with_name(f".{output.name}.lock"), timeout=0)
    try:
        lock.acquire()
    except Timeout:
        if not Path(lock.lock_file).exists():  # (filelock times out where it cannot create it)
            raise StoreError(f"{output}: cannot write in the folder {output.parent} (no lock "
                             "file can be made there): give an --output where you can "
                             "write") from None
        raise ParameterError(
            f"{output}: another run is writing this output now (it holds "
            f"{lock.lock_file}): wait for it to end, or give another --output") from None
    except OSError as error:
        raise StoreError(f"{output}: cannot write in the folder {output.parent} "
                         f"({error.strerror}): give an --output where you can write") from None
    return lock


class MemoryStore:
    """Chunk results kept in memory (no output file)."""

    def __init__(self):
        self.chunks = {}
        self.complete = False  # (nothing finished before the run: see ChunkStore)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def present(self):
        return sorted(self.chunks)

    def has(self, chunk):
        return chunk in self.chunks

    def save(self, chunk, result):
        self.chunks[chunk] = result

    def load(self, chunk):
        return self.chunks[chunk]

    def kept_text(self) -> str:
        return "nothing is kept without an output file"


class ChunkStore:
    """Chunk results saved as ``<output>.partial/chunk_NNNNNN.npz``, each sealed, beside a
    manifest.

    The manifest and every seal hold the SHA-256 of the sweep; a partial result is resumed
    only by the very same sweep, since its chunks would not fit another grid or chunking.
    Use it as a context manager: it holds the output's lock until the block ends.
    """

    def __init__(self, output, spec, resume: bool):
        output = Path(output)
        if not output.parent.is_dir():
            raise ParameterError(f"{output}: the folder {output.parent} does not exist")
        if output.is_dir():
            raise ParameterError(f"{output} is a folder: give --output a file name")
        self.dir = output.with_name(output.name + ".partial")
        self.output = output
        self.spec = spec
        self.digest = spec.digest()
        #: the output already holds this sweep's finished result (a resume of a run that
        #: ended): the driver returns it rather than run the sweep again
        self.complete = False
        self._lock = lock_output(output)
        try:
            self._check_partial(resume)
        except BaseException:
            self._lock.release()
            raise

    def _check_partial(self, resume: bool) -> None:
        if not self.dir.exists():
            if resume and self.output.exists():
                self._check_finished()
            return
        if not (self.dir / "manifest.json").is_file():  # (an interrupted run writes one first)
            raise ParameterError(
                f"{self.dir} is in the way: it holds no partial result of a run (no "
                "manifest.json), so there is nothing to resume; delete it to start over")
        if not resume:
            raise ParameterError(
                f"{self.dir} holds the partial result of an interrupted run: resume it "
                "(--resume) or delete it to start over")
        try:
            digest = json.loads((self.dir / "manifest.json").read_text())["sweep_sha256"]
        except (OSError, ValueError, KeyError, TypeError):
            raise ParameterError(
                f"{self.dir}/manifest.json cannot be read (damaged, or not made by "
                "harvester-sweep): the partial result cannot be checked; delete the folder "
                "to start over") from None
        if digest != self.digest:
            raise ParameterError(
                f"{self.dir} holds a partial result of another sweep (its grid, "
                "parameters, options, package version, engine or solver differ): it cannot be "
                "resumed with this one; delete it to start over")

    def _check_finished(self) -> None:
        """A resume with no partial result, of an output that exists: this sweep's
        finished file is complete; any other file is refused, not run over (a resume run
        once too often computed the whole sweep again, or replaced another sweep's file)."""
        try:
            import netCDF4

            with netCDF4.Dataset(self.output) as nc:
                digest = getattr(nc, "sweep_sha256", None)
        except OSError:
            digest = None
        if digest == self.digest:
            self.complete = True
            return
        whose = ("another sweep's finished result (its grid, parameters, options, package "
                 "version, engine or solver differ)" if digest is not None
                 else "no finished result of a sweep")
        raise ParameterError(
            f"{self.output} holds {whose} and there is no partial result "
            f"{self.dir.name}/ to resume: run without --resume to replace it")

    def finished_result(self, say: bool):
        """The finished result the output holds (``complete``), as an xarray Dataset; said
        on stderr when ``say``."""
        import xarray as xr

        if say:
            print(f"harvester-sweep: {self.output} already holds this sweep's finished "
                  "result: nothing to resume", file=sys.stderr, flush=True)
        with xr.open_dataset(self.output) as ds:
            return ds.load()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._lock.release()
        return False

    def _path(self, chunk: int) -> Path:
        return self.dir / f"chunk_{chunk:06d}.npz"

    def _seal(self, chunk: int) -> Path:
        return self.dir / f"chunk_{chunk:06d}.json"

    def present(self) -> list:
        """The chunks with a file or a seal on disk, sound or not, in order."""
        if not self.dir.is_dir():
            return []
        return sorted({int(path.stem[len("chunk_"):]) for path in self.dir.glob("chunk_*.*")
                       if path.stem[len("chunk_"):].isdigit()})

    def has(self, chunk) -> bool:
        """True when chunk ``chunk`` is on disk and passes its check."""
        return self._verified(chunk) is not None

    def save(self, chunk, result) -> None:
        """Write chunk ``chunk``, then its seal.

        Raises
        ------
        StoreError
            When the disk refuses (full, no permission); the chunks already sealed are kept.
        """
        path = self.dir
        try:
            if not self.dir.exists():  # made with the first chunk: a run that fails earlier
                self.dir.mkdir()       # leaves none
                manifest = {"sweep_sha256": self.digest, "n_chunks": self.spec.n_chunks,
                            "sweep": json.loads(self.spec.canonical())}
                path = self.dir / "manifest.json"
                _write_atomic(path, json.dumps(manifest, indent=1).encode())
            buffer = io.BytesIO()
            np.savez(buffer, **result)
            data = buffer.getvalue()
            path = self._path(chunk)
            _write_atomic(path, data)
            seal = {"sweep_sha256": self.digest, "chunk": chunk, "bytes": len(data),
                    "sha256": hashlib.sha256(data).hexdigest()}
            path = self._seal(chunk)
            _write_atomic(path, json.dumps(seal).encode())
        except OSError as error:
            raise self.unwritten(path, error.strerror) from None

    def unwritten(self, path, why: str) -> StoreError:
        """The error to raise when ``path`` cannot be written (``why``): it says what is
        kept for --resume, and removes a partial result that holds no finished chunk."""
        kept = len(list(self.dir.glob("chunk_*.json"))) if self.dir.is_dir() else 0
        if not kept:  # (nothing to resume: an empty partial result would be in the way)
            self.remove()
            return StoreError(f"cannot write {path}: {why}; no chunk was finished")
        return StoreError(f"cannot write {path}: {why}; the {kept} finished chunks are kept in "
                          f"{self.dir}: make room (or fix the folder) and run the same "
                          "command with --resume")

    def kept_text(self) -> str:
        """What a run that stops now leaves for --resume, in words; a partial result that
        holds no finished chunk is removed (it would only be in the way)."""
        kept = len(list(self.dir.glob("chunk_*.json"))) if self.dir.is_dir() else 0
        if not kept:
            self.remove()
            return "no chunk was finished"
        return (f"the {kept} finished chunks are kept in {self.dir}: run the same command "
                "with --resume")

    def load(self, chunk) -> dict | None:
        """Chunk ``chunk``'s arrays, or None when it is missing or fails its check."""
        data = self._verified(chunk)
        if data is None:
            return None
        with np.load(io.BytesIO(data)) as arrays:
            return {name: arrays[name] for name in arrays.files}

    def _verified(self, chunk: int) -> bytes | None:
        """The bytes of chunk ``chunk`` if its seal vouches for them; a damaged chunk is
        deleted (with a DamagedChunkWarning) so that it is computed again."""
        path, seal = self._path(chunk), self._seal(chunk)
        if not path.exists() and not seal.exists():
            return None
        try:
            return _sealed_bytes(path, seal, self.digest, chunk)
        except _Damage as damage:
            warnings.warn(f"{path} is damaged: {damage}; computing chunk {chunk} again",
                          DamagedChunkWarning, stacklevel=3)
        for stale in (path, seal):
            stale.unlink(missing_ok=True)
        return None

    def remove(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)


def write_result(store, ds, output) -> None:
    """Write a finished sweep's dataset ``ds`` to ``output``, then remove the partial
    result of ``store``; a file that cannot be written keeps it for --resume
    (StoreError)."""
    from .datasets import write_netcdf

    # (the sweep it holds, that a resume of it knows it by: ChunkStore._check_finished; a
    # tip-mass sweep's dataset holds it already, a beam sweep's is given it here)
    ds.attrs.setdefault("sweep_sha256", store.digest)
    try:
        write_netcdf(ds, output)
    except OSError as error:
        raise store.unwritten(output, write_failure(output, error, ds.nbytes)) from None
    store.remove()


def load_computed(store, chunk: int, compute) -> dict:
    """A finished chunk's arrays from ``store``; one damaged since the run began is
    computed again (``compute([chunk])`` saves it), once."""
    result = store.load(chunk)
    if result is None:
        compute([chunk])
        result = store.load(chunk)
        if result is None:
            raise StoreError(f"chunk {chunk} fails its check right after it was written: "
                             f"the disk under {store.dir} does not keep what is written to it")
    return result


def write_failure(path, error: OSError, size: int | None = None) -> str:
    """Why ``path`` could not be written, in words: the system's reason, or, where the
    library gives none (netCDF4 reports every refusal of HDF5, a full disk included, as
    "NetCDF: HDF error"), its text with the free space on the disk against the ``size``
    [bytes] of the data. A reason given beside a disk too full for the data says so too:
    HDF5 on a full disk has also reported "Permission denied"."""
    reason = error.strerror
    text = reason or str(error) or type(error).__name__
    try:
        free = shutil.disk_usage(Path(path).parent).free
    except OSError:
        return text
    if reason:
        if size is None or free >= size:
            return reason
        return f"{reason} (the disk is full: {_bytes(free)} free for about {_bytes(size)} of data)"
    if size is None:
        return f"{text} (no cause given; {_bytes(free)} free on the disk)"
    full = "the disk is full: " if free < size else ""
    return f"{text} (no cause given; {full}{_bytes(free)} free on the disk for about " \
           f"{_bytes(size)} of data)"


def _bytes(count: int) -> str:
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if count >= size:
            return f"{count / size:.3g} {unit}"
    return f"{count} B"


def _write_atomic(path: Path, data: bytes) -> None:
    """Write a file under a temporary name, then rename it: a killed run leaves no half file
    under the real name (and a failed write leaves no temporary one)."""
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with tmp.open("wb") as handle:
            handle.write(data)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


class _Damage(Exception):
    """Why a chunk file fails its check."""


def _sealed_bytes(path: Path, seal: Path, digest: str, chunk: int) -> bytes:
    """The bytes of chunk file ``path`` when its ``seal`` vouches for them and names the
    sweep of SHA-256 ``digest`` and the chunk ``chunk`` (a chunk and its seal copied over
    another's place check out by their checksum alone); else raise _Damage saying what is
    wrong."""
    if not seal.exists():
        raise _Damage("it has no seal (the run stopped before sealing it)")
    try:
        expected = json.loads(seal.read_text())
        written, checksum, sweep = expected["bytes"], expected["sha256"], expected["sweep_sha256"]
        sealed = expected["chunk"]
    except (OSError, ValueError, KeyError, TypeError):
        raise _Damage(f"its seal {seal.name} cannot be read") from None
    if sweep != digest:
        raise _Damage("its seal belongs to another sweep")
    if sealed != chunk:
        raise _Damage(f"its seal is chunk {sealed!r}'s, not chunk {chunk}'s (copied from "
                      "another chunk's place)")
    try:
        data = path.read_bytes()
    except OSError as error:
        raise _Damage(f"it cannot be read ({error.strerror})") from None
    if hashlib.sha256(data).hexdigest() != checksum:
        raise _Damage(f"its {len(data)} bytes do not match the checksum of the {written} "
                      "bytes written")
    return data
