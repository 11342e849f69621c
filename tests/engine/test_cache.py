"""numba's on-disk cache shared by processes that compile at once (harvester_sweep.jit).

numba saves a function's new signature by reading the cache's index, taking the first
data file name it does not use, then writing the index and the file, with no lock: two
processes that compile different signatures of one function at once may both take the
same name, and one signature's entry is lost or names the other's machine code. The
package's ``njit`` locks the cache; here two processes are made to save at the same
moment, and a third must load each signature's own machine code.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parents[2]  # subprocesses import this checkout

MODULE = """
from harvester_sweep.jit import njit


@njit(cache=True)
def twice_plus_one(x):
    return 2 * x + 1
"""

# Both processes read the index before either writes it: each waits at its save until the
# other has arrived at its own (both past the cache lookup of their first call, which the
# lock also guards), then, once it has read the index, until the other has read it too;
# under a lock the other cannot read it, and this save goes on after BLOCKED s.
SAVE = """
import os, sys, time
from numba.core import caching

flags, me, other = sys.argv[1:4]
BLOCKED = 2.0
_save_overload = caching.Cache.save_overload
_save_index = caching.IndexDataCacheFile._save_index


def wait_for(name, seconds):
    deadline = time.monotonic() + seconds
    while not os.path.exists(os.path.join(flags, name)) and time.monotonic() < deadline:
        time.sleep(0.005)


def save_overload(self, sig, data):
    if self._py_func.__module__ == "racing":
        open(os.path.join(flags, "arrived " + me), "w").close()
        wait_for("arrived " + other, 60.0)
    _save_overload(self, sig, data)


def save_index(self, overloads):
    if self._index_name.startswith("racing."):  # (not the package's, flushed at import)
        open(os.path.join(flags, "read " + me), "w").close()
        wait_for("read " + other, BLOCKED)
    _save_index(self, overloads)


caching.Cache.save_overload = save_overload
caching.IndexDataCacheFile._save_index = save_index
import racing

racing.twice_plus_one(eval(me))
"""

LOAD = """
import racing

f = racing.twice_plus_one
print(repr(f(3)), repr(f(3.5j)), len(f.stats.cache_misses), len(f.stats.cache_hits))
"""


def _env(tmp_path):
    path = os.pathsep.join([str(tmp_path), str(ROOT), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}


def test_two_processes_compiling_at_once_each_leave_their_own_machine_code(tmp_path):
    (tmp_path / "racing.py").write_text(MODULE)
    flags = tmp_path / "flags"
    flags.mkdir()
    env = _env(tmp_path)
    racers = [subprocess.Popen([sys.executable, "-c", SAVE, str(flags), me, other], env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
              for me, other in (("3", "3.5j"), ("3.5j", "3"))]
    for racer in racers:
        out, err = racer.communicate(timeout=300)
        assert racer.returncode == 0, err
    assert len(os.listdir(flags)) == 4  # both saved
    done = subprocess.run([sys.executable, "-c", LOAD], env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    # each signature loaded from the cache (nothing compiled again), and its own code run
    assert done.stdout.split() == ["7", "(1+7j)", "0", "2"], done.stdout
