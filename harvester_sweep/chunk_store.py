"""Where a sweep keeps its finished chunks: in memory, or in ``OUT.nc.partial/`` beside the
output file, so that a killed run loses no finished work and ``--resume`` computes only
the chunks still missing.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np

from .parameters import ParameterError


class MemoryStore:
    """Chunk results kept in memory (no output file)."""

    def __init__(self):
        self.chunks = {}

    def has(self, chunk):
        return chunk in self.chunks

    def save(self, chunk, result):
        self.chunks[chunk] = result

    def load(self, chunk):
        return self.chunks[chunk]


class ChunkStore:
    """Chunk results saved as ``<output>.partial/chunk_NNNNNN.npz`` beside a manifest.

    The manifest holds the SHA-256 of the sweep; a partial result is resumed only by the
    very same sweep, since its chunks would not fit another grid or chunking.
    """

    def __init__(self, output, spec, resume: bool):
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
