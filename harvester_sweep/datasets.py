"""xarray datasets and netCDF files: CF units and long names on every variable, all from the
registry of outputs (:mod:`harvester_sweep.outputs`)."""

from __future__ import annotations

import datetime
import os
from pathlib import Path

import numpy as np
import xarray as xr

from .outputs import OUTPUTS, RUN_OUTPUTS, SCENE_OUTPUTS, SERIES, STATUS_NAMES, STROBES
from .parameters import DEFAULT_PRESET, PARAMETERS, PRESET_NOTES


def multiplier_coordinate(n: int) -> dict:
    """The coordinate of the Floquet multipliers (outputs with dims ("multiplier",)): one
    per component of the period map, 3 (x, v, V), 5 with a moving stop (x_s, v_s)."""
    return {"multiplier": ("multiplier", np.arange(1, n + 1), {
        "units": "1", "long_name": "Floquet multiplier, by decreasing modulus"})}


def series_dataset(values: np.ndarray, t0: float, parameters: dict) -> xr.Dataset:
    """Dataset of a recorded series: columns (x, v, V, F_c) sampled every step from ``t0`` [s]."""
    n = values.shape[0]
    step = 1.0 / (parameters["frequency"] * parameters["steps_per_period"])
    time = t0 + step * np.arange(n)
    columns = dict(zip(SERIES, values.T))
    columns["instantaneous_power"] = columns["voltage"] ** 2 / parameters["resistance"]
    data = {name: ("time", columns[name], output.attrs) for name, output in SERIES.items()}
    coords = {"time": ("time", time, {"units": "s", "long_name": "time since the start"})}
    return xr.Dataset(data, coords=coords)


def scene_dataset(result, series: xr.Dataset) -> xr.Dataset:
    """One scene: its metrics (scalars), the series of its last orbit periods, its parameters."""
    ds = series.copy()
    for name in SCENE_OUTPUTS:
        output = OUTPUTS[name]
        value = result.metrics[name]
        if name == "status":
            value = STATUS_NAMES.index(value)
        if output.dims:
            value = [np.nan if v is None else v for v in value]
        ds[name] = (output.dims, np.array(np.nan if value is None else value,
                                          dtype=output.dtype), output.attrs)
    ds = ds.assign_coords(multiplier_coordinate(len(result.metrics["floquet_multipliers_real"])))
    ds.attrs.update(run_attributes(result.parameters, result.notes))
    return ds


def sweep_dataset(spec, chunks: list) -> xr.Dataset:
    """Assemble the outputs of every chunk (in order) into the sweep's Dataset.

    ``spec`` is a :class:`harvester_sweep.sweep_file.SweepSpec`; each chunk a dict of
    ``metrics`` (lines, points per line, len(spec.metrics)), ``strobe`` (..., samples, 2:
    x [m], V [V]), ``error_estimate`` and ``run_time`` [s] (see chunks.compute_chunk).
    Variables: the metrics of ``spec.metrics``, ``error_estimate``, the solver's outputs
    (outputs.RUN_OUTPUTS, the multipliers over ``multiplier``), ``strobe_displacement``
    and ``strobe_voltage`` over ``sample`` when stroboscopic samples were asked; units,
    long names, dtypes and flags from the registry (:mod:`harvester_sweep.outputs`).
    Global attributes: the fixed parameters with their units, the sweep itself, the
    package version, the date and the integration time [s].
    """
    metrics = np.concatenate([c["metrics"] for c in chunks])
    strobe = np.concatenate([c["strobe"] for c in chunks])
    shape = spec.line_shape + (spec.line_length,)
    dims = (("direction",) if spec.continuation else ()) + spec.line_axes + ("frequency",)
    order = (("direction",) if spec.continuation else ()) + tuple(spec.grid)
    if not spec.continuation:
        shape, dims = shape[:-1], dims[:-1]  # lines of one point

    def variable(values, attrs, extra=()):
        da = xr.DataArray(values.reshape(shape + values.shape[2:]), dims=dims + extra,
                          attrs=attrs)
        return da.transpose(*order, *extra)

    data = {}
    for k, name in enumerate(spec.metrics):
        output = OUTPUTS[name]
        data[name] = variable(metrics[..., k].astype(output.dtype), output.attrs)
    if spec.error_estimate != "none":
        errors = np.concatenate([c["error_estimate"] for c in chunks])
        output = OUTPUTS["error_estimate"]
        data[output.name] = variable(errors, {
            **output.attrs, "comment": f"points estimated: {spec.error_estimate}; "
                                       + output.comment})
    for name in RUN_OUTPUTS:
        output = OUTPUTS[name]
        values = np.concatenate([c[name] for c in chunks]).astype(output.dtype)
        data[name] = variable(values, output.attrs, extra=output.dims)
    if spec.samples:
        for col, name in enumerate(STROBES):  # (the columns of a chunk's strobe)
            data[name] = variable(strobe[..., col], OUTPUTS[name].attrs, extra=("sample",))

    coords = {**multiplier_coordinate(data["floquet_multipliers_real"].sizes["multiplier"]),
              **grid_coordinates(spec.grid, spec.spacing)}
    if spec.continuation:
        coords["direction"] = ("direction", list(spec.directions), {
            "units": "1",
            "long_name": "direction of the frequency continuation: each point starts from the "
                         "final state of the previous frequency (up: increasing)"})
    if spec.samples:
        coords["sample"] = ("sample", np.arange(1 - spec.samples, 1), {
            "units": "1", "long_name": "forcing periods before the end of the run (0: last)"})

    fixed = {name: value for name, value in spec.base.items() if name not in spec.grid}
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(run_attributes(fixed, PRESET_NOTES.get(spec.preset, [])))
    ds.attrs.update({
        "title": "harvester_sweep sweep of steady states of a piezoelectric harvester with a "
                 "Hertz stop",
        "preset": spec.preset,
        "grid_axes": " ".join(spec.grid),
        "directions": " ".join(spec.directions) or "none (every point from rest)",
        "sweep": spec.canonical(),
        "sweep_sha256": spec.digest(),
        "run_time": float(sum(c["run_time"] for c in chunks)),
        "run_time_units": "s",
        "run_time_comment": "integration time summed over the chunks",
    })
    return ds


def grid_coordinates(grid: dict, spacing: dict) -> dict:
    """Coordinates of grid axes (name: values [SI]), with units, long names and spacing
    (``linear``, ``log`` or ``list``)."""
    return {name: (name, values, {"units": PARAMETERS[name].unit,
                                  "long_name": PARAMETERS[name].description,
                                  "grid_spacing": spacing[name]})
            for name, values in grid.items()}


def run_attributes(parameters: dict, notes) -> dict:
    """Global attributes: every input parameter (with its unit), notes, version and date."""
    from .version import __version__

    attrs = {
        "Conventions": "CF-1.8",
        "title": "harvester_sweep steady state of a piezoelectric harvester with a Hertz stop",
        "source": f"harvester_sweep {__version__}",
        "history": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
        + " created by harvester_sweep",
        "notes": "; ".join(notes),
    }
    for name, value in parameters.items():
        if value is None or isinstance(value, bool):  # netCDF attributes hold neither
            value = str(value).lower()
        attrs[name] = value
        attrs[f"{name}_units"] = PARAMETERS[name].unit
    return attrs


def write_netcdf(ds: xr.Dataset, path) -> None:
    """Write ``ds`` to ``path`` atomically: to a temporary name beside it, then renamed (a
    failed write leaves neither).

    Raises
    ------
    OSError
        When the file cannot be written (no permission, a full disk); netCDF4 reports what
        HDF5 refuses as a RuntimeError, raised here as an OSError of its first line.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.part")
    try:
        ds.to_netcdf(tmp, engine="netcdf4")
        os.replace(tmp, path)
    except BaseException as error:
        tmp.unlink(missing_ok=True)
        if isinstance(error, RuntimeError):
            raise OSError(str(error).splitlines()[0]) from error
        raise


def branch_dataset(branch, spec) -> xr.Dataset:
    """A branch of orbits (:func:`harvester_sweep.continuation.continue_branch`) along
    ``point``, in the order followed.

    ``spec`` is the checked problem (a continuation.ContinuationSpec). Variables: the
    continued parameter (named after it, in its unit), the engine's metrics but
    ``status`` and ``periods_run``, ``error_estimate``, the Floquet multipliers and
    ``spectral_radius``, ``stable``, ``bifurcation`` (CF flags), ``branch``,
    ``arclength``, ``steps_per_period`` (each point's: refined where its estimate asked),
    ``floquet_multipliers_shift`` (at located bifurcations) and the orbit's state at
    forcing phase 0; global attributes: the fixed
    parameters with their units, the continuation's range and options, why each branch
    ended and the run time [s].
    """
    from .outputs import ENGINE_METRICS
    from .period_map import sorted_multipliers

    points = branch.points
    parameter = spec.parameter
    lam = np.array([pt.lam for pt in points])
    mult = sorted_multipliers(np.array([pt.monodromy for pt in points]))
    radius = np.abs(mult[:, 0])
    metrics = np.array([pt.metrics for pt in points])
    values = {
        "error_estimate": np.array([pt.error for pt in points]),
        "spectral_radius": radius,
        "floquet_multipliers_real": mult.real,
        "floquet_multipliers_imag": mult.imag,
        "stable": radius < 1.0,
        "bifurcation": np.array([pt.bifurcation for pt in points]),
        "branch": np.array([pt.branch for pt in points]),
        "arclength": np.array([pt.arclength for pt in points]),
        **{name: np.array([pt.state[k] for pt in points]) for k, name in enumerate(
            ("orbit_displacement", "orbit_velocity", "orbit_voltage"))},
    }
    for k, name in enumerate(ENGINE_METRICS):
        if name not in ("status", "periods_run"):
            values[name] = metrics[:, k]
    values["orbit_period"] = np.array([pt.period for pt in points])
    values["steps_per_period"] = np.array([pt.steps for pt in points])
    data = {parameter: ("point", lam, {"units": PARAMETERS[parameter].unit,
                                       "long_name": PARAMETERS[parameter].description})}
    for name, value in values.items():
        output = OUTPUTS[name]
        attrs = output.attrs
        if name == "error_estimate":
            attrs = {**attrs, "comment": "the point corrected again at twice its steps per "
                                         "period at the same parameter value (near a fold, "
                                         "normal to the branch); a point above the accuracy "
                                         "target is solved again at a finer step "
                                         "(steps_per_period); " + output.comment}
        data[name] = (("point",) + output.dims, value.astype(output.dtype), attrs)
    shift = np.array([pt.shift for pt in points])
    data[f"{parameter}_shift"] = ("point", shift, {
        "units": PARAMETERS[parameter].unit,
        "long_name": f"change of {parameter} when the point is solved again at other steps "
                     "per period: at a located bifurcation, the larger change of its location "
                     "at 3/2 and at twice its steps (its discretization error); elsewhere, "
                     "corrected normal to the branch at twice its steps",
        "comment": "NaN where no correction or location at the other steps converged"})
    change = np.full(mult.shape, np.nan)
    for k, pt in enumerate(points):
        if pt.multiplier_shift is not None:
            change[k] = pt.multiplier_shift
    data["floquet_multipliers_shift"] = (("point", "multiplier"), change, {
        "units": "1",
        "long_name": "change of each Floquet multiplier, |mu at other steps - mu|, the larger "
                     "when a located bifurcation is located again at 3/2 and at twice its "
                     "steps per period (its multipliers' discretization error)",
        "comment": "NaN at points that are not located bifurcations"})
    data[f"{parameter}_precision"] = ("point", np.array([pt.precision for pt in points]), {
        "units": PARAMETERS[parameter].unit,
        "long_name": f"width of the bracket that locates a bifurcation in {parameter} "
                     "(0 at points not located)"})
    coords = {"point": ("point", np.arange(len(points)), {
        "units": "1", "long_name": "point along the branches, in the order followed"}),
        **multiplier_coordinate(mult.shape[1])}
    fixed = dict(spec.base)  # (the branch's first point, as the spec's check resolved it)
    fixed.pop(parameter)
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(run_attributes(fixed, PRESET_NOTES.get(spec.preset or DEFAULT_PRESET, [])))
    ds.attrs.update({
        "title": "harvester_sweep branch of periodic orbits of a piezoelectric harvester with "
                 "a Hertz stop",
        "preset": spec.preset or DEFAULT_PRESET,
        "continued_parameter": parameter,
        "start": spec.start, "stop": spec.stop,
        "range_units": PARAMETERS[parameter].unit,
        "step": spec.step, "min_step": spec.min_step, "max_step": spec.max_step,
        "max_points": spec.max_points,
        "steps_per_period": spec.steps,
        "period_doubling": "switch" if spec.switch else "mark",
        "ends": "; ".join(branch.stops),
        "run_time": branch.run_time, "run_time_units": "s",
    })
    return ds
