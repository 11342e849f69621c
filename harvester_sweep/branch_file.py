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

Everything is checked before any integration; a bad entry raises ParameterError naming its
key.
"""

from __future__ import annotations

from .continuation import DEFAULTS, check_continuation
from .sweep_file import read_toml, table, unknown_keys

_TOP_KEYS = ("preset", "parameters", "continuation")
_KEYS = ("parameter", "start", "stop", "step", "min_step", "max_step", "max_points",
         "period_doubling")


def load_continuation(source) -> dict:
    """The checked problem of a continuation file (a TOML path or a dict of its shape):
    keyword arguments of :func:`harvester_sweep.continuation.continue_branch`.

    Raises
    ------
    ParameterError
        For a missing or unreadable file, an unknown key or a bad value, naming the key.
    """
    source = read_toml(source, "continuation", _TOP_KEYS)
    fixed = dict(table(source, "parameters"))
    options = table(source, "continuation")
    unknown_keys(options, _KEYS, "continuation.")
    kwargs = {**DEFAULTS, "period_doubling": "mark", **options}
    kwargs.setdefault("parameter", "frequency")
    check_continuation(source.get("preset", "paper"), kwargs["parameter"], kwargs.get("start"),
                       kwargs.get("stop"), kwargs["step"], kwargs["min_step"],
                       kwargs["max_step"], kwargs["max_points"], kwargs["period_doubling"],
                       fixed, prefix="continuation.")
    return {"preset": source.get("preset", "paper"), **kwargs, **fixed}


__all__ = ["load_continuation"]
