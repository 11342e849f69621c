"""Figures drawn from the datasets (matplotlib, no display needed)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .outputs import OUTPUTS, STATUS_NAMES
from .parameters import PARAMETERS, ParameterError

_PREFIXES = [(1e-18, "a"), (1e-15, "f"), (1e-12, "p"), (1e-9, "n"), (1e-6, "\u00b5"),
             (1e-3, "m"), (1.0, ""), (1e3, "k")]


def _prefix(values: np.ndarray) -> tuple[float, str]:
    """Scale and SI prefix so that the largest |value| reads between 1 and 1000."""
    peak = float(np.nanmax(np.abs(values))) if np.size(values) else 0.0
    scale, prefix = 1.0, ""
    for factor, name in _PREFIXES:
        if peak >= factor:
            scale, prefix = factor, name
    return scale, prefix


def plot_scene(ds, path=None) -> Figure:
    """The four panels of the paper's Fig. 3 over the recorded forcing periods.

    (a) displacement with the stop marked (a moving stop's face g + x_s as it moves),
    (b) voltage, (c) instantaneous power, (d) contact force. ``ds`` is a scene dataset (see
    ``SceneResult.dataset``).
    """
    fig = Figure(figsize=(8, 9), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    t = (ds["time"].values - ds["time"].values[0]) * 1e3
    panels = [("displacement", "displacement", "m"), ("voltage", "voltage", "V"),
              ("instantaneous_power", "power", "W"), ("contact_force", "contact force", "N")]
    for ax, (name, label, unit), letter in zip(axes, panels, "abcd"):
        values = ds[name].values
        scale, prefix = _prefix(values)
        ax.plot(t, values / scale, lw=1.0)
        ax.set_ylabel(f"{label} [{prefix}{unit}]")
        ax.set_title(f"({letter}) {label}", loc="left", fontsize="medium")
        ax.grid(alpha=0.3)
        if name == "displacement":
            gap = float(ds.attrs["gap"])
            if isinstance(ds.attrs.get("stop_support_stiffness", "none"), str):  # rigid
                ax.axhline(gap / scale, color="C3", ls="--", lw=1.0,
                           label=f"stop (gap {gap:g} m)")
            else:
                ax.plot(t, (gap + ds["stop_displacement"].values) / scale, color="C3", lw=1.0,
                        label=f"moving stop's face g + x_s (gap {gap:g} m)")
            lower = ds.attrs.get("lower_gap", "none")
            if not isinstance(lower, str):  # (netCDF keeps an unset value as "none")
                ax.axhline(-float(lower) / scale, color="C2", ls="--", lw=1.0,
                           label=f"lower stop (lower_gap {float(lower):g} m)")
            ax.legend(loc="lower right", fontsize="small")
    axes[-1].set_xlabel(f"time from t = {float(ds['time'].values[0]):.4g} s [ms]")
    status = STATUS_NAMES[int(ds["status"])]
    fig.suptitle(
        f"f = {ds.attrs['frequency']:g} Hz, gap = {ds.attrs['gap']:g} m, "
        f"R = {ds.attrs['resistance']:g} Ohm: {status}, orbit period {int(ds['orbit_period'])}, "
        f"mean power {float(ds['power']):.3g} W"
    )
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig


_LINE_STYLES = {"up": dict(color="C0", ls="-", marker="^"), "down": dict(color="C3", ls="--",
                                                                        marker="v"),
                None: dict(color="C0", ls="-", marker=".")}


def plot_sweep(ds, path=None) -> Figure:
    """Draw what a sweep dataset holds (see ``run_sweep``).

    One grid axis: power [W] and x_max [m] against the axis, one curve per direction, with
    the closed-form response without the stop for comparison; bifurcation diagrams
    (stroboscopic x [m] and V [V] against the axis) when the dataset has ``sample``.
    Two grid axes: maps of the power [W] over the two axes, one per direction.

    Raises
    ------
    ParameterError
        For a dataset with more than two grid axes: select a slice first (``ds.isel``).
    """
    axes_names = [d for d in ds.dims if d not in ("direction", "sample", "multiplier")]
    if len(axes_names) == 1:
        return _save(_plot_lines(ds, axes_names[0]), path)
    if len(axes_names) == 2:
        return _save(_plot_maps(ds, axes_names), path)
    raise ParameterError(f"the dataset has {len(axes_names)} grid axes ({', '.join(axes_names)}): "
                         "plot draws one or two; select a slice first, e.g. ds.isel(gap=0)")


_BIFURCATION_MARKS = {"fold": dict(marker="o", color="C2"),
                      "period_doubling": dict(marker="s", color="C4"),
                      "neimark_sacker": dict(marker="D", color="C5"),
                      "grazing": dict(marker="*", color="C1", ms=10)}


def plot_branch(ds, path=None, sweeps=()) -> Figure:
    """A branch of orbits (``continue_branch``): x_max [m] and power [W] against the
    continued parameter, stable parts solid, unstable dashed, located bifurcations marked;
    over the up and down sweeps of ``sweeps`` (sweep datasets along the same parameter),
    when given.

    Raises
    ------
    ParameterError
        For a sweep that is not along the branch's parameter alone.
    """
    axis = ds.attrs["continued_parameter"]
    fig = Figure(figsize=(8, 7), layout="constrained")
    panels = fig.subplots(2, 1, sharex=True)
    lam = ds[axis].values
    stable = ds["stable"].values.astype(bool)
    branch = ds["branch"].values
    flags = ds["bifurcation"].attrs["flag_meanings"].split()
    for ax, name in zip(panels, ("x_max", "power")):
        scale, prefix = _prefix(ds[name].values) if name == "x_max" else (1.0, "")
        y = ds[name].values / scale
        for sweep in sweeps:
            dims = [d for d in sweep[name].dims if d != "direction"]
            if dims != [axis]:
                raise ParameterError(f"a sweep drawn under a branch must run along {axis} "
                                     f"alone (it runs along {', '.join(dims)})")
            for direction in _directions(sweep):
                values = sweep[name].sel(direction=direction) if direction else sweep[name]
                style = {**_LINE_STYLES[direction], "ls": "none"}
                ax.plot(sweep[axis].values, values / scale, ms=4, alpha=0.6,
                        label=f"sweep {direction or 'from rest'}", **style)
        # a piece of one branch and one stability, its end shared with the next piece
        cuts = np.flatnonzero((np.diff(stable.astype(int)) != 0) | (np.diff(branch) != 0)) + 1
        for start, stop in zip(np.r_[0, cuts], np.r_[cuts, len(lam)]):
            end = stop + 1 if stop < len(lam) and branch[stop] == branch[start] else stop
            ax.plot(lam[start:end], y[start:end], color="k", lw=1.2,
                    ls="-" if stable[start] else "--")
        ax.plot([], [], color="k", lw=1.2, label="stable")
        ax.plot([], [], color="k", lw=1.2, ls="--", label="unstable")
        for k, kind in enumerate(flags[1:], start=1):
            at = ds["bifurcation"].values == k
            if at.any():
                ax.plot(lam[at], y[at], ls="none", label=kind.replace("_", " "),
                        **{"ms": 7, **_BIFURCATION_MARKS[kind]})
        if name == "power":
            ax.set_yscale("log")
        elif "gap" in ds.attrs:
            ax.axhline(float(ds.attrs["gap"]) / scale, color="0.2", lw=0.8, ls="-.",
                       label="stop")
        ax.set_ylabel(_label(ds, name, prefix))
        ax.grid(alpha=0.3)
        ax.legend(fontsize="small")
    panels[-1].set_xlabel(_label(ds, axis))
    fig.suptitle(_title(ds, [axis]) + f": branch of {axis}")
    return _save(fig, path)


def plot_basins(ds, path=None) -> Figure:
    """Basins of attraction (a dataset of :mod:`harvester_sweep.basins`).

    Over two grid axes: a map of ``impact_basin_fraction``, the share of starts that land
    on an orbit striking the stop. Over one: that share with its standard error. At one
    point: each attractor's basin fraction, labelled with its impacts per period and power.
    """
    axes_names = ds.attrs["grid_axes"].split()
    fig = Figure(figsize=(7, 4.8), layout="constrained")
    ax = fig.subplots()
    name = "impact_basin_fraction"
    if len(axes_names) == 2:
        x_name, y_name = sorted(axes_names, key=lambda a: a != "frequency")  # frequency across
        scale, prefix = _prefix(ds[y_name].values)
        mesh = ax.pcolormesh(ds[x_name].values, ds[y_name].values / scale,
                             ds[name].transpose(y_name, x_name).values, vmin=0.0, vmax=1.0,
                             shading="nearest", cmap="viridis")
        fig.colorbar(mesh, ax=ax, label=_label(ds, name))
        ax.set_ylabel(_label(ds, y_name, prefix))
        _set_scale(ax, ds, y_name, "y")
    elif len(axes_names) == 1:
        x_name = axes_names[0]
        ax.errorbar(ds[x_name].values, ds[name].values, yerr=ds[name + "_error"].values,
                    marker="o", ms=3, capsize=2, lw=1.0)
        ax.set_ylim(-0.03, 1.03)
        ax.set_ylabel(_label(ds, name))
        ax.grid(alpha=0.3)
    elif not axes_names:
        x_name = None
        k = np.arange(1, ds.sizes["attractor"] + 1)
        ax.bar(k, ds["basin_fraction"].values, yerr=ds["basin_fraction_error"].values,
               capsize=3)
        ax.set_xticks(k, [f"{int(p)}T, {i:g} impacts/T\n{w:.3g} W" for p, i, w in zip(
            ds["orbit_period"].values, ds["impacts_per_period"].values, ds["power"].values)])
        ax.set_ylabel(_label(ds, "basin_fraction"))
        ax.set_ylim(0.0, 1.0)
    else:
        raise ParameterError(f"plot: basins over {len(axes_names)} grid axes; draw one or two "
                             "(select the others with xarray first)")
    if x_name is not None:
        ax.set_xlabel(_label(ds, x_name))
        _set_scale(ax, ds, x_name)
    starts = (f"base shock {ds.attrs['shock']:g} m/s" if "shock" in ds.attrs
              else "starts in a box around rest")
    ax.set_title(f"{ds.attrs['samples']} starts a point, {starts}", loc="left",
                 fontsize="medium")
    fig.suptitle(_title(ds, axes_names) + ": basins of attraction")
    return _save(fig, path)


def _save(fig: Figure, path) -> Figure:
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig


def _directions(ds) -> list:
    return [str(d) for d in ds["direction"].values] if "direction" in ds.dims else [None]


def _label(ds, name: str, prefix: str = "") -> str:
    """``name [unit]`` of an output (the registry's) or a grid axis (its parameter's)."""
    if name in OUTPUTS:
        return OUTPUTS[name].label(prefix)
    unit = PARAMETERS[name].unit if name in PARAMETERS else ds[name].attrs.get("units", "1")
    return f"{name} [{prefix}{'-' if unit == '1' else unit}]"


def _set_scale(ax, ds, name: str, axis: str = "x") -> None:
    if ds[name].attrs.get("grid_spacing") == "log":
        (ax.set_xscale if axis == "x" else ax.set_yscale)("log")


def _plot_lines(ds, axis: str) -> Figure:
    """Responses (and bifurcation diagrams) against one grid axis."""
    from .linear import linear_response

    responses = [name for name in ("power", "x_max") if name in ds]
    strobes = [name for name in ("strobe_displacement", "strobe_voltage") if name in ds]
    n = max(len(responses) + len(strobes), 1)
    fig = Figure(figsize=(8, 2.8 * n + 0.6), layout="constrained")
    panels = list(np.atleast_1d(fig.subplots(n, 1, sharex=True)))
    x = ds[axis].values
    point = {**{name: ds.attrs[name] for name in PARAMETERS if name in ds.attrs}, axis: x}
    X, V = linear_response(**point)
    linear = {"power": np.abs(V) ** 2 / (2 * point["resistance"]), "x_max": np.abs(X)}
    for ax, name in zip(panels, responses):
        scale, prefix = _prefix(ds[name].values) if name == "x_max" else (1.0, "")
        for direction in _directions(ds):
            values = ds[name].sel(direction=direction) if direction else ds[name]
            ax.plot(x, values / scale, ms=3, lw=1.0, label=f"{direction or 'from rest'}",
                    **_LINE_STYLES[direction])
        ax.plot(x, linear[name] / scale, color="0.4", lw=0.8, ls=":",
                label="no stop (closed form)")
        if name == "power":
            ax.set_yscale("log")
        else:
            top = np.nanmax(ds[name].values)
            if "gap" in ds.attrs:
                gap = float(ds.attrs["gap"])
                ax.axhline(gap / scale, color="0.2", lw=0.8, ls="-.", label="stop")
                top = max(top, gap)
            # From 0 to just above the data and the stop: the closed form peaks far higher.
            ax.set_ylim(min(0.0, np.nanmin(ds[name].values)) / scale, 1.15 * top / scale)
        ax.set_ylabel(_label(ds, name, prefix))
        ax.legend(fontsize="small")
    for ax, name in zip(panels[len(responses):], strobes):
        scale, prefix = _prefix(ds[name].values)
        for direction in _directions(ds):
            values = ds[name].sel(direction=direction) if direction else ds[name]
            xs = np.broadcast_to(x[:, None], values.shape)
            ax.plot(xs.ravel(), values.values.ravel() / scale, ls="none", marker=".", ms=2,
                    color=_LINE_STYLES[direction]["color"], alpha=0.5)
            ax.plot([], [], ls="none", marker="o", ms=3, label=direction or "from rest",
                    color=_LINE_STYLES[direction]["color"])
        ax.set_ylabel(f"{name.replace('strobe_', '')} y(nT) [{prefix}{ds[name].attrs['units']}]")
        ax.set_title(f"bifurcation diagram: last {ds.sizes['sample']} stroboscopic samples",
                     loc="left", fontsize="medium")
        ax.legend(fontsize="small", markerscale=1)
    for ax in panels:
        ax.grid(alpha=0.3)
        if ax.get_yscale() == "linear":
            ax.ticklabel_format(axis="y", useOffset=False)
        _set_scale(ax, ds, axis)
    panels[-1].set_xlabel(_label(ds, axis))
    fig.suptitle(_title(ds, [axis]))
    return fig


def _plot_maps(ds, axes_names: list) -> Figure:
    """Maps of the power (else the first metric held) over two grid axes."""
    from matplotlib.colors import LogNorm

    name = next((n for n in ("power", "x_max", "v_rms") if n in ds),
                next(n for n in ds.data_vars if "sample" not in ds[n].dims))
    x_name, y_name = sorted(axes_names, key=lambda a: a != "frequency")  # frequency across
    directions = _directions(ds)
    fig = Figure(figsize=(6 * len(directions), 4.8), layout="constrained")
    panels = np.atleast_1d(fig.subplots(1, len(directions), sharey=True))
    values = ds[name].values
    positive = values[np.isfinite(values) & (values > 0)]
    norm = LogNorm(positive.min(), positive.max()) if positive.size and name == "power" else None
    for ax, direction in zip(panels, directions):
        field = ds[name].sel(direction=direction) if direction else ds[name]
        mesh = ax.pcolormesh(ds[x_name].values, ds[y_name].values,
                             field.transpose(y_name, x_name).values, norm=norm, shading="nearest")
        ax.set_title(f"{name}: {direction or 'each point from rest'}", loc="left",
                     fontsize="medium")
        ax.set_xlabel(_label(ds, x_name))
        _set_scale(ax, ds, x_name)
        _set_scale(ax, ds, y_name, "y")
    panels[0].set_ylabel(_label(ds, y_name))
    fig.colorbar(mesh, ax=list(panels), label=_label(ds, name))
    fig.suptitle(_title(ds, axes_names))
    return fig


def _title(ds, axes_names: list) -> str:
    shown = [f"{n} = {ds.attrs[n]:g} {PARAMETERS[n].unit}" for n in ("gap", "resistance",
                                                                    "frequency")
             if n in ds.attrs and n not in axes_names and not isinstance(ds.attrs[n], str)]
    return f"preset {ds.attrs.get('preset', '?')}: " + ", ".join(shown)
