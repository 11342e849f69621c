"""Basin files: TOML (or a dict of the same shape) read and checked for
:func:`harvester_sweep.basins.basin_map`.

A basin file::

    preset = "paper"
    [parameters]              # fixed values, SI units, any name of PARAMETERS
    steps_per_period = 1024
    [grid]                    # as a sweep file's (omit for one point)
    gap = { start = 0.5e-6, stop = 3e-6, num = 11 }          # [m]
    frequency = { start = 200, stop = 270, num = 36 }         # [Hz]
    [basins]
    samples = 200             # starts per grid point
    seed = 0                  # the same seed gives the same numbers
    shock = 0.01              # [m/s]: starts left by a base shock of this size on the orbit
                              # reached from rest; omit for starts drawn from a box
    # box = { x = 3e-6, v = 5e-3, voltage = 2e-5 }   # [m, m/s, V]: the box's half-widths

An omitted option takes its value from ``basins.DEFAULTS``. Everything is checked before
any integration; a bad entry raises ParameterError naming its key.
"""

from __future__ import annotations

from .basins import DEFAULTS, BasinSpec, check_basins
from .parameters import check_names
from .sweep_file import read_toml, table, unknown_keys

_TOP_KEYS = ("preset", "parameters", "grid", "basins")
_KEYS = ("samples", "seed", "shock", "box")


def load_basins(source) -> BasinSpec:
    """The checked problem of a basin file (a TOML path or a dict of its shape), which
    :func:`harvester_sweep.basins.basin_map` takes as it is.

    Raises
    ------
    ParameterError
        For a missing or unreadable file, an unknown key or a bad value, naming the key.
    """
    source = read_toml(source, "basin", _TOP_KEYS)
    fixed = dict(table(source, "parameters"))
    check_names(fixed)  # (before the call: `preset` among them would be a TypeError)
    grid = table(source, "grid")
    options = table(source, "basins")
    unknown_keys(options, _KEYS, "basins.")
    given = {**DEFAULTS, **options}
    if "preset" in source:
        given["preset"] = source["preset"]
    return check_basins(grid, fixed=fixed, prefix="basins.", **given)


__all__ = ["load_basins"]
