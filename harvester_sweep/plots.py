"""Figures drawn from the datasets (matplotlib, no display needed).

One display unit per quantity on every figure and title: lengths (gaps, x_max, x_min,
displacements) in um, other quantities with the SI prefix their values ask for (10 kOhm,
54 mN). A parameter whose values span two decades or more is drawn on a log axis (as is a
grid axis spaced ``log``); ``scales={"resistance": "linear"}`` (``--linear``, ``--log`` on
the command line) chooses otherwise.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

import numpy as np

from .materials import hertz_stiffness_from_bodies
from .outputs import BIFURCATIONS, ENGINE_METRICS, OUTPUTS, STATUS_NAMES
from .parameters import PARAMETERS, ParameterError

if TYPE_CHECKING:  # (matplotlib is imported where a figure is drawn: the command line's
    # tables format their numbers here without it)
    from matplotlib.figure import Figure

_PREFIXES = [(1e-18, "a"), (1e-15, "f"), (1e-12, "p"), (1e-9, "n"), (1e-6, "\u00b5"),
             (1e-3, "m"), (1.0, ""), (1e3, "k"), (1e6, "M"), (1e9, "G")]
#: Every length is shown in um: the gaps and swings of this harvester are microns, and one
#: unit for a quantity lets two figures (and a title and an axis) be read against each other.
_LENGTH = (1e-6, "\u00b5m")
#: Units shown with an SI prefix; the others (N/m^1.5, s/m, ...) with a plain exponent, as a
#: prefix on a compound unit reads ambiguously.
_PREFIXED = {"Hz", "Ohm", "F", "V", "W", "N", "s", "N/m"}
#: A parameter whose positive values span this ratio or more is drawn on a log axis.
_DECADES = 100.0


def _prefix(values) -> tuple[float, str]:
    """Scale and SI prefix so that the largest |value| reads between 1 and 1000."""
    values = np.asarray(values, dtype=float)
    finite = np.abs(values[np.isfinite(values)])
    peak = float(finite.max()) if finite.size else 0.0
    scale, prefix = 1.0, ""
    for factor, name in _PREFIXES:
        if peak >= factor:
            scale, prefix = factor, name
    return scale, prefix


def _display(unit: str, values=None) -> tuple[float, str]:
    """Scale and shown unit of a quantity in ``unit`` [SI]: it is drawn as values / scale.
    Lengths in um; ``values`` choose the prefix of a prefixed unit (none given: the SI unit)."""
    if unit == "m":
        return _LENGTH
    if unit == "kg" and values is not None:  # (the prefixes go on the gram)
        scale, prefix = _prefix(np.asarray(values, dtype=float) * 1e3)
        return scale * 1e-3, f"{prefix}g"
    if unit in _PREFIXED and values is not None:
        scale, prefix = _prefix(values)
        return scale, prefix + unit
    return 1.0, "-" if unit == "1" else unit


def quantity_text(value: float, unit: str, digits: int = 4) -> str:
    """A value [SI ``unit``] as figures and tables print it, in the one display unit of its
    quantity: ``10 kOhm``, ``1.32 um`` (every length), ``2.5 g``, ``9.03e+08 N/m^1.5``."""
    scale, shown = _display(unit, [value])
    text = f"{value / scale:.{digits}g}"
    return text if shown == "-" else f"{text} {shown}"


def _unit(ds, name: str) -> str:
    """The SI unit of an output (the registry's), a parameter or another variable."""
    if name in OUTPUTS:
        return OUTPUTS[name].units
    if name in PARAMETERS:
        return PARAMETERS[name].unit
    return ds[name].attrs.get("units", "1")


def _label(ds, name: str, shown: str | None = None) -> str:
    """``name [unit]``, in the unit it is drawn in (``shown``; default: the SI unit)."""
    return f"{name} [{shown or _display(_unit(ds, name))[1]}]"


def _axis(ds, name: str, values, log: bool = False) -> tuple[float, str]:
    """Scale and label of a quantity drawn on an axis (a log axis keeps the SI unit: its
    ticks are powers of ten)."""
    scale, shown = _display(_unit(ds, name), None if log else values)
    return scale, _label(ds, name, shown)


def _is_log(ds, name: str, values, scales) -> bool:
    """Whether ``name`` is drawn on a log axis: as ``scales`` says, else where the grid is
    spaced ``log`` or its positive values span two decades or more."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    choice = (scales or {}).get(name)
    if choice is not None:
        if choice not in ("log", "linear"):
            raise ParameterError(f"scale of {name}: {choice!r}; must be 'log' or 'linear'")
        if choice == "log" and values.size and values.min() <= 0:
            raise ParameterError(f"{name} cannot be drawn on a log axis: it takes values <= 0")
        return choice == "log"
    if name in ds.variables and ds[name].attrs.get("grid_spacing") == "log":
        return True
    return bool(values.size > 1 and values.min() > 0 and values.max() >= _DECADES * values.min())


def _check_scales(scales, names) -> None:
    unknown = sorted(set(scales or {}) - set(names))
    if unknown:
        raise ParameterError(f"a scale for {', '.join(unknown)}: the figure's axes are "
                             f"{', '.join(names)}")


def _edges(centres, log: bool) -> np.ndarray:
    """Cell edges around sorted ``centres``: halfway between neighbours (in log space on a
    log axis, so that each cell is centred on its value there), the end cells as wide as
    their neighbours' halves."""
    v = np.log10(centres) if log else np.asarray(centres, dtype=float)
    if v.size == 1:
        half = 0.5 if log else (0.5 * abs(v[0]) or 0.5)
        edges = np.array([v[0] - half, v[0] + half])
    else:
        mid = 0.5 * (v[1:] + v[:-1])
        edges = np.r_[2 * v[0] - mid[0], mid, 2 * v[-1] - mid[-1]]
    return 10.0 ** edges if log else edges


def _new_figure(figsize) -> Figure:
    """A figure with constrained layout on an Agg canvas (text extents are needed to place
    the bifurcation labels; ``savefig`` still writes .pdf or .svg by the name)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _suptitle(fig: Figure, text: str) -> None:
    """The figure's title, wrapped to its width (a long title was cut at both ends) between
    its items, never between a value and its unit."""
    width = max(int(fig.get_figwidth() * 72 / (0.62 * 12)), 30)  # characters of 12 pt
    lines = [""]
    for item in re.split(r"(?<=[,:]) ", text):
        if lines[-1] and len(lines[-1]) + 1 + len(item) > width:
            lines.append(item)
        else:
            lines[-1] = f"{lines[-1]} {item}" if lines[-1] else item
    fig.suptitle("\n".join(lines))


def plot_scene(ds, path=None) -> Figure:
    """The four panels of the paper's Fig. 3 over the recorded forcing periods.

    (a) displacement [um] with the stop marked (a moving stop's face g + x_s as it moves;
    a lower stop at -lower_gap), (b) voltage, (c) instantaneous power, (d) contact force.
    ``ds`` is a scene dataset (see ``SceneResult.dataset``).
    """
    fig = _new_figure((8, 9.4))
    axes = fig.subplots(4, 1, sharex=True)
    t = (ds["time"].values - ds["time"].values[0]) * 1e3
    panels = [("displacement", "displacement", "m"), ("voltage", "voltage", "V"),
              ("instantaneous_power", "power", "W"), ("contact_force", "contact force", "N")]
    for ax, (name, label, unit), letter in zip(axes, panels, "abcd"):
        values = ds[name].values
        scale, shown = _display(unit, values)
        ax.plot(t, values / scale, lw=1.0)
        ax.set_ylabel(f"{label} [{shown}]")
        ax.set_title(f"({letter}) {label}", loc="left", fontsize="medium")
        ax.grid(alpha=0.3)
        if name == "displacement":
            gap = float(ds.attrs["gap"])
            if isinstance(ds.attrs.get("stop_support_stiffness", "none"), str):  # rigid
                ax.axhline(gap / scale, color="C3", ls="--", lw=1.0,
                           label=f"stop (gap {quantity_text(gap, 'm')})")
            else:
                ax.plot(t, (gap + ds["stop_displacement"].values) / scale, color="C3", lw=1.0,
                        label=f"moving stop's face g + x_s (gap {quantity_text(gap, 'm')})")
            lower = ds.attrs.get("lower_gap", "none")
            if not isinstance(lower, str):  # (netCDF keeps an unset value as "none")
                ax.axhline(-float(lower) / scale, color="C2", ls="--", lw=1.0,
                           label=f"lower stop (lower_gap {quantity_text(float(lower), 'm')})")
            # above the panel, right of its title: inside, it covered the orbit's swings
            ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncols=2,
                      fontsize="small", frameon=False, borderaxespad=0.1)
    axes[-1].set_xlabel(f"time from t = {float(ds['time'].values[0]):.4g} s [ms]")
    status = STATUS_NAMES[int(ds["status"])]
    _suptitle(fig, f"{_title(ds, [])}: {status}, orbit period {int(ds['orbit_period'])}, "
                   f"mean power {quantity_text(float(ds['power']), 'W', 3)}")
    return _save(fig, path)


_LINE_STYLES = {"up": dict(color="C0", ls="-", marker="^"), "down": dict(color="C3", ls="--",
                                                                        marker="v"),
                None: dict(color="C0", ls="-", marker=".")}
#: Stroboscopic dots: down as open rings under the up dots (drawn last, smaller, filled), so
#: that where the two directions agree both are seen (the down dots used to cover the up).
_DOTS = {"down": dict(marker="o", ms=4.5, mfc="none", mew=0.8, color="C3", zorder=2),
         "up": dict(marker="o", ms=2.0, color="C0", zorder=3),
         None: dict(marker="o", ms=2.0, color="C0", zorder=3)}


def plot_sweep(ds, path=None, scales=None) -> Figure:
    """Draw what a sweep dataset holds (see ``run_sweep``).

    One grid axis: power [W] and x_max [um] against the axis, one curve per direction, with
    the closed-form response without the stop for comparison; bifurcation diagrams
    (stroboscopic x [um] and V against the axis) when the dataset has ``sample``.
    Two grid axes: maps of the power [W] over the two axes, one per direction, each cell
    centred on its grid value (in log space on a log axis).

    ``scales``: ``{axis: "log" or "linear"}`` for a grid axis; by default log where the
    grid is spaced ``log`` or spans two decades or more.

    Raises
    ------
    ParameterError
        For a dataset with more than two grid axes: select a slice first (``ds.isel``); for
        a scale of an axis the figure does not have, or log of values <= 0.
    """
    axes_names = [d for d in ds.dims if d not in ("direction", "sample", "multiplier")]
    _check_scales(scales, axes_names)
    if len(axes_names) == 1:
        return _save(_plot_lines(ds, axes_names[0], scales), path)
    if len(axes_names) == 2:
        return _save(_plot_maps(ds, axes_names, scales), path)
    raise ParameterError(f"the dataset has {len(axes_names)} grid axes ({', '.join(axes_names)}): "
                         f"plot draws one or two; {_slice_advice(axes_names)}")


def _slice_advice(axes_names: list) -> str:
    """How to cut a dataset of too many grid axes down, naming one of its own axes."""
    return (f"select a slice first with xarray, e.g. ds.isel({axes_names[-1]}=0), and "
            "write it with to_netcdf")


#: Marker of each kind of bifurcation; the larger are drawn first, under the smaller, so
#: that two at nearly one place (the paper S-curve's lower fold, 0.1 Hz from its grazing)
#: both show.
_BIFURCATION_MARKS = {"fold": dict(marker="o", color="C2", ms=7),
                      "period_doubling": dict(marker="s", color="C4", ms=7),
                      "neimark_sacker": dict(marker="D", color="C5", ms=7),
                      "grazing": dict(marker="*", color="C1", ms=14)}
_SHORT = {"fold": "fold", "period_doubling": "PD", "neimark_sacker": "NS", "grazing": "grazing"}
#: Relative width in the parameter (of the larger of the value and the range) a bracket
#: may have for its bifurcation to count as located: the precision asked of a location.
#: Continuation brackets to continuation.LOCATE, 1e-8, where its corrections converge (a
#: test checks it is finer); a wider bracket means the location failed (a correction inside
#: it did not converge, the whole step is its bracket): the bifurcation is somewhere in it,
#: not at its point.
_LOCATED = 1e-6


def bifurcation_points(ds) -> list[dict]:
    """The bifurcations flagged on a branch dataset (``continue_branch``), in its order.

    Each a dict: ``index`` (its point), ``kind`` (fold, period_doubling, neimark_sacker,
    grazing), ``stop`` (a grazing's stop: "upper" or "lower"; else None), ``value`` (the
    parameter at the point), ``located`` (whether its bracket is within ``_LOCATED`` of
    the parameter: the location converged), ``low`` and ``high`` (the interval in the
    parameter that holds it: the value +- the bracket's width, ``<parameter>_precision``).
    """
    name = ds.attrs["continued_parameter"]
    lam = ds[name].values
    flags = ds["bifurcation"].values
    kinds = ds["bifurcation"].attrs["flag_meanings"].split()
    width = ds[f"{name}_precision"].values
    span = abs(float(ds.attrs["stop"]) - float(ds.attrs["start"]))
    upper, lower = _stops(ds, name, lam)
    found = []
    for i in np.flatnonzero(flags):
        kind = kinds[int(flags[i])]
        located = width[i] <= _LOCATED * max(abs(lam[i]), span)
        # The point lies in the bracket, or (a failed location) is the end of the step that
        # holds the bifurcation, whose scaled arclength is the width: either way the
        # bifurcation is within the width of the point.
        low, high = lam[i] - width[i], lam[i] + width[i]
        stop = None
        if kind == "grazing":
            stop = "upper"
            if lower is not None:  # the nearer of the two stops' grazing conditions
                lower_miss = abs(ds["x_min"].values[i] - lower[i])
                upper_miss = np.inf if upper is None else abs(ds["x_max"].values[i] - upper[i])
                stop = "lower" if lower_miss < upper_miss else "upper"
        found.append(dict(index=int(i), kind=kind, stop=stop, value=float(lam[i]),
                          located=bool(located), low=float(low), high=float(high)))
    return found


def _bifurcation_texts(found: list, unit: str) -> list[str]:
    """Each bifurcation's label, with as many digits as tell the values apart: ``fold
    218.58 Hz``; ``fold, not located: 227.0 to 234.5 Hz``."""
    values = [b["value"] for b in found if b["located"]]
    digits = 5
    while digits < 10 and len({f"{v:.{digits}g}" for v in values}) < len(
            set(np.round(values, 12))):
        digits += 1
    texts = []
    for b in found:
        kind = _SHORT[b["kind"]] + (" (lower stop)" if b["stop"] == "lower" else "")
        if b["located"]:
            texts.append(f"{kind} {quantity_text(b['value'], unit, digits)}")
        else:
            scale, shown = _display(unit, [b["low"], b["high"]])
            texts.append(f"{kind}, not located: {b['low'] / scale:.4g} to "
                         f"{b['high'] / scale:.4g} {shown}")
    return texts


def plot_branch(ds, path=None, sweeps=(), scales=None) -> Figure:
    """A branch of orbits (``continue_branch``): x_max [um] (and x_min where a lower stop
    exists) and power [W] against the continued parameter, stable parts solid, unstable
    dashed, each bifurcation marked and labelled with its kind and value (one whose location
    failed: with its bracket, drawn as a bar); over the up and down sweeps of ``sweeps``
    (sweep datasets along the same parameter), when given. A lower stop's grazing is drawn
    on x_min, against the lower stop.

    ``scales``: ``{parameter: "log" or "linear"}``; by default log where the branch, or the
    range asked of it, spans two decades or more.

    Raises
    ------
    ParameterError
        For a sweep that is not along the branch's parameter alone; for a scale of another
        axis, or log of values <= 0.
    """
    axis = ds.attrs["continued_parameter"]
    _check_scales(scales, [axis])
    for sweep in sweeps:
        check_over(ds, sweep)
    upper, lower = _stops(ds, axis, ds[axis].values)
    names = ["x_max"] + (["x_min"] if lower is not None else []) + ["power"]
    fig = _new_figure((9, 3.2 * len(names) + 0.6))
    panels = fig.subplots(len(names), 1, sharex=True)
    lam = ds[axis].values
    # (the range asked for counts too: a branch asked from 100 Ohm to 10 MOhm reads on a
    # log axis even where it ended early)
    asked = np.r_[lam, float(ds.attrs["start"]), float(ds.attrs["stop"])]
    log = _is_log(ds, axis, asked, scales)
    x_scale, x_label = _axis(ds, axis, lam, log)
    x = lam / x_scale
    stable = ds["stable"].values.astype(bool)
    branch = ds["branch"].values
    found = bifurcation_points(ds)
    texts = _bifurcation_texts(found, _unit(ds, axis))
    ys = {}
    for ax, name in zip(panels, names):
        log_y = name == "power"
        scale, y_label = _axis(ds, name, ds[name].values, log_y)
        y = ys[name] = ds[name].values / scale
        for sweep in (sweep for sweep in sweeps if name in sweep):  # (x_min if it was asked)
            for direction in _directions(sweep):
                values = sweep[name].sel(direction=direction) if direction else sweep[name]
                ax.plot(sweep[axis].values / x_scale, values / scale, ls="none", alpha=0.7,
                        label=f"sweep {direction or 'from rest'}", **_DOTS[direction])
        # a piece of one branch and one stability, its end shared with the next piece
        cuts = np.flatnonzero((np.diff(stable.astype(int)) != 0) | (np.diff(branch) != 0)) + 1
        for start, stop in zip(np.r_[0, cuts], np.r_[cuts, len(lam)]):
            end = stop + 1 if stop < len(lam) and branch[stop] == branch[start] else stop
            ax.plot(x[start:end], y[start:end], color="k", lw=1.2, zorder=3.5,  # (over dots)
                    ls="-" if stable[start] else "--")
        ax.plot([], [], color="k", lw=1.2, label="stable")
        ax.plot([], [], color="k", lw=1.2, ls="--", label="unstable")
        if name == "x_max":
            _stop_line(ax, x, upper, y, "stop"
                       + ("" if isinstance(ds.attrs.get("stop_support_stiffness", "none"), str)
                          else " at rest"))
        elif name == "x_min":
            _stop_line(ax, x, lower, y, "lower stop")
        shown = [k for k, b in enumerate(found) if _on_panel(b, name)]
        _mark_bifurcations(ax, [found[k] for k in shown], x, y, x_scale)
        ax.set_yscale("log" if log_y else "linear")
        ax.set_ylabel(y_label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    panels[-1].set_xlabel(x_label)
    for ax in panels:
        ax.set_xscale("log" if log else "linear")
        _no_offset(ax)
    _suptitle(fig, _title(ds, [axis]) + f": branch of {axis}")
    # labels last, where the layout has put the panels: each on the first panel that marks it
    labelled = set()
    for ax, name in zip(panels, names):
        items = []
        for k, b in enumerate(found):
            if _on_panel(b, name) and k not in labelled:
                labelled.add(k)
                items.append((x[b["index"]], ys[name][b["index"]], texts[k]))
        _label_points(ax, items)
    return _save(fig, path)


def dataset_kind(ds) -> str:
    """What a dataset of this tool is, as a message names it."""
    model = "beam " if ds.attrs.get("model") == "beam" else ""
    if "point" in ds.dims:
        return f"a {model}branch (of 'continue')"
    if "time" in ds.dims:
        return f"a {model}scene"
    if "attractor" in ds.dims:
        return f"{model}basins of attraction (of 'basins')"
    return f"a {model}sweep"


def check_over(branch, sweep) -> None:
    """Refuse a dataset that cannot be drawn under ``branch`` (``plot_branch``'s
    ``sweeps``): anything but a sweep, a sweep of another model or preset (its orbits are
    another harvester's, drawn on the branch's axes without a word), and one that does not
    run along the branch's parameter alone.

    Raises
    ------
    ParameterError
        Saying what ``sweep`` is and why it is not drawn.
    """
    axis = branch.attrs["continued_parameter"]
    kind = dataset_kind(sweep)
    if kind not in ("a sweep", "a beam sweep"):
        raise ParameterError(f"{kind}, not a sweep: a branch is drawn over sweeps (of 'run') "
                             f"along {axis}")
    # (a file without the attribute is the tip-mass model's: sweep_file.MODELS' default)
    models = [f.attrs.get("model", "tip_mass") for f in (sweep, branch)]
    if models[0] != models[1]:
        raise ParameterError(f"a sweep of the {models[0]} model, the branch is of the "
                             f"{models[1]} model: not drawn under it")
    presets = [f.attrs.get("preset") for f in (sweep, branch)]
    if all(isinstance(p, str) for p in presets) and presets[0] != presets[1]:
        raise ParameterError(f"a sweep of preset {presets[0]}, the branch is of preset "
                             f"{presets[1]}: not drawn under it")
    dims = [d for d in sweep.dims if d not in ("direction", "sample", "multiplier")]
    if dims != [axis]:
        along = ", ".join(dims) if dims else "no grid axis: a single point"
        raise ParameterError(f"a sweep drawn under a branch must run along {axis} alone "
                             f"(it runs along {along})")


def _on_panel(b: dict, name: str) -> bool:
    """Whether bifurcation ``b`` is drawn on the panel of ``name``: a grazing on the panel
    of its stop's extreme (x_max: upper, x_min: lower) and on power; the others on all."""
    if b["kind"] != "grazing" or name == "power":
        return True
    return (name == "x_min") == (b["stop"] == "lower")


def _stops(ds, axis: str, values) -> tuple:
    """The stops' levels [m] at each of ``values`` of ``axis``: the upper stop's at gap, the
    lower's at -lower_gap (where the axis is a gap, its values), None for a stop not set."""
    def level(name):
        if name == axis:
            return np.asarray(values, dtype=float)
        value = _fixed(ds).get(name, "none")
        return None if isinstance(value, str) else np.full(np.shape(values), float(value))

    upper, lower = level("gap"), level("lower_gap")
    return upper, None if lower is None else -lower


def _stop_line(ax, x, level, y, label: str) -> bool:
    """A stop's levels [m] (``_stops``) as a dash-dot line over lengths ``y`` [um] against
    ``x``, where the orbits come within reach of it (a stop set out of the way, gap = 1 m,
    would squash the panel): whether it was drawn."""
    if level is None:
        return False
    level = level / _LENGTH[0]
    finite = np.abs(y[np.isfinite(y)])
    drawn = bool(finite.size and np.nanmax(np.abs(level)) <= 3 * finite.max())
    if drawn and np.ptp(level) == 0:
        ax.axhline(level[0], color="0.2", lw=0.8, ls="-.", label=label)
    elif drawn:  # (along a gap axis the stop is the diagonal x = gap)
        order = np.argsort(x)
        ax.plot(np.asarray(x)[order], level[order], color="0.2", lw=0.8, ls="-.", label=label)
    return drawn


def _mark_bifurcations(ax, found: list, x, y, x_scale: float) -> None:
    """Each bifurcation's marker, the larger first (under the smaller); one whose location
    failed as an open marker on a bar over its bracket."""
    for kind in _BIFURCATION_MARKS:
        if any(b["kind"] == kind for b in found):
            style = _BIFURCATION_MARKS[kind]
            ax.plot([], [], ls="none", label=kind.replace("_", " "), **style)
    if not all(b["located"] for b in found):
        ax.plot([], [], color="0.5", lw=4, alpha=0.45, label="not located: its bracket")
    order = sorted(found, key=lambda b: -_BIFURCATION_MARKS[b["kind"]]["ms"])
    for z, b in enumerate(order):
        i, style = b["index"], dict(_BIFURCATION_MARKS[b["kind"]])
        if not b["located"]:
            ax.plot([b["low"] / x_scale, b["high"] / x_scale], [y[i], y[i]], color=style["color"],
                    lw=4, alpha=0.45, solid_capstyle="butt", zorder=4 + z, gid="bracket")
            style["mfc"] = "none"
        ax.plot([x[i]], [y[i]], ls="none", zorder=4 + len(order) + z,
                gid=f"bifurcation {b['kind']}", **style)


def _label_points(ax, items: list) -> None:
    """Label points ``(x, y, text)`` (data coordinates) with their texts, each placed, by a
    line to its point, where it overlaps no other label and no marker, stays inside the
    panel and, where it can, off the curves: near points are told apart, none hidden."""
    if not items:
        return
    fig = ax.figure
    fig.draw_without_rendering()  # (the constrained layout places the panels)
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    px = fig.dpi / 72.0
    points = [ax.transData.transform((x, y)) for x, y, _ in items]
    taken = [_box(p, 7 * px) for p in points if np.all(np.isfinite(p))]
    curves = [_along(line.get_transform().transform(line.get_xydata()), 4 * px)
              for line in ax.get_lines() if len(line.get_xydata())]
    curves = np.concatenate(curves) if curves else np.empty((0, 2))
    candidates = [(sx * 10, sy * (8 + 15 * k)) for k in range(10) for sy in (1, -1)
                  for sx in (1, -1)]
    for (x, y, text), _ in sorted(zip(items, points), key=lambda item: item[1][0]):
        if not (np.isfinite(x) and np.isfinite(y)):
            continue
        label = ax.annotate(text, (x, y), xytext=(10, 8), textcoords="offset points",
                            fontsize="small", gid="bifurcation label",
                            arrowprops=dict(arrowstyle="-", lw=0.6, color="0.3", shrinkA=0,
                                            shrinkB=3),
                            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none",
                                      alpha=0.8))
        label.set_in_layout(False)
        best = None
        for dx, dy in candidates:
            label.xyann = (dx, dy)
            label.set_horizontalalignment("left" if dx > 0 else "right")
            label.set_verticalalignment("bottom" if dy > 0 else "top")
            extent = _text_extent(label, renderer)
            inside = ((curves[:, 0] > extent.x0) & (curves[:, 0] < extent.x1)
                      & (curves[:, 1] > extent.y0) & (curves[:, 1] < extent.y1))
            cost = sum(_overlap(extent, other) for other in taken) + 1e3 * (
                extent.width * extent.height - _overlap(extent, frame)) + 20 * inside.sum()
            if best is None or cost < best[0]:
                best = (cost, dx, dy)
            if cost == 0:
                break
        _, dx, dy = best
        label.xyann = (dx, dy)
        label.set_horizontalalignment("left" if dx > 0 else "right")
        label.set_verticalalignment("bottom" if dy > 0 else "top")
        taken.append(_text_extent(label, renderer))


def _along(path, spacing: float) -> np.ndarray:
    """Points every ``spacing`` [px] along a polyline (display coordinates), so that a
    straight line of two points (a stop's level) counts along its length."""
    path = path[np.all(np.isfinite(path), axis=1)]
    if len(path) < 2:
        return path
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(path, axis=0).T))]
    at = np.arange(0.0, s[-1] + spacing, spacing)
    return np.column_stack([np.interp(at, s, path[:, 0]), np.interp(at, s, path[:, 1])])


def _text_extent(label, renderer):
    """The window extent of an annotation's text alone (its line to the point left out)."""
    from matplotlib.text import Text

    label.update_positions(renderer)
    return Text.get_window_extent(label, renderer)


def _box(centre, half):
    from matplotlib.transforms import Bbox

    return Bbox.from_extents(centre[0] - half, centre[1] - half, centre[0] + half,
                             centre[1] + half)


def _overlap(a, b) -> float:
    """Area [px^2] two boxes share."""
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return max(w, 0.0) * max(h, 0.0)


def plot_basins(ds, path=None, scales=None) -> Figure:
    """Basins of attraction (a dataset of :mod:`harvester_sweep.basins`).

    Over two grid axes: a map of ``impact_basin_fraction``, the share of starts that land
    on an orbit striking the stop. Over one: that share with its standard error. At one
    point: each attractor's basin fraction, labelled with its impacts per period and power.
    ``scales`` as for :func:`plot_sweep`. The grid axes are the data's dimensions (a
    dataset sliced with ``ds.isel`` keeps the ``grid_axes`` attribute of its whole grid).
    """
    name = "impact_basin_fraction"
    axes_names = [d for d in ds[name].dims if d != "attractor"]
    _check_scales(scales, axes_names)
    if len(axes_names) > 2:
        raise ParameterError(f"basins over {len(axes_names)} grid axes "
                             f"({', '.join(axes_names)}): plot draws one or two; "
                             f"{_slice_advice(axes_names)}")
    fig = _new_figure((7, 4.8))
    ax = fig.subplots()
    if len(axes_names) == 2:
        x_name, y_name = sorted(axes_names, key=lambda a: a != "frequency")  # frequency across
        mesh = _mesh(ax, ds, ds[name], x_name, y_name, scales, vmin=0.0, vmax=1.0,
                     cmap="viridis")
        fig.colorbar(mesh, ax=ax, label=_label(ds, name))
    elif len(axes_names) == 1:
        x_name = axes_names[0]
        values = ds[x_name].values
        log = _is_log(ds, x_name, values, scales)
        scale, label = _axis(ds, x_name, values, log)
        ax.errorbar(values / scale, ds[name].values, yerr=ds[name + "_error"].values,
                    marker="o", ms=3, capsize=2, lw=1.0)
        lost = ~np.isfinite(ds[name].values)  # (no start reached an orbit: unknown)
        if lost.any():
            _at_foot(ax, values[lost] / scale, ls="none", marker="x", color="k",
                     gid="no orbit", label=f"no start reached an orbit ({int(lost.sum())})")
            ax.legend(fontsize="small")
        ax.set_ylim(-0.03, 1.03)
        ax.set_ylabel(_label(ds, name))
        ax.set_xlabel(label)
        ax.set_xscale("log" if log else "linear")
        ax.grid(alpha=0.3)
    elif not axes_names:
        # (a point sliced from a map keeps the map's attractor slots; those its starts did
        # not reach are NaN there)
        ds = ds.isel(attractor=np.flatnonzero(np.isfinite(ds["basin_fraction"].values)))
        k = np.arange(1, ds.sizes["attractor"] + 1)
        ax.bar(k, ds["basin_fraction"].values, yerr=ds["basin_fraction_error"].values,
               capsize=3)
        ax.set_xticks(k, [f"{int(p)}T, {i:g} impacts/T\n{quantity_text(w, 'W', 3)}" for p, i, w in
                          zip(ds["orbit_period"].values, ds["impacts_per_period"].values,
                              ds["power"].values)])
        ax.set_ylabel(_label(ds, "basin_fraction"))
        ax.set_ylim(0.0, 1.0)
    if not np.isfinite(ds[name].values).any():
        lost = [f"{float(np.max(ds[what].values)):.0%} {what.replace('fraction_', '')}"
                .replace("_", " ") for what in ("fraction_not_settled", "fraction_diverged")
                if float(np.max(ds[what].values)) > 0]
        _panel_note(ax, "no start reached an orbit" + (f": up to {', '.join(lost)}"
                                                        if lost else ""))
    _no_offset(ax)
    starts = (f"base shock {ds.attrs['shock']:g} m/s" if "shock" in ds.attrs
              else "starts in a box around rest")
    ax.set_title(f"{ds.attrs['samples']} starts a point, {starts}", loc="left",
                 fontsize="medium")
    _suptitle(fig, _title(ds, axes_names) + ": basins of attraction")
    return _save(fig, path)


def _save(fig: Figure, path) -> Figure:
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig


def _directions(ds) -> list:
    return [str(d) for d in ds["direction"].values] if "direction" in ds.dims else [None]


def _no_offset(ax) -> None:
    """No offset ("+2.1e2") over a linear axis's tick labels; the display units keep the
    lengths and prefixed quantities free of a "1e-6" multiplier."""
    from matplotlib.ticker import ScalarFormatter

    for axis in (ax.xaxis, ax.yaxis):
        if isinstance(axis.get_major_formatter(), ScalarFormatter):
            axis.get_major_formatter().set_useOffset(False)


#: The metrics a sweep stores whatever its outputs (sweep_file.ALWAYS_STORED): never drawn
#: as a response of their own (status marks the points instead).
_BOOKKEEPING = ("status", "periods_run")


def _line_outputs(ds) -> tuple[list, list]:
    """The responses and the stroboscopic samples drawn against one grid axis: power and
    x_max where the file holds them, else each metric it holds (a sweep asked for v_rms
    alone drew an empty frame); orbit_period comes with the samples and is not drawn."""
    strobes = [name for name in ("strobe_displacement", "strobe_voltage") if name in ds]
    responses = [name for name in ("power", "x_max") if name in ds]
    if not responses:
        skip = _BOOKKEEPING + (("orbit_period",) if strobes else ())
        responses = [name for name in ENGINE_METRICS if name in ds and name not in skip]
    if not responses and not strobes:
        raise ParameterError("the sweep holds no output plot draws: it needs a metric "
                             '(power, x_max, v_rms, ...) or "strobe" in sweep.outputs')
    return responses, strobes


def _say_no_value(ax, ds, name: str) -> None:
    """Where no point has a value of ``name`` (all NaN), say so across the panel, with the
    points' statuses (as the markers at its foot count them), else why the registry leaves
    it NaN: an empty frame read as a plot that failed."""
    if np.isfinite(ds[name].values).any():
        return
    status = ds["status"].values if "status" in ds else np.zeros(0)
    unsettled = [(s, int(np.sum(status == STATUS_NAMES.index(s)))) for s in _UNSETTLED]
    said = ", ".join(f"{s} ({count} of {status.size})" for s, count in unsettled if count)
    why = said or (OUTPUTS[name].comment if name in OUTPUTS else "")
    _panel_note(ax, f"no point has a value of {name}" + (f": {why}" if why else ""))


def _panel_note(ax, text: str) -> None:
    """``text`` across the middle of panel ``ax``: why it holds no data (gid "no value")."""
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", wrap=True,
            gid="no value", bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="none",
                                      alpha=0.8))


def _at_foot(ax, x, **style) -> None:
    """Markers at ``x`` (data units) at the foot of panel ``ax``: points with no value to
    be drawn at, placed along the axis all the same."""
    ax.plot(x, np.full(len(x), 0.04), transform=ax.get_xaxis_transform(), **style)


def _plot_lines(ds, axis: str, scales=None) -> Figure:
    """Responses (and bifurcation diagrams) against one grid axis."""
    from .linear import linear_response

    responses, strobes = _line_outputs(ds)
    n = len(responses) + len(strobes)
    fig = _new_figure((8, 2.8 * n + 0.6))
    panels = list(np.atleast_1d(fig.subplots(n, 1, sharex=True)))
    values = ds[axis].values
    log = _is_log(ds, axis, values, scales)
    x_scale, x_label = _axis(ds, axis, values, log)
    x = values / x_scale
    point = {**{name: value for name, value in _fixed(ds).items() if name in PARAMETERS},
             axis: values}
    X, V = linear_response(**point)
    power = np.abs(V) ** 2 / (2 * point["resistance"])
    linear = {"power": power, "power_peak": 2 * power, "v_rms": np.abs(V) / np.sqrt(2),
              "v_peak": np.abs(V), "x_max": np.abs(X), "x_min": -np.abs(X)}
    linear = {k: np.broadcast_to(v, x.shape) for k, v in linear.items()}  # (an axis it
    # does not depend on, the gap: one value)
    for ax, name in zip(panels, responses):
        log_y = name in ("power", "power_peak")
        scale, y_label = _axis(ds, name, ds[name].values, log_y)
        for direction in _directions(ds):
            data = ds[name].sel(direction=direction) if direction else ds[name]
            ax.plot(x, data / scale, ms=3, lw=1.0, label=f"{direction or 'from rest'}",
                    **_LINE_STYLES[direction])
            if "status" in ds:
                status = ds["status"].sel(direction=direction) if direction else ds["status"]
                _mark_unsettled(ax, status.values, x, data.values / scale, legend=False,
                                where=direction or "")
        if name in linear:
            ax.plot(x, linear[name] / scale, color="0.4", lw=0.8, ls=":",
                    label="no stop (closed form)")
        y = ds[name].values / scale
        finite = y[np.isfinite(y)]
        _say_no_value(ax, ds, name)
        if log_y:
            ax.set_yscale("log")
        elif finite.size:  # (none, every point too stiff: matplotlib's limits, NaN-free)
            low, top = min(0.0, finite.min()), max(0.0, finite.max())
            upper = _stops(ds, axis, values)[0]
            if name == "x_max" and _stop_line(ax, x, upper, y, "stop"):
                top = max(top, np.nanmax(upper) / scale)
            # From 0 to just beyond the data and the stop: the closed form peaks far higher.
            pad = 0.15 * (top - low)
            if pad > 0:  # (all zero, no impacts: matplotlib's own limits)
                ax.set_ylim(low - pad if low < 0 else low, top + pad if top > 0 else top)
        ax.set_ylabel(y_label)
        ax.legend(fontsize="small")
    for ax, name in zip(panels[len(responses):], strobes):
        scale, shown = _display(_unit(ds, name), ds[name].values)
        for direction in sorted(_directions(ds), key=lambda d: d != "down"):  # down first
            data = ds[name].sel(direction=direction) if direction else ds[name]
            xs = np.broadcast_to(x[:, None], data.shape)
            ax.plot(xs.ravel(), data.values.ravel() / scale, ls="none", alpha=0.8,
                    gid=f"strobe {direction or 'from rest'}", **_DOTS[direction])
            ax.plot([], [], ls="none", label=direction or "from rest",
                    **{**_DOTS[direction], "ms": 4.5})
        _say_no_value(ax, ds, name)
        ax.set_ylabel(f"{name.replace('strobe_', '')} y(nT) [{shown}]")
        ax.set_title(f"bifurcation diagram: last {ds.sizes['sample']} stroboscopic samples",
                     loc="left", fontsize="medium")
        ax.legend(fontsize="small", markerscale=1)
    for ax in panels:
        ax.grid(alpha=0.3)
        ax.set_xscale("log" if log else "linear")
        _no_offset(ax)
    panels[-1].set_xlabel(x_label)
    _suptitle(fig, _title(ds, [axis]))
    return fig


def _mesh(ax, ds, field, x_name: str, y_name: str, scales, status=None, **style):
    """``field`` over two grid axes as cells centred on the grid values (in log space on a
    log axis), the axes in their display units and scales; with ``status`` (the same
    grid's), the cells that are not a steady state marked (_mark_unsettled)."""
    field = field.sortby([x_name, y_name]).transpose(y_name, x_name)
    axes, centres = [], []
    for name, which in ((x_name, "x"), (y_name, "y")):
        values = field[name].values
        log = _is_log(ds, name, values, scales)
        scale, label = _axis(ds, name, values, log)
        getattr(ax, f"set_{which}label")(label)
        getattr(ax, f"set_{which}scale")("log" if log else "linear")
        axes.append(_edges(values, log) / scale)
        centres.append(values / scale)
    mesh = ax.pcolormesh(axes[0], axes[1], field.values, shading="flat", **style)
    if status is not None:
        status = status.sortby([x_name, y_name]).transpose(y_name, x_name)
        _mark_unsettled(ax, status.values, centres[0][None, :], centres[1][:, None])
    return mesh


#: How a map or a curve marks its points that are not a steady state, by status name.
_UNSETTLED = {"not settled": "x", "diverged": "+", "too stiff": "1"}


def _mark_unsettled(ax, status, x, y, legend: bool = True, where: str = "") -> None:
    """Mark the points whose ``status`` (numbers of the registry) is not "settled" at
    display coordinates ``x``, ``y`` (arrays of its shape): a marker per status, black
    on a white edge so that it reads on any colour, counted in the legend (drawn here
    when ``legend``; ``where``: a direction, said with the count). A reader must see which
    values are not a steady state's (a not-settled point's metrics are its last
    periods'). A point with no value there (NaN: too stiff, diverged) is marked at the
    foot of the panel, at its place along the x axis: it has no height to be drawn at."""
    from matplotlib import patheffects

    status = np.asarray(status)
    x, y = (np.broadcast_to(v, status.shape) for v in (x, y))
    marked = False
    for name, marker in _UNSETTLED.items():
        mask = status == STATUS_NAMES.index(name)
        if mask.any():
            style = dict(ls="none", marker=marker, color="k", ms=6, path_effects=[
                patheffects.withStroke(linewidth=2.5, foreground="w")])
            label = f"{name} ({int(mask.sum())}{', ' + where if where else ''})"
            placed = mask & np.isfinite(y)
            if placed.any():
                ax.plot(x[placed], y[placed], label=label, **style)
                label = "_" + label  # (counted once in the legend)
            unplaced = mask & ~placed
            if unplaced.any():
                _at_foot(ax, x[unplaced], label=label, gid=f"{name}, no value", **style)
            marked = True
    if marked and legend:
        ax.legend(fontsize="small", loc="upper right", framealpha=0.8)


def _plot_maps(ds, axes_names: list, scales=None) -> Figure:
    """Maps of the power (else the first metric held) over two grid axes."""
    from matplotlib.colors import LogNorm

    name = next((n for n in ("power", "x_max", "v_rms") if n in ds),
                next(n for n in ds.data_vars if "sample" not in ds[n].dims))
    x_name, y_name = sorted(axes_names, key=lambda a: a != "frequency")  # frequency across
    directions = _directions(ds)
    fig = _new_figure((6 * len(directions), 4.8))
    panels = np.atleast_1d(fig.subplots(1, len(directions), sharey=True))
    values = ds[name].values
    positive = values[np.isfinite(values) & (values > 0)]
    log = positive.size and name == "power"
    norm = LogNorm(positive.min(), positive.max()) if log else None
    scale, label = _axis(ds, name, values, log)
    for ax, direction in zip(panels, directions):
        field = ds[name].sel(direction=direction) if direction else ds[name]
        status = None if "status" not in ds else \
            ds["status"].sel(direction=direction) if direction else ds["status"]
        mesh = _mesh(ax, ds, field / scale, x_name, y_name, scales, status, norm=norm)
        ax.set_title(f"{name}: {direction or 'each point from rest'}", loc="left",
                     fontsize="medium")
        _no_offset(ax)
    for ax in panels[1:]:
        ax.set_ylabel("")
    fig.colorbar(mesh, ax=list(panels), label=label)
    _suptitle(fig, _title(ds, axes_names))
    return fig


def _fixed(ds) -> dict:
    """A dataset's fixed values: its attributes, and the scalar coordinates a selection
    left (``ds.sel(gap=1e-6)``)."""
    return {**ds.attrs, **{name: float(ds[name]) for name in ds.coords
                           if name in PARAMETERS and ds[name].ndim == 0}}


def _title(ds, axes_names: list) -> str:
    preset = f"preset {ds.attrs['preset']}: " if "preset" in ds.attrs else ""
    return preset + parameters_text(_fixed(ds), axes_names)


def parameters_text(values, skip=(), stiffness: bool = True) -> str:
    """The fixed values a reader of a figure or table needs, formatted (``frequency = 140
    Hz, gap = 1 um, resistance = 10 kOhm``): frequency, gap, a lower stop, the load, a
    moving stop's support, and a contact stiffness derived from stop_mass. ``values``: a
    parameter set or a dataset's attributes (unset: None or "none"); ``skip``: names not
    fixed (a grid's or a branch's axes); ``stiffness``: with the derived one."""

    def given(name):
        value = values.get(name)
        return None if name in skip or value is None or isinstance(value, str) else value

    shown = [f"{n} = {quantity_text(float(given(n)), PARAMETERS[n].unit)}"
             for n in ("frequency", "gap", "lower_gap", "resistance") if given(n) is not None]
    if given("stop_support_stiffness") is not None:
        shown.append("moving stop: " + ", ".join(
            f"{n} = {quantity_text(float(given(n)), PARAMETERS[n].unit, 3)}"
            for n in ("stop_mass", "stop_support_stiffness", "stop_support_damping")
            if given(n) is not None))
    derived = derived_stiffness(values, skip) if stiffness else ""
    if derived:
        shown.append(derived)
    return ", ".join(shown)


def derived_stiffness(values, skip=()) -> str:
    """``hertz_stiffness = ... (derived from stop_mass = ...)`` where the contact stiffness
    of ``values`` (a parameter set or a dataset's attributes) is the one stop_mass and the
    materials give, else "" (not set, given by hand beside a moving stop, or varied)."""
    names = ("mass", "tip_material", "stop_mass", "stop_material", "hertz_stiffness")
    got = {n: values.get(n) for n in names}
    if any(n in skip for n in names) or got["stop_mass"] is None or isinstance(
            got["stop_mass"], str):
        return ""
    try:
        computed = hertz_stiffness_from_bodies(float(got["mass"]), got["tip_material"],
                                               float(got["stop_mass"]), got["stop_material"])
    except (KeyError, TypeError, ValueError):
        return ""
    if not np.isclose(computed, float(got["hertz_stiffness"]), rtol=1e-12):
        return ""  # (given by hand beside a moving stop)
    return (f"hertz_stiffness = {computed:.3g} N/m^1.5 (derived from stop_mass = "
            f"{quantity_text(float(got['stop_mass']), 'kg')}, {got['tip_material']} tip on "
            f"{got['stop_material']} stop)")


def plot_beam_scene(ds, path=None) -> Figure:
    """A beam orbit as the paper's Fig. 3, with the quantity the stop is there to limit:
    (a) tip and contact-point displacement [um] with the stop's gap (and a rod's face),
    (b) voltage, (c) instantaneous power, (d) contact force, (e) root strain
    [microstrain]. ``ds``: the time history of ``beam_runs.beam_scene``."""
    fig = _new_figure((8, 11))
    axes = fig.subplots(5, 1, sharex=True)
    t = (ds["time"].values - ds["time"].values[0]) * 1e3
    panels = [("tip_displacement", "displacement", "m"), ("voltage", "voltage", "V"),
              ("instantaneous_power", "power", "W"), ("contact_force", "contact force", "N"),
              ("root_strain", "root strain", "1")]
    for ax, (name, label, unit), letter in zip(axes, panels, "abcde"):
        values = ds[name].values
        scale, shown = (1e-6, "\u00b5strain") if unit == "1" else _display(unit, values)
        ax.plot(t, values / scale, lw=1.0, label="tip" if name == "tip_displacement" else None)
        ax.set_ylabel(f"{label} [{shown}]")
        ax.set_title(f"({letter}) {label}", loc="left", fontsize="medium")
        ax.grid(alpha=0.3)
        if name == "tip_displacement":
            ax.plot(t, ds["contact_displacement"].values / scale, lw=1.0, color="C1",
                    label="contact point")
            gap = float(ds.attrs.get("parameter_gap", np.nan))
            if "stop_face" in ds:
                ax.plot(t, (gap + ds["stop_face"].values) / scale, color="C3", lw=1.0,
                        label="rod face g + u_c")
            elif np.isfinite(gap):
                ax.axhline(gap / scale, color="C3", ls="--", lw=1.0,
                           label=f"stop (gap {quantity_text(gap, 'm')})")
            ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncols=3,
                      fontsize="small", frameon=False, borderaxespad=0.1)
    axes[-1].set_xlabel("time from the orbit's start [ms]")
    power = float(ds["power"]) if "power" in ds else None
    _suptitle(fig, "beam orbit" + (f": mean power {quantity_text(power, 'W', 3)}"
                                   if power is not None else ""))
    return _save(fig, path)


def plot_beam_sweep(ds, path=None) -> Figure:
    """What a beam sweep dataset (``beam_runs.beam_sweep``) holds. One grid axis: power,
    tip displacement extremes [um] and root strain [microstrain] against it, one curve per
    direction. Two grid axes: maps of the power and of the root strain (the first
    direction's, where there are several)."""
    grid = [d for d in ds.dims if d not in ("direction", "mode", "multiplier")]
    directions = list(ds["direction"].values) if "direction" in ds.dims else [None]
    if len(grid) == 1:
        axis = grid[0]
        fig = _new_figure((7.5, 8))
        panels = fig.subplots(3, 1, sharex=True)
        x = ds[axis].values
        x_scale, x_shown = _display(_unit(ds, axis), x)
        for d in directions:
            part = ds if d is None else ds.sel(direction=d)
            style = dict(_LINE_STYLES[d if d in _LINE_STYLES else None])
            label = d or None
            for ax, name, scale in ((panels[0], "power", None), (panels[1], "x_max", 1e-6),
                                    (panels[2], "root_strain_max", 1e-6)):
                values = part[name].values
                s = scale or _display("W", ds["power"].values)[0]
                ax.plot(x / x_scale, values / s, lw=1.0, ms=4, label=label, **style)
                _mark_unsettled(ax, part["status"].values, x / x_scale, values / s,
                                legend=False, where=d or "")
            panels[1].plot(x / x_scale, part["x_min"].values / 1e-6, lw=1.0, ms=4,
                           **dict(style, alpha=0.5))
        power_scale, power_shown = _display("W", ds["power"].values)
        panels[0].set_ylabel(f"power [{power_shown}]")
        panels[1].set_ylabel("tip x_max, x_min [\u00b5m]")
        panels[2].set_ylabel("root strain [\u00b5strain]")
        for ax in panels:
            ax.grid(alpha=0.3)
        if directions != [None] or (ds["status"].values != 0).any():
            panels[0].legend(fontsize="small")
        panels[-1].set_xlabel(f"{axis} [{x_shown}]")
    elif len(grid) == 2:
        from matplotlib.colors import LogNorm

        fig = _new_figure((11, 4.5))
        part = ds if directions == [None] else ds.sel(direction=directions[0])
        x_name, y_name = sorted(grid, key=lambda a: a != "frequency")  # frequency across
        for ax, name in zip(fig.subplots(1, 2), ("power", "root_strain_max")):
            values = part[name].values
            positive = values[np.isfinite(values) & (values > 0)]
            if name == "power" and positive.size:  # (as the tip-mass model's maps)
                norm, (scale, shown) = LogNorm(positive.min(), positive.max()), (1.0, "W")
            else:
                norm, scale, shown = None, 1e-6, "\u00b5strain"
            mesh = _mesh(ax, ds, part[name] / scale, x_name, y_name, None, part["status"],
                         norm=norm)
            fig.colorbar(mesh, ax=ax, label=f"{name} [{shown}]")
            ax.set_title(f"{name}: {directions[0] or 'each point from its linear steady state'}",
                         loc="left", fontsize="medium")
            _no_offset(ax)
    else:
        raise ParameterError(f"the dataset has {len(grid)} grid axes ({', '.join(grid)}): "
                             f"plot draws one or two; {_slice_advice(grid)}")
    _suptitle(fig, f"beam model, preset {ds.attrs.get('preset', '')}")
    return _save(fig, path)


def plot_beam_branch(ds, path=None) -> Figure:
    """A beam branch (``beam_continuation.continue_beam_branch``): power and tip x_max
    [um] against the parameter, each branch its own line (a colour per orbit period),
    stable parts solid and unstable dashed, each located bifurcation marked and labelled
    with its value."""
    parameter = ds.attrs["parameter"]
    x = ds[parameter].values
    x_scale, x_shown = _display(_unit(ds, parameter), x)
    fig = _new_figure((7.5, 6.5))
    panels = fig.subplots(2, 1, sharex=True)
    stable = ds["stable"].values.astype(bool)
    branch = ds["branch"].values if "branch" in ds else np.zeros(len(x), dtype=int)
    period = ds["orbit_period"].values if "orbit_period" in ds else np.ones(len(x), dtype=int)
    names = list(BIFURCATIONS)
    for ax, (name, unit) in zip(panels, (("power", "W"), ("x_max", "m"))):
        y = ds[name].values
        scale, shown = (1e-6, "\u00b5m") if unit == "m" else _display(unit, y)
        labelled = set()
        for b in np.unique(branch):  # (each branch its own line, a colour per period)
            on = branch == b
            periods = int(period[on][0])
            colour = f"C{int(np.log2(max(periods, 1)))}"
            for part, style in ((stable, "-"), (~stable, "--")):
                label = "stable" if style == "-" else "unstable"
                if len(np.unique(period)) > 1:
                    label += f", {periods} period{'s' if periods > 1 else ''}"
                ax.plot(x[on] / x_scale, np.where(part, y, np.nan)[on] / scale,
                        colour + style, lw=1.2, label=None if label in labelled else label)
                labelled.add(label)
        for i in np.flatnonzero(ds["bifurcation"].values):
            kind = names[int(ds["bifurcation"].values[i])]
            ax.plot(x[i] / x_scale, y[i] / scale, ls="none", **_BIFURCATION_MARKS[kind])
            ax.annotate(f"{_SHORT[kind]} {x[i] / x_scale:.6g}", (x[i] / x_scale, y[i] / scale),
                        textcoords="offset points", xytext=(4, 4 + 10 * (i % 3)),
                        fontsize="small")
        ax.set_ylabel(f"{name} [{shown}]")
        ax.grid(alpha=0.3)
    panels[0].legend(fontsize="small")
    panels[-1].set_xlabel(f"{parameter} [{x_shown}]")
    _suptitle(fig, f"beam branch in {parameter}, preset {ds.attrs.get('preset', '')}")
    return _save(fig, path)


def plot_beam_basins(ds, path=None) -> Figure:
    """Beam basins (``beam_basins.beam_basins``): each start in the first mode's plane
    coloured by the attractor it reaches, and each attractor's basin fraction with its
    standard error and its power."""
    fig = _new_figure((11, 4.5))
    left, right = fig.subplots(1, 2)
    label = ds["sample_attractor"].values
    for a in range(ds.sizes["attractor"]):
        pick = label == a
        left.plot(ds["start_eta_1"].values[pick], ds["start_eta_1_rate"].values[pick], "o",
                  ms=3, color=f"C{a % 10}",
                  label=f"attractor {a}: {int(ds['impacts_per_period'][a])} impact(s)/period")
    if (label < 0).any():
        left.plot(ds["start_eta_1"].values[label < 0], ds["start_eta_1_rate"].values[label < 0],
                  "x", color="0.5", label="not settled")
    left.set_xlabel("first mode at the start [m kg^0.5]")
    left.set_ylabel("its rate [m kg^0.5/s]")
    left.legend(fontsize="small")
    fractions = ds["basin_fraction"].values
    names = [f"{a}: {quantity_text(float(ds['power'][a]), 'W', 3)}"
             for a in range(ds.sizes["attractor"])]
    right.bar(names, fractions, yerr=ds["basin_fraction_error"].values,
              color=[f"C{a % 10}" for a in range(len(names))])
    right.set_ylabel("basin fraction [-]")
    right.set_xlabel("attractor: its power")
    _suptitle(fig, f"beam basins, preset {ds.attrs.get('preset', '')}")
    return _save(fig, path)
