"""Basins of coexisting attractors: which steady state does the harvester land on?

Where orbits coexist (the stop's hysteresis band), the state the device starts from decides
which one it reaches. :func:`basin_fractions` draws initial states uniformly from a box
around rest, solves each to its steady state with the periodic-orbit solver (every start
one point of the lane engine), and groups them by attractor: the same orbit period, and a
final state within ``TOLERANCE`` of one of the orbit's stroboscopic states (a period-p
orbit is reached at any of its p phases). The fraction of starts that reach an attractor
estimates the share of the box its basin holds, with a binomial standard error.
"""

from __future__ import annotations

import math
from dataclasses import fields, replace

import numpy as np
import xarray as xr

from ._engine import MAX_ORBIT_PERIOD, METRIC, STATUS
from .datasets import run_attributes
from .linear import linear_response
from .outputs import OUTPUTS, metric_index
from .packing import check_runnable, pack_points
from .parameters import ParameterError, resolve_parameters
from .results import solve

#: Two final states belong to one attractor when they differ by less than this, relative to
#: the largest stroboscopic amplitude of each component over the starts [-]. Orbits are
#: solved to ~1e-10; distinct attractors differ by far more.
TOLERANCE = 1e-6
#: The components of a start, with their units, and the default half-width of the box in
#: multiples of the larger of the gap and the stop-free displacement amplitude |X| (the
#: velocity and voltage scaled from it by w and the stop-free |V| / |X|).
BOX = {"x": "m", "v": "m/s", "voltage": "V"}
BOX_SIZE = 2.0
MAX_SAMPLES = 1_000_000


def basin_fractions(preset: str | None = "paper", samples: int = 1000, seed: int = 0,
                    box: dict | None = None, **parameters) -> xr.Dataset:
    """The attractors reached from ``samples`` initial states, and each one's share.

    Parameters
    ----------
    preset : str or None
        A preset name; ``None`` is the paper's.
    samples : int
        Initial states drawn, 1 to 1,000,000.
    seed : int
        Seed of numpy's default generator (>= 0): the same seed gives the same starts and
        the same numbers on any thread count.
    box : dict, optional
        Half-widths of the box of starts around rest: ``x`` [m], ``v`` [m/s], ``voltage``
        [V], each > 0 (default: BOX_SIZE times the larger of the gap and the stop-free
        amplitude, and the velocity and voltage of that amplitude).
    **parameters
        Overrides by name in SI units, as :func:`harvester_sweep.run_scene`.

    Returns
    -------
    xarray.Dataset
        Along ``attractor`` (most frequent first): ``basin_fraction`` [1] and its
        ``basin_fraction_error`` [1], and each attractor's metrics and Floquet spectral
        radius (of the first start that reached it); ``fraction_not_settled`` and
        ``fraction_diverged`` [1] for the starts that reached no orbit. The orbits are
        solved at the point's step with no error estimate: the attractors are told apart,
        not polished.

    Raises
    ------
    ParameterError
        For a parameter, ``samples``, ``seed`` or ``box`` out of range, before any work.
    """
    if isinstance(samples, bool) or not isinstance(samples, int) \
            or not 1 <= samples <= MAX_SAMPLES:
        raise ParameterError(f"samples [-] = {samples!r}: must be an integer in 1 .. "
                             f"{MAX_SAMPLES:,}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ParameterError(f"seed [-] = {seed!r}: must be an integer >= 0")
    p = resolve_parameters(preset, **parameters)
    check_runnable(p)
    half = _box(p, box)
    starts = np.random.default_rng(seed).uniform(-1.0, 1.0, (samples, 3)) * half
    one = pack_points([p])
    packed = replace(one, **{f.name: np.repeat(getattr(one, f.name), samples, axis=0)
                             for f in fields(one)})
    packed.states[:, :3] = starts
    results = solve(packed, samples=MAX_ORBIT_PERIOD)
    status = results.metrics[:, METRIC.status]
    members = _group(results)
    first = np.array([m[0] for m in members], dtype=int)
    fraction = np.array([len(m) for m in members], dtype=float) / samples

    def per_attractor(name, values):
        return ("attractor",), values[first].astype(OUTPUTS[name].dtype), OUTPUTS[name].attrs

    ds = xr.Dataset(
        {
            "basin_fraction": (("attractor",), fraction, OUTPUTS["basin_fraction"].attrs),
            "basin_fraction_error": (("attractor",), np.sqrt(fraction * (1 - fraction)
                                                              / samples),
                                     OUTPUTS["basin_fraction_error"].attrs),
            **{name: per_attractor(name, results.metrics[:, metric_index(name)])
               for name in ("orbit_period", "power", "v_peak", "x_max", "x_min",
                            "impacts_per_period", "contact_force_max")},
            "spectral_radius": per_attractor("spectral_radius",
                                             results.run_outputs()["spectral_radius"]),
            "fraction_not_settled": ((), np.mean(status == STATUS.not_settled),
                                     OUTPUTS["fraction_not_settled"].attrs),
            "fraction_diverged": ((), np.mean(status == STATUS.diverged),
                                  OUTPUTS["fraction_diverged"].attrs),
        },
        coords={"attractor": ("attractor", np.arange(1, len(members) + 1),
                              {"long_name": "attractor, most frequent first", "units": "1"})},
        attrs={**run_attributes(p, []), "samples": samples, "seed": seed,
               **{f"box_{name}": float(h) for name, h in zip(BOX, half)},
               "box_units": ", ".join(f"box_{name}: {u}" for name, u in BOX.items())},
    )
    return ds


def _box(p: dict, box: dict | None) -> np.ndarray:
    """Half-widths of the box of starts [m, m/s, V]."""
    X, V = linear_response(**p)
    x = BOX_SIZE * max(abs(complex(X)), abs(p["gap"]))
    w = 2 * math.pi * p["frequency"]
    half = np.array([x, w * x, x * abs(complex(V)) / max(abs(complex(X)), 1e-300)])
    for name, value in (box or {}).items():
        if name not in BOX:
            raise ParameterError(f"box.{name}: unknown; must be among "
                                 + ", ".join(f'"{k}"' for k in BOX))
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not 0 < value < math.inf:
            raise ParameterError(f"box.{name} [{BOX[name]}] = {value!r}: must be a number "
                                 "> 0 and finite")
        half[list(BOX).index(name)] = value
    return half


def _group(results) -> list:
    """The starts of each attractor (index arrays, most frequent first): settled starts
    with the same orbit period whose final state lies within TOLERANCE of one of the
    stroboscopic states of the group's first start."""
    status = results.metrics[:, METRIC.status]
    period = results.metrics[:, METRIC.orbit_period].astype(int)
    left = np.flatnonzero(status == STATUS.settled)
    if not left.size:
        return []
    strobes = results.strobes  # (n, MAX_ORBIT_PERIOD, 3): the orbit repeated
    scale = np.max(np.abs(strobes[left]), axis=(0, 1)) + 1e-300
    groups = []
    while left.size:
        head = left[0]
        orbit = strobes[head, -period[head]:]  # its p states
        distance = np.min(np.max(np.abs(results.finals[left, None, :3] - orbit[None]) / scale,
                                 axis=2), axis=1)
        member = (period[left] == period[head]) & (distance <= TOLERANCE)
        member[0] = True  # (the head always leaves, whatever rounding says)
        groups.append(left[member])
        left = left[~member]
    return sorted(groups, key=len, reverse=True)


__all__ = ["basin_fractions"]
