"""xarray datasets and netCDF files: CF units and long names on every variable."""

from __future__ import annotations

import datetime
import os
from pathlib import Path

import numpy as np
import xarray as xr

from .parameters import PARAMETERS

#: Metric name -> (CF units, long name). The names are those of ``scene --json``.
METRICS: dict[str, tuple[str, str]] = {
    "power": ("W", "mean electrical power V_rms^2/R over the orbit"),
    "v_rms": ("V", "root mean square voltage over the orbit"),
    "v_peak": ("V", "peak absolute voltage over the orbit"),
    "power_peak": ("W", "peak instantaneous electrical power v_peak^2/R"),
    "x_max": ("m", "largest tip displacement (positive towards the stop)"),
    "x_min": ("m", "smallest tip displacement"),
    "contact_force_max": ("N", "peak contact force"),
    "impacts_per_period": ("1", "impacts per forcing period"),
    "approach_velocity": ("m/s", "mean tip velocity at first touch of the stop"),
    "orbit_period": ("1", "forcing periods per orbit (0 when not settled)"),
    "converged": ("1", "steady state reached within the budget of periods (1) or not (0)"),
    "periods_run": ("1", "forcing periods integrated"),
    "error_estimate": ("1", "estimated relative error of power, v_peak, x_max and x_min: their "
                       "change when the run is repeated at twice the steps per period"),
    "steps_per_period": ("1", "RK4 steps per forcing period"),
    "run_time": ("s", "wall-clock integration time"),
}

#: Time series variables of a recorded orbit: name -> (column, CF units, long name).
SERIES: dict[str, tuple[int, str, str]] = {
    "displacement": (0, "m", "tip displacement relative to the base x"),
    "velocity": (1, "m/s", "tip velocity dx/dt"),
    "voltage": (2, "V", "voltage across the load V"),
    "contact_force": (3, "N", "contact force of the stop F_c"),
}

STATUS_FLAGS = {"flag_values": np.array([0, 1, 2, 3], dtype="i1"),
                "flag_meanings": "settled not_settled diverged too_stiff"}


def series_dataset(values: np.ndarray, t0: float, parameters: dict) -> xr.Dataset:
    """Dataset of a recorded series: columns (x, v, V, F_c) sampled every step from ``t0`` [s]."""
    n = values.shape[0]
    step = 1.0 / (parameters["frequency"] * parameters["steps_per_period"])
    time = t0 + step * np.arange(n)
    data = {
        name: ("time", values[:, col], {"units": units, "long_name": long})
        for name, (col, units, long) in SERIES.items()
    }
    data["instantaneous_power"] = ("time", values[:, 2] ** 2 / parameters["resistance"],
                     {"units": "W", "long_name": "instantaneous electrical power V^2/R"})
    coords = {"time": ("time", time, {"units": "s", "long_name": "time since the start"})}
    return xr.Dataset(data, coords=coords)


def scene_dataset(result, series: xr.Dataset) -> xr.Dataset:
    """One scene: its metrics (scalars), the series of its last orbit periods, its parameters."""
    ds = series.copy()
    for name, (units, long) in METRICS.items():
        value = result.metrics[name]
        attrs = {"units": units, "long_name": long}
        if name == "approach_velocity":
            attrs["comment"] = "NaN when the orbit has no impact (impacts_per_period = 0)"
        if name == "error_estimate":
            attrs["comment"] = "NaN when the point did not settle"
        ds[name] = ((), np.nan if value is None else float(value), attrs)
    code = ["settled", "not settled", "diverged", "too stiff"].index(result.metrics["status"])
    ds["status"] = ((), np.int8(code), {"units": "1", "long_name": "outcome of the run",
                                        **STATUS_FLAGS})
    ds.attrs.update(run_attributes(result.parameters, result.notes))
    return ds


def run_attributes(parameters: dict, notes) -> dict:
    """Global attributes: every input parameter (with its unit), notes, version and date."""
    from . import __version__

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
    """Write ``ds`` to ``path`` atomically: to a temporary name beside it, then renamed."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.part")
    ds.to_netcdf(tmp, engine="netcdf4")
    os.replace(tmp, path)
