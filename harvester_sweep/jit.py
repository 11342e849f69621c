"""How every compiled function is compiled: one set of numba options for the models' and
the engine's (JIT), and plain IEEE arithmetic for the orbit solver's (SOLVER_JIT).

Bit-for-bit reproducible whichever lane, group or thread runs a point: no reassociation
(it would let a vector loop sum in another order than scalar code) and no approximate
functions. FMA contraction is allowed: LLVM fuses a multiply into an add of the same basic
block, so differently shaped code may round differently, but every lane runs the same
vector code and which steps run scalar code is decided by the point's own state
(tests/engine/test_reproducibility.py checks a point in several lanes, groups and thread
counts). No nnan/ninf either: the divergence check relies on isfinite. nsz and arcp let
LLVM vectorize the lane loop, which has no division, so that arcp cannot make a vector
lane differ from scalar code.

Every compiled function of the package is made by :func:`njit`, numba's with its on-disk
cache made safe for processes that compile at once (_LockedCacheFile).
"""

from __future__ import annotations

import contextlib
import os

import numba
from filelock import FileLock
from numba.core.caching import IndexDataCacheFile

FASTMATH = frozenset({"nsz", "arcp", "contract"})
JIT = dict(cache=True, fastmath=set(FASTMATH), error_model="numpy")

#: The orbit solver's compiled decisions (and the small dense algebra they use): plain
#: IEEE arithmetic, no contraction or reassociation, so that an expression rounds as
#: the same expression in numpy does.
SOLVER_JIT = dict(cache=True, error_model="numpy")


#: The longest a process waits for the lock on numba's cache folder [s].
CACHE_LOCK_WAIT = 60.0


class _LockedCacheFile(IndexDataCacheFile):
    """numba's cache of one function (an index of signatures and a data file for each),
    read and written under a lock on its folder.

    numba saves a new signature by reading the index, taking the first data file name the
    index does not use, and writing the index and then the data file, with no lock. Two
    processes that first compile different signatures of one function at once (two test
    workers, two sweeps of different models, Dask workers) can take the same name: the
    index can end up naming one signature's file while the file holds the other's machine
    code, which every later process loads and runs for it (numba issue #10128). Under the
    lock a save is whole before any other process reads or saves, and a load reads an
    index and the file it names from one state. Compiling stays outside the lock.
    """

    @contextlib.contextmanager
    def _locked(self):
        # (another process holds the lock for the milliseconds of a save: a lock not had
        # in CACHE_LOCK_WAIT, or none to be had in a folder not writable, is gone without)
        lock = FileLock(os.path.join(self._cache_path, "harvester-sweep-cache.lock"),
                        timeout=CACHE_LOCK_WAIT)
        try:
            lock.acquire()
        except OSError:  # (filelock's Timeout is one)
            yield
            return
        try:
            yield
        finally:
            lock.release()

    def save(self, key, data):
        with self._locked():
            super().save(key, data)

    def load(self, key):
        with self._locked():
            return super().load(key)

    def flush(self):
        with self._locked():
            super().flush()


def njit(**options):
    """numba.njit with ``options`` (JIT or SOLVER_JIT), its cache locked (_LockedCacheFile)."""
    def compiled(function):
        dispatcher = numba.njit(**options)(function)
        cache = getattr(dispatcher, "_cache", None)
        if isinstance(getattr(cache, "_cache_file", None), IndexDataCacheFile):
            cache._cache_file.__class__ = _LockedCacheFile
        return dispatcher

    return compiled
