"""Sweep files: TOML (or a dict of the same shape) read and checked into a :class:`SweepSpec`.

A sweep file::

    model = "tip_mass"      # or "beam": the bimorph in modes (beam_cluster.run_beam_file)
    preset = "paper"
    [parameters]            # fixed values, SI units, any name of PARAMETERS
    gap = 1e-6
    [grid]                  # one axis per parameter: a list, or a range table
    frequency = { start = 100, stop = 300, num = 201 }        # [Hz]
    resistance = [1e3, 1e4, 1e5]                              # [Ohm]
    [sweep]
    directions = ["up", "down"]   # continue the state along frequency (omit: each point from rest)
    outputs = ["power", "x_max", "strobe"]
    samples = 64                  # stroboscopic samples kept per point when "strobe" is asked
    chunk_size = 4096             # points per chunk file, rounded to whole frequency lines
                                  # (default: 4096, and 128 lines at least under continuation,
                                  # up to 131072 points)
    error_estimate = "all"        # step-halving error estimate (and the accuracy target met)
                                  # on every point (default), "sample" (~64 points) or "none"

Everything is checked before any integration; a bad entry raises :class:`ParameterError`
naming its key.

A beam sweep (``model = "beam"``) has the same parts with the beam's presets and parameters
(beam_parameters.BEAM_PARAMETERS); its ``[sweep]`` takes ``directions`` and ``chunk_size``
only, since every beam point is solved with all its outputs and its error estimate.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .outputs import ENGINE_METRICS
from .outputs import OUTPUTS as OUTPUT_VARIABLES
from .parameters import (
    DEFAULT_PRESET,
    PARAMETERS,
    ParameterError,
    check_names,
    is_number,
    resolve_parameters,
    value_text,
    whole_number,
)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

#: What ``sweep.outputs`` may name: the kernel metrics, and "strobe" for bifurcation diagrams.
#: ``status`` and ``periods_run`` are always stored: without them no value can be trusted.
ALWAYS_STORED = ("status", "periods_run")
METRIC_OUTPUTS = tuple(name for name in ENGINE_METRICS if name not in ALWAYS_STORED)
OUTPUTS = METRIC_OUTPUTS + ("strobe",)
DIRECTIONS = ("up", "down")
DEFAULT_SAMPLES = 32
DEFAULT_CHUNK_SIZE = 4096
# Under continuation a chunk is one kernel call whose lanes walk its lines, and its end waits
# for the longest line: the default chunk holds at least this many lines (a 32 x 201 sweep
# up and down ran at 157-169 M steps/s in chunks of 20 lines, at 239-279 in one of 64).
DEFAULT_CHUNK_LINES = 128
DEFAULT_CHUNK_CAP = 2**17  # points: a chunk's arrays take about 2 kB a point with 32 samples

#: The models a sweep file may name (``model``; default the tip-mass model).
MODELS = ("tip_mass", "beam")
_TOP_KEYS = ("model", "preset", "parameters", "grid", "sweep")
_SWEEP_KEYS = ("directions", "outputs", "samples", "chunk_size", "error_estimate")
_BEAM_SWEEP_KEYS = ("directions", "chunk_size")
#: A settled beam point takes 5 to 140 ms, one that runs its budget of periods a second
#: or more (benchmarks/results/beam.md), where a tip-mass point takes under a millisecond:
#: a beam chunk is small, so that an interruption loses minutes of work, not hours. Under
#: continuation it holds whole lines, at least DEFAULT_BEAM_CHUNK_LINES of them: a
#: chunk's lines are solved together at each frequency step, and the modal engine's
#: threads share that step's points.
DEFAULT_BEAM_CHUNK_SIZE = 64
DEFAULT_BEAM_CHUNK_LINES = 8
ERROR_ESTIMATES = ("sample", "all", "none")
ERROR_SAMPLE_POINTS = 64  # points given an error estimate by default
_RANGE_KEYS = ("start", "stop", "num", "scale")
#: Most values on one grid axis: a range's ``num`` is refused beyond it before numpy
#: allocates the axis (num = 1e12 asked for 7 TiB), and each value is checked in Python
#: (~1 us). At ~1 ms a point, 1e7 points are hours on a machine.
MAX_AXIS_POINTS = 10**7
#: Most points of a grid, counted from the axes' lengths before any axis is made (three
#: axes of 1e7 values are 1e21 points, beyond a 64-bit index): at ~1e4 RK4 steps a point
#: at the least, more are years of work on any machine.
MAX_GRID_POINTS = 10**12
#: Axes longer than this enter the sweep's identity (and the manifest of its partial
#: result) by their SHA-256, not value by value: a JSON list of 1e7 values took seconds.
LISTED_AXIS_POINTS = 4096


@dataclass(frozen=True)
class SweepSpec:
    """A checked sweep.

    Attributes
    ----------
    preset : str
        Preset the fixed parameters start from.
    fixed : dict
        Overrides of ``[parameters]`` (SI units), not including the grid axes.
    grid : dict of str -> numpy.ndarray
        Grid axis name -> values (SI units of the parameter), in file order. With
        ``directions``, the frequency axis is sorted ascending.
    spacing : dict of str -> str
        Grid axis name -> ``"linear"``, ``"log"`` or ``"list"`` (how the values were given).
    directions : tuple of str
        ``("up",)``, ``("down",)``, ``("up", "down")``, or ``()`` for points run from rest.
    metrics : tuple of str
        Metric names stored, always ending with ``status`` and ``periods_run``.
    samples : int
        Stroboscopic samples stored per point, 0 when "strobe" is not asked.
    chunk_size : int
        Points per chunk, before rounding to whole frequency lines (default: DEFAULT_CHUNK_SIZE,
        and under continuation DEFAULT_CHUNK_LINES lines, up to DEFAULT_CHUNK_CAP points).
    error_estimate : str
        Which points get a step-halving error estimate, and with it the accuracy target met
        where the step is automatic: ``"all"`` (the default), ``"sample"`` (about
        ERROR_SAMPLE_POINTS spread over the grid) or ``"none"``.
    base : dict
        The validated parameters of ``preset`` with ``fixed`` (SI units), resolved once:
        what the grid's points share.
    model : str
        ``"tip_mass"`` or ``"beam"`` (its parameters those of beam_parameters, its metrics
        every output of a beam point, always with the error estimate).
    """

    preset: str
    fixed: dict
    grid: dict
    spacing: dict
    directions: tuple
    metrics: tuple
    samples: int
    chunk_size: int
    error_estimate: str = "all"
    base: dict = None
    model: str = "tip_mass"

    @property
    def continuation(self) -> bool:
        """True when each point starts from the previous frequency's final state."""
        return bool(self.directions)

    @property
    def line_axes(self) -> tuple:
        """Grid axes that index independent lines (all but frequency under continuation)."""
        return tuple(a for a in self.grid if not (self.continuation and a == "frequency"))

    @property
    def line_length(self) -> int:
        """Points per line: the frequency axis under continuation, else 1."""
        return len(self.grid["frequency"]) if self.continuation else 1

    @property
    def line_shape(self) -> tuple:
        """Shape of the array of lines: (direction,) if any, then the line axes."""
        dirs = (len(self.directions),) if self.continuation else ()
        return dirs + tuple(len(self.grid[a]) for a in self.line_axes)

    @property
    def n_lines(self) -> int:
        return math.prod(self.line_shape)

    @property
    def n_points(self) -> int:
        return self.n_lines * self.line_length

    @property
    def lines_per_chunk(self) -> int:
        return max(1, self.chunk_size // self.line_length)

    @property
    def _part_lines(self) -> int:
        """Lines a chunk may draw from: all of them, but for the beam under continuation
        those of one direction (a beam chunk's lines are solved together at each frequency
        step, which a chunk across two directions would halve)."""
        if self.model == "beam" and self.continuation:
            return self.n_lines // len(self.directions)
        return self.n_lines

    @property
    def n_chunks(self) -> int:
        part = self._part_lines
        return self.n_lines // part * -(-part // self.lines_per_chunk)

    def chunk_lines(self, chunk: int) -> range:
        """The lines of chunk ``chunk`` (0 <= chunk < n_chunks): lines_per_chunk of them in
        line order, fewer at the end of the grid (or, for the beam, of a direction)."""
        part = self._part_lines
        per_part = -(-part // self.lines_per_chunk)
        which, k = divmod(chunk, per_part)
        first = which * part + k * self.lines_per_chunk
        return range(first, min(first + self.lines_per_chunk, (which + 1) * part))

    def estimated(self, flat_index: np.ndarray) -> np.ndarray:
        """Which points (by index line * line_length + position along the line) get an
        error estimate: a fixed stride over the grid, whatever the chunking."""
        if self.error_estimate == "none":
            return np.zeros(np.shape(flat_index), dtype=bool)
        stride = 1 if self.error_estimate == "all" else max(
            1, self.n_points // ERROR_SAMPLE_POINTS)
        return np.asarray(flat_index) % stride == 0

    def values_at(self, point: int) -> dict:
        """Grid values [SI] of point ``point`` (index line * line_length + position along
        the line, the line in ascending frequency)."""
        line, position = divmod(point, self.line_length)
        index = [int(i) for i in np.unravel_index(line, self.line_shape)]
        if self.continuation:
            index.pop(0)  # (the direction)
        values = {a: self.grid[a][i].item() for a, i in zip(self.line_axes, index)}
        if self.continuation:
            values["frequency"] = self.grid["frequency"][position].item()
        return values

    def point_parameters(self, values: dict) -> dict:
        """Validated parameters of one point from its grid ``values`` (SI units)."""
        if self.model == "beam":
            from .beam_parameters import resolve_beam_parameters

            return resolve_beam_parameters(self.preset, **self.fixed, **values)
        return resolve_parameters(self.preset, **self.fixed, **values)

    def canonical(self) -> str:
        """JSON text that identifies the sweep (what a partial result must match)."""
        from .version import __version__

        return json.dumps(
            {
                "version": __version__,
                "model": self.model,
                # Chunks made by another engine or solver would not match: a development
                # install changes them without changing the version.
                "kernel_sha256": (_tip_mass_digest() if self.model == "tip_mass"
                                  else _beam_digest()),
                "preset": self.preset,
                "parameters": self.base,
                "grid": {name: _identity(values) for name, values in self.grid.items()},
                "directions": list(self.directions),
                "metrics": list(self.metrics),
                "samples": self.samples,
                "chunk_size": self.chunk_size,
                "error_estimate": self.error_estimate,
            },
            sort_keys=True,
        )

    def digest(self) -> str:
        """SHA-256 of :meth:`canonical`."""
        return hashlib.sha256(self.canonical().encode()).hexdigest()


def _digest(compiled: str, names: tuple) -> str:
    """SHA-256 of a compiled digest and of the package's files ``names``."""
    from ._engine import cache

    python = cache.source_digest(tuple(Path(__file__).parent / name for name in names))
    return hashlib.sha256(f"{compiled} {python}".encode()).hexdigest()


def _tip_mass_digest() -> str:
    """SHA-256 of the source a tip-mass point's numbers come from: the engine's and the
    orbit solver's (orbits.SOURCE_DIGEST, the model's declaration included), and the
    Python that resolves its parameters, packs them and chooses its step."""
    from .orbits import SOURCE_DIGEST

    return _digest(SOURCE_DIGEST, ("parameters.py", "packing.py", "timescales.py",
                                   "contact.py", "results.py"))


def _beam_digest() -> str:
    """SHA-256 of the source a beam point's numbers come from: the modal engine's, and the
    Python that chooses its steps, solves its orbit (Newton on the period map, the step
    halvings) and measures it, which for the beam is most of the method."""
    from ._engine.modal import SOURCE_DIGEST as MODAL_DIGEST

    return _digest(MODAL_DIGEST, ("beam_runs.py", "beam_packing.py", "modal_map.py",
                                  "bimorph.py", "rod.py", "materials.py", "contact.py",
                                  "beam_parameters.py", "models/beam.py"))


def _identity(values: np.ndarray):
    """An axis as it enters the sweep's identity: its values, or for a long one their
    count, dtype and SHA-256."""
    if len(values) <= LISTED_AXIS_POINTS:
        return values.tolist()
    data = np.ascontiguousarray(values)
    return {"values": len(data), "dtype": str(data.dtype),
            "sha256": hashlib.sha256(data.tobytes()).hexdigest()}


def load_sweep(source, model: str | None = "tip_mass") -> SweepSpec:
    """A checked :class:`SweepSpec` from a TOML file path or a dict of the same shape, of
    ``model``, the model the caller runs ("tip_mass" or "beam"): a sweep of the other one
    is refused, saying which command runs it. ``model`` None: the model the sweep names
    (``model``, "tip_mass" where it names none).

    Raises
    ------
    ParameterError
        For a missing or unreadable file, an unknown key, a value of the wrong type (a TOML
        boolean, string, date, array or table where a number is due, and so on), an empty,
        non-finite or out-of-range grid, or options that contradict each other; the message
        names the key. No other exception comes from the file's content.
    """
    if isinstance(source, SweepSpec):
        _check_model(source.model, model)
        return source
    source = read_toml(source, "sweep", _TOP_KEYS)
    named = source.get("model", "tip_mass")
    _check_model(named, model)
    beam = named == "beam"
    if beam:
        from .beam_parameters import BEAM_PARAMETERS as registry
        from .beam_parameters import DEFAULT_BEAM_PRESET as default_preset
        from .beam_parameters import resolve_beam_parameters as resolve
    else:
        registry, default_preset, resolve = PARAMETERS, DEFAULT_PRESET, resolve_parameters
    preset = source.get("preset", default_preset)
    fixed = dict(table(source, "parameters"))
    if not beam and "model" not in source:
        _beam_without_model(preset, fixed, table(source, "grid"))
    # (names checked before the call: `preset` among them would be a TypeError)
    for name in fixed if beam else ():
        if name not in registry:
            raise ParameterError(f"unknown beam parameter {value_text(name)}: known "
                                 f"parameters are {', '.join(registry)}")
    check_names(() if beam else fixed)
    base = resolve(preset, **fixed)  # bad values, named
    grid, spacing = {}, {}
    check_grid_size(table(source, "grid"))
    for name, entry in table(source, "grid").items():
        grid[name], spacing[name] = axis(name, entry, fixed, registry)
    if not grid:
        raise ParameterError("grid: give at least one parameter to sweep, e.g. "
                             "frequency = { start = 100, stop = 300, num = 201 }")
    options = table(source, "sweep")
    if beam:
        for key in options:
            if key in _SWEEP_KEYS and key not in _BEAM_SWEEP_KEYS:
                raise ParameterError(
                    f"sweep.{key}: not for the beam model, which stores every output of "
                    "every point with its error estimate; its keys are "
                    + ", ".join(_BEAM_SWEEP_KEYS))
    unknown_keys(options, _BEAM_SWEEP_KEYS if beam else _SWEEP_KEYS, "sweep.")
    directions = _directions(options, grid)
    if directions:
        grid["frequency"] = np.sort(grid["frequency"])  # "up" means increasing frequency
    line_length = len(grid["frequency"]) if directions else 1
    if beam:
        from .beam_runs import SCALARS

        chunk_size = _integer(options, "chunk_size", max(
            DEFAULT_BEAM_CHUNK_SIZE, DEFAULT_BEAM_CHUNK_LINES * line_length))
        spec = SweepSpec(preset, fixed, grid, spacing, directions,
                         SCALARS + ("modal_amplitude",), 0, chunk_size, "all", base, "beam")
        _check_corners(spec)
        return spec
    outputs = _string_list(options, "outputs", OUTPUTS, list(METRIC_OUTPUTS))
    samples = 0
    if "strobe" in outputs:
        samples = _integer(options, "samples", DEFAULT_SAMPLES)
    elif "samples" in options:
        raise ParameterError('sweep.samples: stroboscopic samples need "strobe" in sweep.outputs')
    metrics = tuple(n for n in METRIC_OUTPUTS if n in outputs or (samples and n == "orbit_period"))
    error_estimate = options.get("error_estimate", "all")
    if error_estimate not in ERROR_ESTIMATES:
        raise ParameterError(f"sweep.error_estimate = {value_text(error_estimate)}: must be one of "
                             + ", ".join(f'"{e}"' for e in ERROR_ESTIMATES))
    chunk_size = _integer(options, "chunk_size", max(
        DEFAULT_CHUNK_SIZE, min(DEFAULT_CHUNK_LINES * line_length, DEFAULT_CHUNK_CAP)))
    spec = SweepSpec(preset, fixed, grid, spacing, directions, metrics + ALWAYS_STORED, samples,
                     chunk_size, error_estimate, base)
    _check_corners(spec)
    if samples:
        budget = int(grid["max_periods"].min()) if "max_periods" in grid else base["max_periods"]
        if samples > budget:
            raise ParameterError(f"sweep.samples = {samples}: more than max_periods = {budget:g}, "
                                 "the most forcing periods a point runs")
    return spec


def _beam_without_model(preset, fixed: dict, grid: dict) -> None:
    """Refuse a file that names a beam preset or parameter but no ``model``: it is read as
    the tip-mass model's, whose messages ("unknown parameter 'n_modes'") would not say
    what is missing."""
    from .beam_parameters import BEAM_PARAMETER_PRESETS, BEAM_PARAMETERS

    beam_only = [name for name in (*fixed, *grid)
                 if name in BEAM_PARAMETERS and name not in PARAMETERS]
    preset = preset if isinstance(preset, str) else None  # (a bad one is refused later)
    if preset in BEAM_PARAMETER_PRESETS or beam_only:
        what = (f"preset {value_text(preset)}" if preset in BEAM_PARAMETER_PRESETS
                else f"parameter {value_text(beam_only[0])}")
        raise ParameterError(f"{what} is the beam model's: add model = \"beam\" to the "
                             "sweep file (without it the file is the tip-mass model's)")


def _check_model(named, model: str | None) -> None:
    """Refuse a sweep whose ``model`` is unknown or not ``model``, the one the caller runs
    (None: any), in one line saying which command runs it."""
    if named not in MODELS:
        raise ParameterError(f"model = {value_text(named)}: must be one of "
                             + ", ".join(f'"{m}"' for m in MODELS))
    if model is not None and named != model:
        command = ("harvester-sweep beam-sweep SWEEP.toml (beam_cluster.run_beam_file in "
                   "Python)" if named == "beam" else "harvester-sweep run SWEEP.toml "
                   "(run_sweep in Python)")
        raise ParameterError(f"model = \"{named}\": a sweep of the {named.replace('_', '-')} "
                             f"model; run it with {command}")


def read_toml(source, what: str, keys) -> dict:
    """The table of a TOML file path, or ``source`` itself when it is a dict; its keys
    among ``keys`` (ParameterError, naming the file or key, otherwise)."""
    if isinstance(source, (str, Path)):
        path = Path(source)
        try:
            with path.open("rb") as handle:
                source = tomllib.load(handle)
        except OSError as error:
            raise ParameterError(f"{path}: cannot read the {what} file ({error.strerror})") \
                from None
        except ValueError as error:  # TOMLDecodeError, bytes not UTF-8, an integer of
            # over 4300 digits (Python refuses to convert it)
            raise ParameterError(f"{path}: not valid TOML: {error}") from None
    if not isinstance(source, dict):
        raise ParameterError(f"a {what} is a TOML file path or a dict with keys "
                             + ", ".join(keys))
    unknown_keys(source, keys, "")
    return source


def unknown_keys(entries: dict, known, prefix: str) -> None:
    """ParameterError for the first key of ``entries`` not among ``known``."""
    for key in entries:
        if key not in known:
            raise ParameterError(f"{prefix}{_key(key)}: unknown key; known keys are "
                                 + ", ".join(known))


def _key(key) -> str:
    """A key as written in a message: quoted when it is not plain text (TOML's quoted keys
    may hold a newline, which would break the one-line message)."""
    return key if isinstance(key, str) and key.isprintable() else value_text(key)


def table(source: dict, key: str) -> dict:
    value = source.get(key, {})
    if not isinstance(value, dict):
        raise ParameterError(f"{key}: must be a table, e.g. [{key}]")
    return value


def check_grid_size(grid: dict, per_point: int = 1, what: str = "points") -> None:
    """Refuse, before any axis is made, a grid of more than MAX_GRID_POINTS points
    (``per_point`` runs each: a basin map's starts): its size is the product of its axes'
    lengths, a range's ``num`` or a list's length. An axis of another shape is left to
    :func:`axis` to refuse."""
    sizes = []
    for key, entry in grid.items():
        if isinstance(entry, dict):
            try:
                sizes.append(whole_number(f"{key}.num", entry.get("num"), 1))
            except ParameterError:  # (refused with its axis)
                pass
        elif isinstance(entry, (list, tuple, np.ndarray)):
            sizes.append(len(entry))
    count = math.prod(sizes) * per_point
    if count > MAX_GRID_POINTS:
        raise ParameterError(
            f"grid: {' x '.join(f'{n:,}' for n in sizes)}"
            f"{f' x {per_point:,} starts' if per_point > 1 else ''} = {count:.3g} {what}, "
            f"more than the {MAX_GRID_POINTS:.0e} a run may hold (years of work): make the "
            "grid coarser")


def axis(name: str, entry, fixed: dict, registry=PARAMETERS) -> tuple[np.ndarray, str]:
    """Values [SI] and spacing of one grid axis of a parameter of ``registry`` (the
    model's), each value checked against its range."""
    key = f"grid.{_key(name)}"
    if name not in registry:
        raise ParameterError(f"{key}: unknown parameter; known parameters are "
                             + ", ".join(registry))
    parameter = registry[name]
    if parameter.kind not in ("float", "int"):
        raise ParameterError(f"{key}: only numeric parameters can be swept ({name} is "
                             f"{parameter.range_text()}); set it in [parameters]")
    if name in fixed:
        raise ParameterError(f"{key}: {name} is also set in [parameters]; give it in one place")
    if name in OUTPUT_VARIABLES:  # (a dataset variable of that name holds each point's own)
        raise ParameterError(f"{key}: {name} is also an output (each point's own, refined where "
                             "its error estimate asks), so it cannot be a grid axis: run one "
                             "sweep for each value")
    if isinstance(entry, dict):
        values, spacing = _range(key, entry), entry.get("scale", "linear")
        return _distinct(key, _checked_range(parameter, values), parameter.unit), spacing
    elif isinstance(entry, (list, tuple, np.ndarray)):
        # (a TOML array as it is: a nested one is refused below, not flattened)
        if isinstance(entry, np.ndarray) and entry.ndim != 1:
            raise ParameterError(f"{key}: an array of shape {entry.shape}; an axis is one list "
                                 "of values (one axis per parameter)")
        values = list(entry) if isinstance(entry, (list, tuple)) else entry.tolist()
        spacing = "list"
        if not values:
            raise ParameterError(f"{key}: the list of values is empty")
        if len(values) > MAX_AXIS_POINTS:
            raise ParameterError(f"{key}: {len(values)} values, more than the "
                                 f"{MAX_AXIS_POINTS:.0e} an axis may hold")
    else:
        raise ParameterError(f"{key}: give a list of values or a table "
                             "{ start, stop, num, scale = \"linear\" | \"log\" }")
    checked = []
    for value in values:
        try:  # (check refuses bools, strings, dates, arrays and tables: not numbers)
            checked.append(parameter.check(value))
        except ParameterError as error:
            raise ParameterError(f"grid.{error}") from None
    values = np.asarray(checked, dtype=np.int64 if parameter.kind == "int" else np.float64)
    return _distinct(key, values, parameter.unit), spacing


def _distinct(key: str, values: np.ndarray, unit: str) -> np.ndarray:
    """``values``, refused where one repeats: the dataset's coordinate would hold it twice,
    and ``ds.sel`` could not pick either point."""
    unique, counts = np.unique(values, return_counts=True)
    if (counts > 1).any():
        twice = unique[counts > 1][0].item()
        raise ParameterError(f"{key}: the value {twice!r} [{unit}] appears "
                             f"{counts[counts > 1][0]} times; an axis's values must differ")
    return values


def _checked_range(parameter, values: np.ndarray) -> np.ndarray:
    """The values of a range table checked against ``parameter``'s range as a whole: each
    is checked (Parameter.check, which names the first bad one) only where the array says
    one may be bad, since an allowed range is an interval (a million values took a second
    one by one)."""
    with np.errstate(invalid="ignore"):
        whole = np.isfinite(values) & (values == np.round(values)
                                       if parameter.kind == "int" else True)
    suspects = [int(i) for i in (np.flatnonzero(~whole)[:1].tolist()
                                 + [np.argmin(values), np.argmax(values)])]
    for i in sorted(suspects):
        try:
            parameter.check(values[i].item())
        except ParameterError as error:
            raise ParameterError(f"grid.{error}") from None
    return values.astype(np.int64) if parameter.kind == "int" else values


def _range(key: str, entry: dict) -> np.ndarray:
    """Values of a range table ``{start, stop, num, scale}``."""
    unknown_keys(entry, _RANGE_KEYS, f"{key}.")
    for part in ("start", "stop", "num"):
        if part not in entry:
            raise ParameterError(f"{key}.{part}: missing; a range is "
                                 "{ start, stop, num, scale = \"linear\" | \"log\" }")
    ends = []
    for part in ("start", "stop"):
        value = entry[part]
        try:  # (as a float: numpy cannot take an integer beyond int64 as an end)
            number = float(value) if is_number(value) else math.nan
        except OverflowError:  # an integer beyond a double's range (tomllib reads any size)
            number = math.inf
        if not math.isfinite(number):
            raise ParameterError(f"{key}.{part} = {value_text(value)}: must be a finite number")
        ends.append(number)
    start, stop = ends
    num = whole_number(f"{key}.num", entry["num"], 1, MAX_AXIS_POINTS)
    scale = entry.get("scale", "linear")
    if scale == "linear":
        with np.errstate(over="ignore", invalid="ignore"):  # (stop - start beyond a double:
            return np.linspace(start, stop, num)  # inf and nan, refused by the check)
    if scale == "log":
        if start <= 0 or stop <= 0:
            raise ParameterError(f"{key}: scale = \"log\" needs start > 0 and stop > 0 "
                                 f"(got start = {value_text(start)}, stop = {value_text(stop)})")
        return np.geomspace(start, stop, num)
    raise ParameterError(f"{key}.scale = {value_text(scale)}: must be \"linear\" or \"log\"")


def _directions(options: dict, grid: dict) -> tuple:
    if "directions" not in options:
        return ()
    directions = _string_list(options, "directions", DIRECTIONS, None)
    if "frequency" not in grid:
        raise ParameterError("sweep.directions: continuation runs along frequency, which is "
                             "not a grid axis; add grid.frequency or remove sweep.directions")
    return tuple(d for d in DIRECTIONS if d in directions)


def _string_list(options: dict, key: str, allowed, default) -> list:
    value = options.get(key, default)
    if not isinstance(value, list) or not value:
        raise ParameterError(f"sweep.{key}: must be a non-empty list of "
                             + ", ".join(f'"{a}"' for a in allowed))
    for item in value:
        if item not in allowed:
            raise ParameterError(f"sweep.{key}: {value_text(item)} is unknown; must be among "
                                 + ", ".join(f'"{a}"' for a in allowed))
    return value


def _integer(options: dict, key: str, default: int) -> int:
    return whole_number(f"sweep.{key}", options.get(key, default), 1)


def _check_corners(spec: SweepSpec) -> None:
    """Check the parameter sets at the corners of the grid before any work.

    Each value was checked against its own range; what remains are the checks that couple
    parameters (the step against the fastest oscillation and the load circuit's decay,
    hertz_stiffness against stop_mass). These are monotonic in each parameter, so the
    grid's extreme values are where they fail first.
    """
    extremes = [(name, sorted({float(values.min()), float(values.max())}))
                for name, values in spec.grid.items()]
    for corner in itertools.product(*(values for _, values in extremes)):
        values = {name: value for (name, _), value in zip(extremes, corner)}
        try:
            p = spec.point_parameters(values)  # (a point too stiff is flagged, not refused here)
            if spec.model == "beam":  # (but a beam's grid beyond steps_per_period's range is)
                from .beam_packing import beam_system, first_steps

                first_steps(p, beam_system(p))
        except ParameterError as error:
            at = ", ".join(f"{name} = {value:g}" for name, value in values.items())
            raise ParameterError(f"grid: at the grid point {at}: {error}") from None
