"""The figures as a designer reads them (issue 44): each test draws a small real run (or a
real branch relabelled) with matplotlib's Agg canvas and reads the figure back: axis
scales, unit labels, cell edges, marker labels and where the titles and legends lie."""

from __future__ import annotations

import itertools
import re
import warnings

import numpy as np
import pytest
import xarray as xr
from matplotlib.text import Text

from harvester_sweep import (
    ParameterError,
    basin_fractions,
    basin_map,
    cli,
    continue_branch,
    resolve_parameters,
    run_scene,
)
from harvester_sweep.cli import _bifurcation_table
from harvester_sweep.outputs import STATUS_NAMES
from harvester_sweep.plots import bifurcation_points, plot_basins, plot_branch, plot_sweep
from harvester_sweep.sweep import run_sweep

UM = "\u00b5m"
FAST = {"steps_per_period": 256, "max_periods": 300}


@pytest.fixture(scope="module")
def s_curve():
    """The paper S-curve's lower half at 1 um, 300 down to 210 Hz: its grazing at
    218.68 Hz, 0.1 Hz from its lower fold at 218.58 Hz, and its upper fold at 258.10 Hz."""
    return continue_branch("paper", "frequency", 300.0, 210.0, gap=1e-6, steps_per_period=256)


def _drawn(fig):
    fig.draw_without_rendering()
    return fig.canvas.get_renderer()


def _inside(inner, outer, slack=1.0) -> bool:
    return (inner.x0 >= outer.x0 - slack and inner.x1 <= outer.x1 + slack
            and inner.y0 >= outer.y0 - slack and inner.y1 <= outer.y1 + slack)


def _labels(ax):
    return [t for t in ax.texts if t.get_gid() == "bifurcation label"]


def _text_box(label, renderer):
    """A label's text alone, without the line to its point."""
    return Text.get_window_extent(label, renderer)


def _relabelled(ds, name, values, **attrs):
    """A real branch with its parameter replaced by ``name`` taking ``values`` (the same
    points, stabilities and flags): a branch of a parameter over decades without running
    one."""
    old = ds.attrs["continued_parameter"]
    out = ds.rename({old: name, f"{old}_precision": f"{name}_precision",
                     f"{old}_shift": f"{name}_shift"})
    out[name] = ("point", np.asarray(values, dtype=float), {"units": "Ohm"})
    out[f"{name}_precision"] = out[f"{name}_precision"] * 0.0  # (every one located)
    out.attrs.update({"continued_parameter": name, "start": float(values[0]),
                      "stop": float(values[-1]), old: ds.attrs["start"], **attrs})
    out.attrs.pop(name, None)
    return out


def test_a_branch_over_decades_is_drawn_on_a_log_axis_unless_the_user_says_linear(s_curve):
    """A branch from 100 Ohm to 10 MOhm spreads over a log axis (on a linear one most of its
    points sat at the left edge); the user can still ask for linear; a frequency branch
    stays linear."""
    lam = np.geomspace(100.0, 1e7, s_curve.sizes["point"])
    branch = _relabelled(s_curve, "resistance", lam)
    axes = plot_branch(branch).axes
    assert [ax.get_xscale() for ax in axes] == ["log", "log"]
    assert axes[-1].get_xlabel() == "resistance [Ohm]"
    linear = plot_branch(branch, scales={"resistance": "linear"}).axes
    assert [ax.get_xscale() for ax in linear] == ["linear", "linear"]
    assert plot_branch(s_curve).axes[-1].get_xscale() == "linear"
    early = _relabelled(s_curve, "resistance", np.geomspace(100.0, 4865.0, lam.size))
    early.attrs["stop"] = 1e7  # (asked for 10 MOhm, stalled at 4.9 kOhm)
    assert plot_branch(early).axes[-1].get_xscale() == "log"
    with pytest.raises(ValueError, match="frequency"):
        plot_branch(branch, scales={"frequency": "log"})


def test_lengths_are_in_um_with_no_offset_on_branches_maps_and_lines(s_curve):
    """The gap as a branch's parameter, a map's axis and the x_max of a line plot: in um,
    ticks of order one, no "1e-6" multiplier over the axis."""
    gaps = np.linspace(0.5e-6, 2e-6, s_curve.sizes["point"])
    branch = _relabelled(s_curve, "gap", gaps)
    branch["gap"].attrs["units"] = "m"
    fig = plot_branch(branch)
    _drawn(fig)
    top, bottom = fig.axes[0], fig.axes[1]
    assert bottom.get_xlabel() == f"gap [{UM}]" and top.get_ylabel() == f"x_max [{UM}]"
    assert bottom.get_xscale() == "linear"
    assert bottom.xaxis.get_offset_text().get_text() == ""
    assert 0.4 <= min(bottom.get_xticks()[1:-1]) and max(bottom.get_xticks()) <= 2.5

    ds = run_sweep({"preset": "paper", "parameters": FAST,
                    "grid": {"gap": [1e-6, 2e-6], "frequency": [200.0, 240.0]},
                    "sweep": {"outputs": ["power", "x_max"]}}, progress=False)
    fig = plot_sweep(ds)
    _drawn(fig)
    ax = fig.axes[0]
    assert ax.get_ylabel() == f"gap [{UM}]" and ax.yaxis.get_offset_text().get_text() == ""
    assert ax.get_ylim()[0] == pytest.approx(0.5) and ax.get_ylim()[1] == pytest.approx(2.5)
    line = plot_sweep(ds.sel(frequency=200.0))
    _drawn(line)
    assert line.axes[-1].get_xlabel() == f"gap [{UM}]" and "frequency = 200 Hz" in \
        line.get_suptitle()
    assert line.axes[1].get_ylabel() == f"x_max [{UM}]"
    assert all(a.xaxis.get_offset_text().get_text() == "" for a in line.axes)
    assert [x.get_label() for x in line.axes[1].get_lines()][-1] == "stop"  # x_max = gap
    sliced = plot_sweep(ds.sel(gap=1e-6))  # (the selected gap: in the title, as the stop)
    assert f"gap = 1 {UM}" in sliced.get_suptitle()
    stop = [x for x in sliced.axes[1].get_lines() if x.get_label() == "stop"]
    assert len(stop) == 1 and stop[0].get_ydata()[0] == pytest.approx(1.0)

    basins = basin_map({"gap": [1e-6, 2e-6], "frequency": [200.0, 240.0]}, "paper",
                       samples=4, shock=0.01, steps_per_period=256)
    fig = plot_basins(basins)
    _drawn(fig)
    ax = fig.axes[0]
    assert ax.get_ylabel() == f"gap [{UM}]" and ax.yaxis.get_offset_text().get_text() == ""
    np.testing.assert_allclose(ax.collections[0].get_coordinates()[:, 0, 1], [0.5, 1.5, 2.5])


@pytest.fixture(scope="module")
def load_map():
    """README's fr.toml, smaller: four loads from 1 kOhm to 1 MOhm (log) x 3 frequencies."""
    return run_sweep({"preset": "paper", "parameters": {"gap": 1e-6, **FAST},
                      "grid": {"frequency": [200.0, 240.0, 280.0],
                               "resistance": {"start": 1e3, "stop": 1e6, "num": 4,
                                              "scale": "log"}},
                      "sweep": {"directions": ["up", "down"], "outputs": ["power"]}},
                     progress=False)


def test_log_map_cells_are_centred_on_their_values_in_log_space(load_map):
    """Each load's row runs from value / sqrt(10) to value * sqrt(10): the 1 kOhm row as tall
    as the others on the log axis (it was a thin strip), the frequency columns halfway
    between their values."""
    fig = plot_sweep(load_map)
    for ax in fig.axes[:2]:
        assert ax.get_yscale() == "log" and ax.get_ylabel() in ("resistance [Ohm]", "")
        edges = ax.collections[0].get_coordinates()
        rows = edges[:, 0, 1]
        np.testing.assert_allclose(np.log10(rows), [2.5, 3.5, 4.5, 5.5, 6.5], rtol=1e-12)
        np.testing.assert_allclose(edges[0, :, 0], [180.0, 220.0, 260.0, 300.0])
        assert ax.get_ylim() == pytest.approx((10 ** 2.5, 10 ** 6.5))
    assert fig.axes[0].get_ylabel() == "resistance [Ohm]"
    assert plot_sweep(load_map, scales={"resistance": "linear"}).axes[0].get_yscale() == \
        "linear"


def test_every_bifurcation_is_marked_and_labelled_with_its_value_none_hidden(s_curve):
    """The lower fold (218.58 Hz) and the grazing (218.68 Hz) lie on one spot: each has
    its label with kind and value, no label overlaps another or leaves the panel, and the
    star is drawn under the smaller fold dot."""
    fig = plot_branch(s_curve)
    renderer = _drawn(fig)
    top = fig.axes[0]
    texts = sorted(t.get_text() for t in _labels(top))
    assert texts == ["fold 218.58 Hz", "fold 258.1 Hz", "grazing 218.68 Hz"], texts
    boxes = [_text_box(t, renderer) for t in _labels(top)]
    frame = top.get_window_extent(renderer)
    assert all(_inside(box, frame) for box in boxes)
    for a, b in itertools.combinations(boxes, 2):
        assert not a.overlaps(b), (a, b)
    markers = {line.get_gid(): line for line in top.get_lines()
               if (line.get_gid() or "").startswith("bifurcation")}
    star, dot = markers["bifurcation grazing"], markers["bifurcation fold"]
    assert star.get_zorder() < dot.get_zorder() and star.get_markersize() > dot.get_markersize()


def test_a_failed_location_is_printed_and_drawn_as_its_bracket(s_curve):
    """A fold whose bracket stayed 7.5 Hz wide: labelled and printed as the interval that
    holds it, drawn as a bar over that interval, not as a value with ten digits."""
    ds = s_curve.copy(deep=True)
    i = [b["index"] for b in bifurcation_points(ds) if b["kind"] == "fold"][0]
    value = float(ds["frequency"][i])
    ds["frequency_precision"][i] = 7.5
    found = [b for b in bifurcation_points(ds) if b["index"] == i][0]
    assert not found["located"] and found["low"] == pytest.approx(value - 7.5)
    fig = plot_branch(ds)
    _drawn(fig)
    top = fig.axes[0]
    text = [t.get_text() for t in _labels(top) if "not located" in t.get_text()]
    assert text == [f"fold, not located: {value - 7.5:.4g} to {value + 7.5:.4g} Hz"]
    assert "not located: its bracket" in [t.get_text() for t in top.get_legend().get_texts()]
    bars = [line for line in top.get_lines() if line.get_gid() == "bracket"]
    assert len(bars) == 1
    np.testing.assert_allclose(bars[0].get_xdata(), [value - 7.5, value + 7.5])
    table = _bifurcation_table(ds)
    row = [line for line in table.splitlines() if "not located" in line]
    assert len(row) == 1 and f"{value - 7.5:.6g} to {value + 7.5:.6g}" in row[0]
    assert f"{value:.10g}" not in table


def test_a_lower_stop_grazing_is_drawn_against_x_min_and_the_lower_stop():
    """A lower stop alone (the upper one 1 m away): its grazing is marked on an x_min panel
    at the lower stop's line, labelled as the lower stop's, and not on x_max; the upper
    stop, out of reach, draws no line."""
    ds = continue_branch("paper", "frequency", 300.0, 215.0, gap=1.0, lower_gap=1e-6,
                         steps_per_period=256)
    fig = plot_branch(ds)
    _drawn(fig)
    x_max, x_min, power = fig.axes[:3]
    assert x_min.get_ylabel() == f"x_min [{UM}]" and power.get_ylabel() == "power [W]"
    stops = [line for line in x_min.get_lines() if line.get_label() == "lower stop"]
    assert len(stops) == 1 and stops[0].get_ydata()[0] == pytest.approx(-1.0)
    assert not [line for line in x_max.get_lines() if line.get_label().startswith("stop")]
    grazing = [line for line in x_min.get_lines() if line.get_gid() == "bifurcation grazing"]
    assert len(grazing) == 1 and grazing[0].get_ydata()[0] == pytest.approx(-1.0, abs=1e-3)
    assert not [line for line in x_max.get_lines() if line.get_gid() == "bifurcation grazing"]
    assert [t.get_text() for t in _labels(x_min)] == ["grazing (lower stop) 218.68 Hz"]
    assert "grazing (lower)" in _bifurcation_table(ds)


def test_titles_print_formatted_values_with_the_lower_and_the_moving_stop(s_curve):
    """Titles in display units with prefixes (no "1e-06 m", no "10000 Ohm"), with lower_gap,
    a moving stop's support and a stiffness derived from stop_mass, inside the figure."""
    branch = s_curve.copy()
    branch.attrs.update(lower_gap=1.5e-6)
    fig = plot_branch(branch)
    renderer = _drawn(fig)
    title = fig.get_suptitle()
    assert f"gap = 1 {UM}" in title and f"lower_gap = 1.5 {UM}" in title
    assert "resistance = 10 kOhm" in title and "e-06" not in title and "10000" not in title
    assert _inside(fig._suptitle.get_window_extent(renderer), fig.bbox)

    moving = s_curve.copy()
    moving.attrs.update(stop_mass=2.5e-3, stop_support_stiffness=15791.4,
                        stop_support_damping=0.628)
    title = plot_branch(moving).get_suptitle().replace("\n", " ")
    assert ("moving stop: stop_mass = 2.5 g, stop_support_stiffness = 15.8 kN/m, "
            "stop_support_damping = 0.628 N s/m") in title

    scene = run_scene("paper", stop_mass=1e-2, lower_gap=1.5e-6, frequency=245.0, **FAST)
    fig = scene.plot()
    renderer = _drawn(fig)
    title = fig.get_suptitle().replace("\n", " ")
    k_h = resolve_parameters("paper", stop_mass=1e-2)["hertz_stiffness"]
    assert f"hertz_stiffness = {k_h:.3g} N/m^1.5 (derived from stop_mass = 10 g" in title
    assert f"lower_gap = 1.5 {UM}" in title and "frequency = 245 Hz" in title
    assert _inside(fig._suptitle.get_window_extent(renderer), fig.bbox)


def test_the_scene_legend_leaves_the_orbit_uncovered():
    """The displacement panel's legend (stop, lower stop) covers no point of the orbit."""
    fig = run_scene("paper", lower_gap=1.5e-6, frequency=245.0, **FAST).plot()
    renderer = _drawn(fig)
    ax = fig.axes[0]
    assert ax.get_ylabel() == f"displacement [{UM}]"
    legend = ax.get_legend().get_window_extent(renderer)
    orbit = ax.get_lines()[0]
    points = orbit.get_transform().transform(orbit.get_xydata())
    covered = ((points[:, 0] >= legend.x0) & (points[:, 0] <= legend.x1)
               & (points[:, 1] >= legend.y0) & (points[:, 1] <= legend.y1))
    assert not covered.any()
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        f"stop (gap 1 {UM})", f"lower stop (lower_gap 1.5 {UM})"]
    assert _inside(legend, fig.bbox)


def test_the_basin_bar_chart_titles_fit_the_figure():
    """At one point: the figure's title and the panel's are inside the figure (the title
    was cut at both ends)."""
    ds = basin_fractions("paper", samples=8, shock=0.01, gap=1.32e-6, frequency=245.2,
                         steps_per_period=256)
    fig = plot_basins(ds)
    renderer = _drawn(fig)
    assert "gap = 1.32 \u00b5m" in fig.get_suptitle()
    assert "resistance = 10 kOhm" in fig.get_suptitle()  # (wrapped between items only)
    assert _inside(fig._suptitle.get_window_extent(renderer), fig.bbox)
    assert _inside(fig.axes[0].title.get_window_extent(renderer), fig.bbox)
    assert _inside(fig.axes[0]._left_title.get_window_extent(renderer), fig.bbox)


def test_down_dots_lie_under_the_up_dots_of_a_bifurcation_diagram():
    """Where the directions agree both show: down as open rings under smaller filled up
    dots."""
    ds = run_sweep({"preset": "paper", "parameters": FAST,
                    "grid": {"frequency": [200.0, 240.0]},
                    "sweep": {"directions": ["up", "down"], "outputs": ["power", "strobe"],
                              "samples": 2}}, progress=False)
    fig = plot_sweep(ds)
    ax = fig.axes[-1]
    assert ax.get_ylabel() == "voltage y(nT) [\u00b5V]"
    dots = {line.get_gid(): line for line in ax.get_lines() if line.get_gid()}
    up, down = dots["strobe up"], dots["strobe down"]
    assert up.get_zorder() > down.get_zorder()
    assert up.get_markersize() < down.get_markersize() and down.get_markerfacecolor() == "none"
    assert fig.axes[-2].get_ylabel() == f"displacement y(nT) [{UM}]"


def test_a_beam_branch_draws_each_branch_apart_in_the_colour_of_its_period():
    """Two branches, of one period and of two, that overlap in frequency: each is its own
    line (none joins the last point of one to the first of the next), the legend names
    each period, and each located bifurcation is labelled with its value."""
    import xarray as xr

    from harvester_sweep.outputs import BIFURCATIONS
    from harvester_sweep.plots import plot_beam_branch

    f = np.r_[np.linspace(140, 165, 30), np.linspace(148.6, 159.3, 20)]
    branch = np.r_[np.zeros(30, int), np.ones(20, int)]
    period = np.where(branch == 0, 1, 2)
    flags = np.zeros(50, int)
    flags[[8, 21]] = list(BIFURCATIONS).index("period_doubling")
    ds = xr.Dataset({"frequency": ("point", f, {"units": "Hz"}),
                     "power": ("point", 1e-8 * (1 + 0.1 * branch + 0.01 * np.sin(f)),
                               {"units": "W"}),
                     "x_max": ("point", 1e-6 * (1 + 0.2 * branch), {"units": "m"}),
                     "stable": ("point", np.ones(50, int)), "bifurcation": ("point", flags),
                     "branch": ("point", branch), "orbit_period": ("point", period)},
                    attrs={"parameter": "frequency", "preset": "bimorph_tip"})
    fig = plot_beam_branch(ds)
    ax = fig.axes[0]
    drawn = [line for line in ax.get_lines() if np.isfinite(line.get_ydata()).sum() > 1]
    assert len(drawn) == 2  # (the stable part of each branch)
    assert {len(line.get_xdata()) for line in drawn} == {30, 20}
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "stable, 1 period" in labels and "stable, 2 periods" in labels
    notes = [t.get_text() for t in ax.texts]
    assert any(f"{f[8]:.6g}" in n for n in notes) and any(f"{f[21]:.6g}" in n for n in notes)


def _marks(ax, name):
    """The points drawn for the status ``name``: (label, x, y) of each such marker line."""
    return [(line.get_label(), line.get_xdata(), line.get_ydata()) for line in ax.get_lines()
            if line.get_label().startswith(name)]


def test_points_that_are_not_a_steady_state_are_marked_where_they_lie(load_map):
    """A map's cell and a curve's point whose status is not "settled" carry a marker of
    that status, counted in the legend: its metrics are not a steady state's. (The
    statuses are set by hand on a real run: the figure must show what the file says.)"""
    ds = load_map.copy(deep=True)
    ds["status"].loc[dict(direction="up", frequency=240.0, resistance=1e4)] = 1
    ds["status"].loc[dict(direction="down", frequency=280.0, resistance=1e3)] = 2
    fig = plot_sweep(ds)
    up, down = fig.axes[0], fig.axes[1]
    ((label, x, y),) = _marks(up, "not settled")
    assert label == "not settled (1)" and (x[0], y[0]) == pytest.approx((240.0, 1e4))
    assert not _marks(up, "diverged") and not _marks(down, "not settled")
    ((label, x, y),) = _marks(down, "diverged")
    assert label == "diverged (1)" and (x[0], y[0]) == pytest.approx((280.0, 1e3))
    assert any(t.get_text() == "not settled (1)" for t in up.get_legend().get_texts())
    line = plot_sweep(ds.sel(resistance=1e4))  # (power and x_max against frequency)
    for ax in line.axes[:2]:
        ((label, x, y),) = _marks(ax, "not settled")
        assert label == "not settled (1, up)" and x[0] == pytest.approx(240.0)
    power = line.axes[0].get_lines()[0].get_ydata()[1]  # (the up curve's, at 240 Hz)
    assert _marks(line.axes[0], "not settled")[0][2][0] == pytest.approx(power)


def test_a_beam_map_is_drawn_as_the_tip_mass_models_with_its_unsettled_points():
    from harvester_sweep.beam_runs import beam_sweep
    from harvester_sweep.plots import plot_beam_sweep

    ds = beam_sweep({"gap": [1e-6, 2e-6], "frequency": [150.0, 200.0]}, "bimorph_tip",
                    n_modes=1)
    ds["status"].loc[dict(gap=2e-6, frequency=150.0)] = 1
    fig = plot_beam_sweep(ds)
    power, strain = fig.axes[:2]  # (the colour bars after them)
    for ax in (power, strain):
        assert ax.get_xlabel() == "frequency [Hz]" and ax.get_ylabel() == f"gap [{UM}]"
        ((label, x, y),) = _marks(ax, "not settled")
        assert label == "not settled (1)" and (x[0], y[0]) == pytest.approx((150.0, 2.0))
    assert power.collections[0].norm.__class__.__name__ == "LogNorm"


def _err_lines(capsys) -> list:
    """The command's lines on stderr (the note of a cold numba cache left out)."""
    return [line for line in capsys.readouterr().err.splitlines()
            if "compiling the RK4 kernel" not in line]


def _at_foot(fig, ax, line, x_values) -> bool:
    """Whether ``line``'s markers lie at ``x_values`` along the axis and at the foot of the
    panel (its lowest tenth), in display coordinates."""
    _drawn(fig)
    shown = line.get_transform().transform(np.column_stack([line.get_xdata(),
                                                            line.get_ydata()]))
    want = ax.transData.transform(np.column_stack([x_values, np.ones(len(x_values))]))[:, 0]
    box = ax.get_window_extent()
    return bool(np.all(np.isfinite(shown)) and np.allclose(shown[:, 0], want)
                and np.all((shown[:, 1] > box.y0) & (shown[:, 1] < box.y0 + 0.1 * box.height)))


def test_a_line_plot_whose_points_are_all_too_stiff_says_so_and_marks_them(tmp_path, capsys):
    """Every point refused as too stiff (max_steps_per_period = 100), up and down: each
    panel says that no point has a value and why, and marks the points at its foot, as
    the two-axis map marks its cells; no numpy warning. (It warned "All-NaN slice" twice
    and crashed on NaN axis limits.)"""
    ds = run_sweep({"preset": "paper", "parameters": {"gap": 1e-6, "max_steps_per_period": 100},
                    "grid": {"frequency": [130.0, 140.0]},
                    "sweep": {"directions": ["up", "down"]}}, progress=False)
    assert (ds["status"].values == STATUS_NAMES.index("too stiff")).all()  # (the case)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_sweep(ds)
    for ax, name in zip(fig.axes, ("power", "x_max")):
        said = [t.get_text() for t in ax.texts if t.get_gid() == "no value"]
        assert said == [f"no point has a value of {name}: too stiff (4 of 4)"]
        marks = [line for line in ax.get_lines() if line.get_label().startswith("too stiff")]
        assert [line.get_label() for line in marks] == ["too stiff (2, up)",
                                                        "too stiff (2, down)"]
        assert all(_at_foot(fig, ax, line, [130.0, 140.0]) for line in marks)
    path = tmp_path / "stiff.nc"
    ds.to_netcdf(path)
    assert cli.main(["plot", str(path), "--output", str(tmp_path / "s.png")]) == 0
    assert _err_lines(capsys) == [] and (tmp_path / "s.png").exists()


def test_a_point_with_no_value_on_a_curve_is_marked_at_the_foot_of_the_panel(load_map):
    """A too-stiff point among settled ones (NaN metrics, set by hand on a real run) is
    marked where it lies along the axis: it was drawn at a NaN height, unseen."""
    ds = load_map.sel(resistance=1e4).copy(deep=True)
    where = dict(direction="up", frequency=240.0)
    ds["status"].loc[where] = STATUS_NAMES.index("too stiff")
    ds["power"].loc[where] = np.nan
    fig = plot_sweep(ds)
    ax = fig.axes[0]
    (mark,) = [line for line in ax.get_lines() if line.get_label().startswith("too stiff")]
    assert mark.get_label() == "too stiff (1, up)" and _at_foot(fig, ax, mark, [240.0])
    assert not [t for t in ax.texts if t.get_gid() == "no value"]  # (others have values)


def test_a_sweep_without_power_and_x_max_plots_the_outputs_it_holds():
    """outputs = ["v_rms"] drew an empty frame: it draws v_rms, with its closed form, which
    the run matches where the stop is out of reach (gap 1 m); a sweep holding no output
    that plot draws is refused in one line."""
    ds = run_sweep({"preset": "paper", "parameters": {"gap": 1.0, **FAST},
                    "grid": {"frequency": [200.0, 240.0]}, "sweep": {"outputs": ["v_rms"]}},
                   progress=False)
    (ax,) = plot_sweep(ds).axes
    assert ax.get_ylabel() == "v_rms [\u00b5V]"
    lines = {line.get_label(): line.get_ydata() for line in ax.get_lines()}
    np.testing.assert_allclose(lines["from rest"], ds["v_rms"].values / 1e-6)
    np.testing.assert_allclose(lines["no stop (closed form)"], ds["v_rms"].values / 1e-6,
                               rtol=1e-5)
    with pytest.raises(ParameterError, match="no output plot draws"):
        plot_sweep(ds.drop_vars("v_rms"))


def _basins(axes: dict):
    """A basins dataset over ``axes`` as basins.basin_map lays it out: two attractor slots,
    the first point's second NaN (its starts reached one attractor)."""
    dims = tuple(axes)
    shape = tuple(len(v) for v in axes.values())
    share = np.linspace(0.1, 0.9, int(np.prod(shape))).reshape(shape)
    basin = np.stack([share, 1 - share], axis=-1)
    basin[(0,) * len(dims) + (1,)] = np.nan
    seen = np.isfinite(basin)
    per = dims + ("attractor",)
    return xr.Dataset(
        {"impact_basin_fraction": (dims, share),
         "impact_basin_fraction_error": (dims, 0.1 * np.ones(shape)),
         "basin_fraction": (per, basin), "basin_fraction_error": (per, 0.1 * basin),
         "orbit_period": (per, seen.astype(int)),
         "impacts_per_period": (per, np.where(seen, 1.0, np.nan)),
         "power": (per, np.where(seen, 1e-15, np.nan))},
        coords={**{k: (k, np.asarray(v, dtype=float)) for k, v in axes.items()},
                "attractor": ("attractor", [1, 2])},
        attrs={"grid_axes": " ".join(dims), "samples": 4, "shock": 0.01, "preset": "paper"})


def test_sliced_basins_plot_as_basins_of_as_many_axes_and_the_refusal_names_an_axis():
    """ds.isel, as the refusal of three axes advises, keeps grid_axes of the whole grid: a
    slice was refused as three axes, or failed in sortby ("not 1-D"). The refusals of
    three axes (basins and sweeps) name one of the dataset's own axes (they said gap)."""
    ds = _basins({"frequency": [200.0, 240.0], "resistance": [1e3, 1e4],
                  "damping_ratio": [0.01, 0.02]})
    for plot, data in ((plot_basins, ds),
                       (plot_sweep, ds[["impact_basin_fraction"]].rename(
                           impact_basin_fraction="power"))):
        with pytest.raises(ParameterError, match="3 grid axes") as refused:
            plot(data)
        (axis,) = re.findall(r"isel\((\w+)=0\)", str(refused.value))
        assert axis in ds["impact_basin_fraction"].dims
    plane = ds.isel(damping_ratio=1)
    ax = plot_basins(plane).axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("frequency [Hz]", "resistance [kOhm]")
    np.testing.assert_allclose(ax.collections[0].get_array(),
                               plane["impact_basin_fraction"].values.T)  # (rows: loads)
    line = ds.isel(damping_ratio=1, resistance=0)
    ax = plot_basins(line).axes[0]
    assert ax.get_xlabel() == "frequency [Hz]"
    np.testing.assert_allclose(ax.get_lines()[0].get_ydata(),
                               line["impact_basin_fraction"].values)
    point = ds.isel(damping_ratio=0, resistance=0, frequency=0)  # (one attractor reached)
    ax = plot_basins(point).axes[0]
    assert len(ax.patches) == 1
    assert not [t for t in ax.get_xticklabels() if "nan" in t.get_text()]


def test_over_refuses_what_is_not_a_sweep_of_the_branchs_model_and_says_what_it_is(
        s_curve, tmp_path, capsys):
    """A beam sweep (or another preset's) was drawn under a tip-mass branch without a
    word; a scene or a branch given to --over was said to run along "" or "point"."""
    from harvester_sweep.beam_runs import beam_sweep

    sweep = run_sweep({"preset": "paper", "parameters": {"gap": 1e-6, **FAST},
                       "grid": {"frequency": [220.0, 260.0]}}, progress=False)
    plot_branch(s_curve, sweeps=[sweep])  # (of its model and preset: drawn)
    beam = beam_sweep({"frequency": [220.0, 260.0]}, "bimorph_tip", n_modes=1)
    with pytest.raises(ParameterError, match="beam model"):
        plot_branch(s_curve, sweeps=[beam])
    other = sweep.copy()
    other.attrs["preset"] = "strong_coupling"
    with pytest.raises(ParameterError, match="preset strong_coupling"):
        plot_branch(s_curve, sweeps=[other])
    branch = tmp_path / "branch.nc"
    s_curve.to_netcdf(branch)
    run_scene("paper", **FAST).to_netcdf(tmp_path / "scene.nc")
    beam.to_netcdf(tmp_path / "beam.nc")
    for over, said in (("beam.nc", "beam model"), ("scene.nc", "a scene"),
                       ("branch.nc", "a branch")):
        argv = ["plot", str(branch), "--over", str(tmp_path / over), "--output",
                str(tmp_path / "o.png")]
        assert cli.main(argv) == 2
        (line,) = _err_lines(capsys)
        assert said in line and str(tmp_path / over) in line and "runs along" not in line
        assert not (tmp_path / "o.png").exists()


@pytest.mark.parametrize("content, said", [(b"hi\n", "text"), (b"", "empty")])
def test_a_file_that_is_not_netcdf_is_said_in_a_short_line(content, said, tmp_path, capsys):
    """A text or empty file given to plot: one short line saying what it is, not
    xarray's advice on IO engines."""
    path = tmp_path / "text.nc"
    path.write_bytes(content)
    assert cli.main(["plot", str(path), "--output", str(tmp_path / "p.png")]) == 2
    (line,) = _err_lines(capsys)
    assert line.startswith(f"harvester-sweep: error: {path}: ") and said in line
    assert "engine" not in line and len(line) < 100 + len(str(path))


def test_basins_where_no_start_reached_an_orbit_say_so():
    """Three periods settle no start: the impact basin fraction is NaN (unknown) at both
    points of the line and the single point; the line drew an empty frame around 0 Hz and
    the point empty bars. Both now say why, and the line marks each point at its foot."""
    line = basin_map({"frequency": [240.0, 250.0]}, samples=4, steps_per_period=512,
                     max_periods=3, progress=False)
    point = line.isel(frequency=0)
    for ds in (line, point):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            ax = plot_basins(ds).axes[0]
        said = [t.get_text() for t in ax.texts if t.get_gid() == "no value"]
        assert said == ["no start reached an orbit: up to 100% not settled"]
    marks = [m for m in plot_basins(line).axes[0].get_lines() if m.get_gid() == "no orbit"]
    assert len(marks) == 1 and list(marks[0].get_xdata()) == [240.0, 250.0]
