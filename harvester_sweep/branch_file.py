"""Continuation files: TOML (or a dict of the same shape) read and checked for
:func:`harvester_sweep.continuation.continue_branch`.

A continuation file::

    preset = "paper"
    [parameters]              # fixed values, SI units, any name of PARAMETERS
    gap = 1e-6
    [continuation]
    parameter = "frequency"   # any numeric parameter
    start = 150.0             # [Hz]: the branch starts from the orbit reached from rest here
    stop = 300.0              # [Hz]
    step = 0.01               # initial arclength step, relative to |stop - start|
    min_step = 1e-7           # ... the smallest before the branch is given up
    max_step = 0.05           # ... the largest
    max_points = 2000         # budget of points, on all branches
    period_doubling = "mark"  # or "switch": also follow the doubled branch

An omitted option takes its value from ``continuation.DEFAULTS`` (those above). Everything
is checked before any integration; a bad entry raises ParameterError naming its key.
"""

from __future__ import annotations

from .continuation import DEFAULTS, ContinuationSpec, check_continuation
from .sweep_file import read_toml, table, unknown_keys

_TOP_KEYS = ("preset", "parameters", "continuation")
_KEYS = ("parameter", "start", "stop", "step", "min_step", "max_step", "max_points",
         "period_doubling")


def load_continuation(source) -> ContinuationSpec:
    """The checked problem of a continuation file (a TOML path or a dict of its shape),
    which :func:`harvester_sweep.continuation.continue_branch` takes as it is; an omitted
    key takes its value from ``continuation.DEFAULTS``.

    Raises
    ------
    ParameterError
        For a missing or unreadable file, an unknown key or a bad value, naming the key.
    """
    source = read_toml(source, "continuation", _TOP_KEYS)
    fixed = dict(table(source, "parameters"))
    options = table(source, "continuation")
    unknown_keys(options, _KEYS, "continuation.")
    given = {**DEFAULTS, "start": None, "stop": None, **options}
    if "preset" in source:
        given["preset"] = source["preset"]
    return check_continuation(**given, fixed=fixed, prefix="continuation.")


__all__ = ["load_continuation"]
