"""Basins of coexisting attractors: which steady state does the harvester land on?

Where orbits coexist (the stop's hysteresis band), the state the device starts from decides
which one it reaches. Starts are drawn in one of two ways:

- **a box** (the default): states drawn uniformly from a box around rest, at t = 0;
- **a base shock** of a given size: the device runs on the orbit it reaches from rest, and
  at a moment drawn uniformly over that orbit the base's velocity jumps by ``shock``
  [m/s], up or down with equal odds. An impulse moves no mass, so the tip keeps its place
  and its velocity relative to the base jumps by ``-mu_1 shock`` or ``+mu_1 shock``, mu_1
  the ``base_forcing_factor`` through which the base's acceleration, an impulse of it too,
  forces the tip (mu_1 = 1, a lumped tip: it keeps its absolute velocity); the voltage is
  unchanged. The start is that state, at that moment's forcing phase (the step boundary of
  the RK4 orbit the moment falls on).

Each start is solved to its steady state by the periodic-orbit solver (every start one
point of the lane engine), and the starts are grouped by attractor: the same orbit period,
and a final state within ``TOLERANCE`` of one of the orbit's p states at the same forcing
phase (a period-p orbit is reached at any of its p phases). The fraction of starts that
reach an attractor estimates the share of its basin among the starts, with a binomial
standard error.

:func:`basin_fractions` does this at one point, :func:`basin_map` at every point of a
grid, with the same draws at every point: the differences between neighbouring points are
then the physics, not the luck of different draws.
"""

from __future__ import annotations

import itertools
import math
import sys
from dataclasses import dataclass, fields, replace

import numpy as np
import xarray as xr
from tqdm import tqdm

from . import period_map
from ._engine import MAX_ORBIT_PERIOD, METRIC, PARAM, SERIES, STATE, STATUS
from .datasets import grid_coordinates, run_attributes
from .linear import linear_response
from .models import tip_mass
from .orbits import scale_floors
from .outputs import OUTPUTS, metric_index
from .packing import check_runnable, pack_points
from .parameters import (
    DEFAULT_PRESET,
    PRESET_NOTES,
    ParameterError,
    check_seed,
    is_number,
    resolve_parameters,
    whole_number,
)
from .results import solve
from .run_estimate import announce, estimate_basins
from .sweep_file import axis, check_grid_size

#: Two final states belong to one attractor when they differ by less than this, relative to
#: the largest stroboscopic amplitude of each component over the starts [-]. Orbits are
#: solved to ~1e-10; distinct attractors differ by far more.
TOLERANCE = 1e-6
#: The components of a start, with their units, and the default half-width of the box in
#: multiples of the larger of the gap and the stop-free displacement amplitude |X| (the
#: velocity and voltage scaled from it by w and the stop-free |V| / |X|).
BOX = {c.name: c.unit for c in tip_mass.STATE}
BOX_SIZE = 2.0
MAX_SAMPLES = 1_000_000
#: Starts handed to one solve: bounds the memory of a map (about 2 kB a start); the
#: numbers do not depend on it, as a point's result never depends on the other points.
CALL_STARTS = 8192
#: What each attractor reports beside its basin fraction (the metrics of the first start
#: that reached it).
ATTRACTOR_OUTPUTS = ("orbit_period", "power", "v_peak", "x_max", "x_min",
                     "impacts_per_period", "contact_force_max", "spectral_radius")
#: Defaults of a map's options, the one place they are written: basin_map's and
#: basin_fractions' keywords and a basin file's omitted keys (basin_file) read them. Starts
#: per grid point [-], the seed [-], and starts from each point's default box (no box, no
#: shock).
DEFAULTS = {"preset": DEFAULT_PRESET, "samples": 200, "seed": 0, "box": None, "shock": None}
#: Starts basin_fractions draws at its one point by default [-]: one point affords more
#: than each point of a map.
POINT_SAMPLES = 1000


@dataclass(frozen=True)
class BasinSpec:
    """A checked basin problem (:func:`check_basins`), which :func:`basin_map` takes as it
    is.

    Attributes
    ----------
    preset : str or None
        Preset the parameters start from (``None``: the paper's).
    fixed : dict
        Fixed parameters by name (SI units), as given, not including the grid axes.
    axes : dict of str -> numpy.ndarray
        Grid axis name -> values (SI units of the parameter), in the order given; empty
        for one point.
    spacing : dict of str -> str
        Grid axis name -> ``"linear"``, ``"log"`` or ``"list"``.
    samples, seed : int
        Starts per grid point, and the seed of the draws [-].
    box : dict or None
        Half-widths of the box of starts: ``x`` [m], ``v`` [m/s], ``voltage`` [V].
    shock : float or None
        Size of the base shock [m/s], instead of a box.
    base : dict
        The validated parameters of ``preset`` with ``fixed`` (SI units).

    A grid point's parameters are resolved when asked (:meth:`point`), not held: a map of
    millions of points held them all (gigabytes) before its size was even said. Each point
    is checked runnable (not too stiff) by :func:`basin_map` before any integration.
    """

    preset: str | None
    fixed: dict
    axes: dict
    spacing: dict
    samples: int
    seed: int
    box: dict | None
    shock: float | None
    base: dict

    @property
    def shape(self) -> tuple:
        """The grid's shape, one length per axis; () for one point."""
        return tuple(len(a) for a in self.axes.values())

    @property
    def n_points(self) -> int:
        return math.prod(self.shape)

    def point(self, i: int) -> dict:
        """The validated parameters (SI units) of grid point ``i``, the last axis fastest."""
        index = np.unravel_index(i, self.shape) if self.axes else ()
        values = {name: a[j].item() for (name, a), j in zip(self.axes.items(), index)}
        return resolve_parameters(self.preset, **self.fixed, **values)


def check_basins(grid, preset, samples, seed, box, shock, fixed: dict,
                 prefix: str = "") -> BasinSpec:
    """The checked basin problem, every value validated once here: ``grid`` as
    :func:`basin_map`'s, the draw options, ``fixed`` the fixed parameters by name (SI
    units). Bad input raises ParameterError naming it (a draw option after ``prefix``),
    with its unit and allowed range; a grid point too stiff raises TooStiffError."""
    try:
        samples, seed, box, shock = check_draws(samples, seed, box, shock)
    except ParameterError as error:
        raise ParameterError(f"{prefix}{error}") from None
    base = resolve_parameters(preset, **fixed)
    if not isinstance(grid, dict):
        raise ParameterError("grid: must be a table of parameter name -> values, e.g. "
                             "{\"frequency\": [240.0, 245.0]}")
    check_grid_size(grid, samples, "starts")  # (before any axis is made)
    axes, spacing = {}, {}
    for name, entry in grid.items():
        axes[name], spacing[name] = axis(name, entry, fixed)
    spec = BasinSpec(preset, dict(fixed), axes, spacing, samples, seed, box, shock, base)
    # The checks that couple parameters fail first at the grid's corners (as a sweep's);
    # every point is checked runnable by basin_map, once its size is said.
    corners = itertools.product(*({0, len(a) - 1} for a in axes.values()))
    for corner in corners:
        check_runnable(spec.point(int(np.ravel_multi_index(corner, spec.shape))
                                  if axes else 0))
    return spec


def basin_fractions(preset: str | None = DEFAULTS["preset"], samples: int = POINT_SAMPLES,
                    seed: int = DEFAULTS["seed"], box: dict | None = DEFAULTS["box"],
                    shock: float | None = DEFAULTS["shock"], *, yes: bool = False,
                    **parameters) -> xr.Dataset:
    """The attractors reached from ``samples`` starts at one point, and each one's share.

    Parameters
    ----------
    preset : str or None
        A preset name; ``None`` is the paper's.
    samples : int
        Starts drawn, 1 to 1,000,000.
    seed : int
        Seed of numpy's default generator (>= 0): the same seed gives the same starts and
        the same numbers on any thread count.
    box : dict, optional
        Half-widths of the box of starts around rest: ``x`` [m], ``v`` [m/s], ``voltage``
        [V], each > 0 (default: BOX_SIZE times the larger of the gap and the stop-free
        amplitude, and the velocity and voltage of that amplitude).
    shock : float, optional
        Instead of a box: the size of a base shock [m/s] (> 0), a jump of the base's
        velocity at a random moment of the orbit reached from rest (module docstring).
    yes : bool
        Start a run estimated beyond run_estimate.LONG_RUN_SECONDS (1 h); without it such
        a run is refused before any work, as a sweep is.
    **parameters
        Overrides by name in SI units, as :func:`harvester_sweep.run_scene`.

    Returns
    -------
    xarray.Dataset
        Along ``attractor`` (most frequent first): ``basin_fraction`` [1] and its
        ``basin_fraction_error`` [1], and each attractor's metrics and Floquet spectral
        radius (of the first start that reached it); ``impact_basin_fraction`` [1] (the
        starts that reach an orbit striking the stop) with its error;
        ``fraction_not_settled`` and ``fraction_diverged`` [1] for the starts that reached
        no orbit. The orbits are solved at the point's step with no error estimate: the
        attractors are told apart, not polished.

    Raises
    ------
    ParameterError
        For a parameter, ``samples``, ``seed``, ``box`` or ``shock`` out of range, or a
        run beyond an hour without ``yes``, before any work.
    """
    return basin_map({}, preset, samples, seed, box, shock, progress=False, yes=yes,
                     **parameters)


def basin_map(grid: dict | BasinSpec, preset: str | None = DEFAULTS["preset"],
              samples: int = DEFAULTS["samples"], seed: int = DEFAULTS["seed"],
              box: dict | None = DEFAULTS["box"], shock: float | None = DEFAULTS["shock"], *,
              progress: bool = True, yes: bool = False, **parameters) -> xr.Dataset:
    """:func:`basin_fractions` at every point of a grid, with the same draws at each.

    Parameters
    ----------
    grid : dict or BasinSpec
        One axis per parameter name: a list of values [SI] or a range table ``{"start",
        "stop", "num", "scale"}``, as a sweep file's ``[grid]``. Or a problem already
        checked (:func:`check_basins`, ``basin_file.load_basins``), taken as it is: then
        no other argument but ``progress`` is given.
    preset, samples, seed, box, shock, **parameters
        As :func:`basin_fractions`; ``box`` and ``shock`` apply at every point (the default
        box is each point's own).
    progress : bool
        The map's size and estimated run time on stderr before it starts, and a progress
        bar of the starts solved there when it is a terminal.
    yes : bool
        Start a map estimated beyond run_estimate.LONG_RUN_SECONDS (1 h) (the command
        line's ``--yes``); without it such a map is refused before any work.

    Returns
    -------
    xarray.Dataset
        Dimensions: the grid's axes (coordinates in SI units), then ``attractor`` (at each
        point most frequent first, padded with NaN, and orbit_period 0, to the largest
        count). Variables as :func:`basin_fractions`; ``impact_basin_fraction`` is the map
        designers look at.

    Raises
    ------
    ParameterError
        As :func:`basin_fractions`, and for a bad grid, a grid of more than
        sweep_file.MAX_GRID_POINTS starts, a grid point too stiff or a map beyond an hour
        without ``yes``, before any work.
    """
    options = dict(preset=preset, samples=samples, seed=seed, box=box, shock=shock)
    if not isinstance(grid, BasinSpec):
        spec = check_basins(grid, fixed=parameters, **options)
    elif parameters or options != DEFAULTS:
        # (a checked problem holds every option: another beside it would be ignored)
        raise ParameterError("a BasinSpec is the whole problem: give no other argument "
                             "beside it but progress")
    else:
        spec = grid
    preset, samples, seed, box, shock = (spec.preset, spec.samples, spec.seed, spec.box,
                                         spec.shock)
    base, axes, spacing = spec.base, spec.axes, spec.spacing
    import numba

    announce(estimate_basins(spec, numba.get_num_threads(), CALL_STARTS), yes, progress,
             "make the grid coarser or the samples fewer")
    for i in range(spec.n_points):  # (bad input fails before any integration)
        check_runnable(spec.point(i))
    found = _solve(spec, progress)
    halves = [_box(spec.point(0), box)] if shock is None and not axes else None

    shape = tuple(len(a) for a in axes.values())
    dims = tuple(axes) + ("attractor",)
    width = max(len(f["basin_fraction"]) for f in found)

    def per_point(name):
        values = np.array([f[name] for f in found]).reshape(shape)
        return tuple(axes), values, OUTPUTS[name].attrs

    def per_attractor(name, pad):
        output = OUTPUTS[name]
        values = np.full((len(found), width), pad, dtype=output.dtype)
        for i, f in enumerate(found):
            values[i, :len(f[name])] = f[name]
        return dims, values.reshape(shape + (width,)), output.attrs

    data = {name: per_attractor(name, 0 if name == "orbit_period" else np.nan)
            for name in ("basin_fraction", "basin_fraction_error") + ATTRACTOR_OUTPUTS}
    data.update({name: per_point(name) for name in (
        "impact_basin_fraction", "impact_basin_fraction_error", "fraction_not_settled",
        "fraction_diverged")})
    coords = {"attractor": ("attractor", np.arange(1, width + 1), {
        "long_name": "attractor, most frequent first", "units": "1"}),
        **grid_coordinates(axes, spacing)}
    fixed = {name: value for name, value in base.items() if name not in axes}
    if shock is None:
        given = dict(zip(BOX, halves[0])) if not axes else box or {}
        starts = {"starts": "uniform in a box around rest at t = 0, of half-widths box_* "
                            "(unset: each point's default)",
                  **{f"box_{name}": float(h) for name, h in given.items()},
                  "box_units": ", ".join(f"box_{name}: {u}" for name, u in BOX.items())}
    else:
        starts = {"starts": "base shock at a uniform moment of the orbit reached from rest",
                  "shock": shock, "shock_units": "m/s"}
    ds = xr.Dataset(data, coords=coords, attrs={
        **run_attributes(fixed, PRESET_NOTES.get(preset or DEFAULT_PRESET, [])),
        "title": "harvester_sweep basins of attraction of a piezoelectric harvester with a "
                 "Hertz stop",
        "preset": preset or DEFAULT_PRESET, "grid_axes": " ".join(axes), "samples": samples,
        "seed": seed, **starts})
    return ds


def check_draws(samples, seed, box, shock):
    """The draw options, checked (ParameterError naming the one out of range)."""
    samples, seed = whole_number("samples", samples, 1, MAX_SAMPLES), check_seed(seed)
    if shock is not None:
        if box is not None:
            raise ParameterError("box and shock: give one, the starts are drawn from a box "
                                 "or left by a base shock")
        if not is_number(shock) or not 0 < shock < math.inf:
            raise ParameterError(f"shock [m/s] = {shock!r}: must be a number > 0 and finite")
        shock = float(shock)
    if box is not None:
        if not isinstance(box, dict):
            raise ParameterError(f"box = {box!r}: must be a table of half-widths "
                                 + ", ".join(f"{k} [{u}]" for k, u in BOX.items()))
        for name, value in box.items():
            if name not in BOX:
                raise ParameterError(f"box.{name}: unknown; must be among "
                                     + ", ".join(f'"{k}"' for k in BOX))
            if not is_number(value) or not 0 < value < math.inf:
                raise ParameterError(f"box.{name} [{BOX[name]}] = {value!r}: must be a "
                                     "number > 0 and finite")
    return samples, seed, box, shock


def _box(p: dict, box: dict | None) -> np.ndarray:
    """Half-widths of the box of starts [m, m/s, V]: ``box``'s, else the point's default."""
    X, V = linear_response(**p)
    x = BOX_SIZE * max(abs(complex(X)), abs(p["gap"]))
    w = 2 * math.pi * p["frequency"]
    half = np.array([x, w * x, x * abs(complex(V)) / max(abs(complex(X)), 1e-300)])
    for name, value in (box or {}).items():
        half[list(BOX).index(name)] = value
    return half


def _solve(spec: BasinSpec, progress) -> list:
    """Every point's attractors (dicts of :func:`_attractors`), ``spec.samples`` starts
    each; the points' parameters resolved a call's worth at a time."""
    samples, shock = spec.samples, spec.shock
    draws = np.random.default_rng(spec.seed)
    if shock is None:
        unit = draws.uniform(-1.0, 1.0, (samples, 3))
    else:
        when = draws.random(samples)  # the moment, as a fraction of the orbit
        sign = np.where(draws.random(samples) < 0.5, -1.0, 1.0)
    per_call = max(1, CALL_STARTS // samples)
    found = []
    with tqdm(total=spec.n_points * samples, unit="start", desc="basins", smoothing=0.1,
              disable=not progress or not sys.stderr.isatty()) as bar:
        for first in range(0, spec.n_points, per_call):
            chunk = [spec.point(i) for i in range(first, min(first + per_call, spec.n_points))]
            one = pack_points(chunk)
            packed = replace(one, **{f.name: np.repeat(getattr(one, f.name), samples, axis=0)
                                     for f in fields(one)})
            if shock is None:
                halves = np.array([_box(p, spec.box) for p in chunk])
                packed.states[:, :3] = (unit[None] * halves[:, None]).reshape(-1, 3)
            else:
                factors = np.array([p["base_forcing_factor"] for p in chunk])
                packed.rows[:, PARAM.phase], packed.states[:] = _shocked(one, when, sign,
                                                                         shock, factors)
            results = solve(packed, samples=MAX_ORBIT_PERIOD, on_points=bar.update)
            for i in range(len(chunk)):
                part = slice(i * samples, (i + 1) * samples)
                found.append(_attractors(results, part, packed.rows[part]))
    return found


def _shocked(one, when, sign, shock, factors):
    """Forcing phases [rad] (n * samples,) and states (n * samples, len(STATE)) a base shock
    leaves on the orbit each point of ``one`` reaches from rest (the state the motion
    reached, where it reaches none); ``factors`` (n,): each point's base_forcing_factor
    mu_1 [-], by which the base's acceleration, the shock's too, forces the tip."""
    rest = solve(one, samples=MAX_ORBIT_PERIOD)
    phases, states = [], []
    for i, row in enumerate(one.rows):
        n = int(row[PARAM.steps])
        period = max(int(rest.metrics[i, METRIC.orbit_period]), 1)
        orbit = period_map.record(row, rest.finals[i], period)
        step = np.minimum((when * period * n).astype(np.int64), period * n - 1)
        state = np.repeat(rest.finals[i][None], len(when), axis=0)
        state[:, :3] = orbit[step, :3]
        state[:, STATE.stop_x] = orbit[step, SERIES.stop_displacement]
        state[:, STATE.stop_v] = orbit[step, SERIES.stop_velocity]
        # the velocities relative to the base: the tip's, and a moving stop's (0 if rigid)
        state[:, STATE.v] -= sign * shock * factors[i]  # (a moving stop: mu_1 = 1)
        state[:, STATE.stop_v] -= np.where(row[PARAM.stop_ratio] > 0, sign * shock, 0.0)
        phases.append(2.0 * math.pi * (step % n) / n)
        states.append(state)
    return np.concatenate(phases), np.concatenate(states)


def _attractors(results, part: slice, rows: np.ndarray) -> dict:
    """The attractors reached by the starts ``part`` of ``results`` (one point's, of
    parameter rows ``rows``): basin fractions and metrics, most frequent first."""
    metrics, finals = results.metrics[part], results.finals[part]
    samples = len(metrics)
    status = metrics[:, METRIC.status]
    period = metrics[:, METRIC.orbit_period].astype(int)
    n = int(rows[0, PARAM.steps])
    section = np.rint(rows[:, PARAM.phase] / (2.0 * math.pi) * n).astype(np.int64)
    left = np.flatnonzero(status == STATUS.settled)
    # (floored as the solver floors its scales: the orbit of an unforced device is rest)
    scale = np.maximum(np.max(np.abs(results.strobes[part][left][..., :3]), axis=(0, 1)),
                       scale_floors(rows[:1], 3)[0]) if left.size else None
    groups = []
    while left.size:
        head = left[0]
        p = period[head]
        orbit = period_map.record(rows[head], finals[head], p)[:, :3]
        # the orbit's p states at the forcing phase of each start left
        at = (section[left] - section[head]) % n
        states = orbit[at[:, None] + n * np.arange(p)[None, :]]
        distance = np.min(np.max(np.abs(finals[left, None, :3] - states) / scale, axis=2),
                          axis=1)
        member = (period[left] == p) & (distance <= TOLERANCE)
        member[0] = True  # (the head always leaves, whatever rounding says)
        groups.append(left[member])
        left = left[~member]
    groups.sort(key=len, reverse=True)
    first = np.array([g[0] for g in groups], dtype=int)
    fraction = np.array([len(g) for g in groups], dtype=float) / samples
    impacts = metrics[first, METRIC.impacts_per_period] if groups else np.empty(0)
    # (where no start reached an orbit the share that strikes is unknown, not 0)
    impact = float(fraction[impacts > 0].sum()) if groups else math.nan
    found = {"basin_fraction": fraction,
             "basin_fraction_error": np.sqrt(fraction * (1 - fraction) / samples),
             "impact_basin_fraction": impact,
             "impact_basin_fraction_error": math.sqrt(impact * (1 - impact) / samples),
             "fraction_not_settled": float(np.mean(status == STATUS.not_settled)),
             "fraction_diverged": float(np.mean(status == STATUS.diverged))}
    radius = results.run_outputs()["spectral_radius"][part]
    for name in ATTRACTOR_OUTPUTS:
        found[name] = (radius if name == "spectral_radius"
                       else metrics[:, metric_index(name)])[first]
    return found


__all__ = ["BasinSpec", "basin_fractions", "basin_map", "check_basins"]
