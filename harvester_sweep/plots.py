"""Figures drawn from the datasets (matplotlib, no display needed)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

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

    (a) displacement with the stop marked, (b) voltage, (c) instantaneous power,
    (d) contact force. ``ds`` is a scene dataset (see ``SceneResult.dataset``).
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
            ax.axhline(gap / scale, color="C3", ls="--", lw=1.0, label=f"stop (gap {gap:g} m)")
            ax.legend(loc="lower right", fontsize="small")
    axes[-1].set_xlabel(f"time from t = {float(ds['time'].values[0]):.4g} s [ms]")
    status = str(["settled", "not settled", "diverged"][int(ds["status"])])
    fig.suptitle(
        f"f = {ds.attrs['frequency']:g} Hz, gap = {ds.attrs['gap']:g} m, "
        f"R = {ds.attrs['resistance']:g} Ohm: {status}, orbit period {int(ds['orbit_period'])}, "
        f"mean power {float(ds['power']):.3g} W"
    )
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig
