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

Everything is checked before any integration; a bad entry raises ParameterError naming its
key.
"""

from __future__ import annotations

from .basins import check_draws
from .parameters import ParameterError, check_names, resolve_parameters
from .sweep_file import axis, read_toml, table, unknown_keys

_TOP_KEYS = ("preset", "parameters", "grid", "basins")
_KEYS = ("samples", "seed", "shock", "box")
DEFAULT_SAMPLES = 200


def load_basins(source) -> dict:
    """The checked problem of a basin file (a TOML path or a dict of its shape): keyword
    arguments of :func:`harvester_sweep.basins.basin_map`.

    Raises
    ------
    ParameterError
        For a missing or unreadable file, an unknown key or a bad value, naming the key.
    """
    source = read_toml(source, "basin", _TOP_KEYS)
    preset = source.get("preset", "paper")
    fixed = dict(table(source, "parameters"))
    check_names(fixed)
    resolve_parameters(preset, **fixed)
    grid = table(source, "grid")
    for name, entry in grid.items():
        axis(name, entry, fixed)
    options = table(source, "basins")
    unknown_keys(options, _KEYS, "basins.")
    kwargs = {"samples": DEFAULT_SAMPLES, "seed": 0, **options}
    try:
        check_draws(kwargs["samples"], kwargs["seed"], kwargs.get("box"), kwargs.get("shock"))
    except ParameterError as error:
        raise ParameterError(f"basins.{error}") from None
    return {"grid": grid, "preset": preset, **kwargs, **fixed}


__all__ = ["load_basins"]
