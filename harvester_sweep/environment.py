"""The environment variables the package reads before numba starts: checked first, so that
a bad value is said in one line rather than as numba's traceback at import."""

from __future__ import annotations

import os
import sys
from pathlib import Path

#: The command line's name: where the package is imported by it, a bad variable ends the
#: command with exit status 2, as any bad input does.
COMMAND = "harvester-sweep"


def threads_problem(environ=os.environ) -> str | None:
    """What is wrong with NUMBA_NUM_THREADS (the threads numba runs on [-]), in one line,
    or None. numba takes a whole number >= 1 (as Python's int() reads it) or the
    variable unset; anything else is a ValueError from deep inside its import (an empty
    one a warning with a traceback in it)."""
    text = environ.get("NUMBA_NUM_THREADS")
    if text is None:
        return None
    try:
        ok = int(text) >= 1
    except ValueError:
        ok = False
    if ok:
        return None
    return (f"NUMBA_NUM_THREADS [-] = {text!r}: must be a whole number >= 1 (this machine has "
            f"{os.cpu_count()} CPUs), or unset for all of them")


def check_threads() -> None:
    """Raise ValueError in one line for a bad NUMBA_NUM_THREADS; under the command line,
    say it and exit 2 (the command's main has not started yet: the package's import
    comes first)."""
    problem = threads_problem()
    if problem is None:
        return
    if Path(sys.argv[0]).name.startswith(COMMAND):  # (the script, or Windows' .exe)
        print(f"{COMMAND}: error: {problem}", file=sys.stderr)
        raise SystemExit(2)
    raise ValueError(problem)
