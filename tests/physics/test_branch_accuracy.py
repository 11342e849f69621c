"""Branch points and located bifurcations meet the accuracy target, and say how far off
they are, against references written here from SciPy (issue 45).

The reference is the exact period map of docs/model.md integrated by SciPy's DOP853 at
rtol 1e-12, restarted at each contact switch (``tests/helpers.Reference``), with its
steps capped at ``REFERENCE_MAX_STEP`` of a period: an orbit that penetrates the stop by
less than a nanometre (next to a grazing) is in contact for a few hundredths of a period,
and without the cap the reference's event location (a sign change between two of its
step ends) missed such a contact, so that the reference's orbit was the stop-free one
(measured on the gap branch below, 0.3 nm into the stop: 4.5e-5 off the engine's with
the cap off, 5.6e-9 with it at 1/4000 or 1/1000 of a period, the engine's estimate
5.0e-9). Nothing of the engine's
integrator, switch location, monodromy or continuation enters it; from the package it
takes the validated parameters and each point's orbit state, as a first guess that the
reference's own Newton iteration moves onto its fixed point.

- every point's ``error_estimate`` is at or below ``accuracy`` (a gap branch of the paper
  scene through both folds, a frequency branch of the strong-coupling preset through a
  period doubling, and its resistance branch from 100 Ohm to 10 MOhm), and every located
  bifurcation's shift (its larger change at 3/2 and twice the steps) is within
  ``accuracy`` of its value;
- points of the gap branch (the most estimated, stable and unstable) are within twice
  their estimate of the reference's orbit at the same gap (the error of fourth-order RK4
  is 16/15 of the change at twice the steps; measured 1.02-1.21 times);
- the gap branch's two folds and the strong-coupling period doubling are within twice
  their reported shift (plus half their bracket, the location's own width) of the
  reference's: a fold as the vertex of the parameter on three sections across the
  reference's branch, the period doubling where the reference's ``det(I + M)`` vanishes.

A Neimark-Sacker point, whose stop moves, has its own reference:
tests/physics/test_neimark_sacker_accuracy.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import tests.helpers as helpers
from harvester_sweep import continue_branch, resolve_parameters
from harvester_sweep.outputs import BIFURCATIONS
from tests.helpers import Reference, period_map_jacobian, secant

FOLD = list(BIFURCATIONS).index("fold")
PERIOD_DOUBLING = list(BIFURCATIONS).index("period_doubling")
NEIMARK_SACKER = list(BIFURCATIONS).index("neimark_sacker")
GRAZING = list(BIFURCATIONS).index("grazing")
#: The reference's largest step, in forcing periods [-] (see the module's docstring).
REFERENCE_MAX_STEP = 1 / 1000
#: The reference's multipliers' own error [-] (tests/helpers.period_map_jacobian).
REFERENCE_MULTIPLIER = 1e-9
ORBIT = ("orbit_displacement", "orbit_velocity", "orbit_voltage")
GAP_BRANCH = dict(preset="paper", parameter="gap", start=0.5e-6, stop=3e-6,
                  fixed={"frequency": 240.0})
PD_BRANCH = dict(preset="strong_coupling", parameter="frequency", start=150.0, stop=140.0,
                 fixed={"gap": 3e-6})


@pytest.fixture(autouse=True)
def capped_reference(monkeypatch):
    """The reference with its steps capped (module docstring)."""
    def capped(fun, t_span, y0, **options):
        return solve_ivp(fun, t_span, y0, max_step=_MAX_STEP[0], **options)

    monkeypatch.setattr(helpers, "solve_ivp", capped)


_MAX_STEP = [np.inf]  # [s], set for the parameters of each reference run (_parameters)


def _parameters(case, value):
    p = resolve_parameters(case["preset"], **{**case["fixed"], case["parameter"]: value})
    _MAX_STEP[0] = REFERENCE_MAX_STEP / p["frequency"]
    return p


def _branch(case):
    return continue_branch(case["preset"], case["parameter"], case["start"], case["stop"],
                           **case["fixed"])


@pytest.fixture(scope="module")
def gap_branch():
    return _branch(GAP_BRANCH)


@pytest.fixture(scope="module")
def pd_branch():
    return _branch(PD_BRANCH)


def reference_orbit(p, y, periods, monodromy=True):
    """The reference's fixed point of P^periods near ``y`` and (where ``monodromy``) its
    monodromy there, else None: chord steps on the central-difference Jacobian at ``y``
    (the engine's orbit is within about 1e-7 of the fixed point, where a chord step gains
    some seven digits), until a step is below 1e-12 of the scales or for 8 steps (the
    reference's own rounding then moves its iterates)."""
    y = np.asarray(y, float)
    image, jacobian, scale = period_map_jacobian(p, y, periods)
    for _ in range(8):
        step = np.linalg.solve(jacobian - np.eye(3), y - image)
        y = y + step
        if np.max(np.abs(step) / scale) < 1e-12:
            break
        image = Reference(p).integrate(y, 0.0, periods / p["frequency"])[0][:3]
    return y, period_map_jacobian(p, y, periods)[1] if monodromy else None


def reference_metrics(p, y, periods, samples=200001):
    """power [W], v_peak [V], x_max and x_min [m] of the reference's orbit from ``y``."""
    duration = periods / p["frequency"]
    end, pieces = Reference(p).integrate(y, 0.0, duration, dense=True)
    t = np.linspace(0.0, duration, samples)
    x_v = np.full((3, t.size), np.nan)
    for sol, _ in pieces:
        inside = (t >= sol.t[0]) & (t <= sol.t[-1])
        x_v[:, inside] = sol.sol(t[inside])[:3]
    return {"power": end[3] / duration / p["resistance"], "v_peak": np.abs(x_v[2]).max(),
            "x_max": x_v[0].max(), "x_min": x_v[0].min()}


def point_error(case, ds, i):
    """The error of point ``i`` against the reference's orbit at its parameter value, as
    accuracy.halving_error measures a change: the largest of power and v_peak relative to
    themselves and x_max and x_min relative to the displacement amplitude."""
    point = ds.isel(point=i)
    p = _parameters(case, float(point[case["parameter"]]))
    periods = int(point["orbit_period"])
    y, _ = reference_orbit(p, [float(point[n]) for n in ORBIT], periods, monodromy=False)
    ref = reference_metrics(p, y, periods)
    amplitude = 0.5 * (ref["x_max"] - ref["x_min"])
    return max(abs(float(point["power"]) / ref["power"] - 1),
               abs(float(point["v_peak"]) / ref["v_peak"] - 1),
               abs(float(point["x_max"]) - ref["x_max"]) / amplitude,
               abs(float(point["x_min"]) - ref["x_min"]) / amplitude)


def reference_fold(case, ds, i, h=1e-5):
    """The reference's fold near point ``i``: the parameter on three sections of the
    reference's branch, normal to the engine's branch at -h, 0 and h along it (scaled as
    continuation scales: amplitudes, and the range), and the vertex of the parabola
    through them (the fold is where the parameter turns)."""
    name = case["parameter"]
    scale = np.array([np.abs(ds[n]).max() for n in ("x_max", "orbit_velocity",
                                                    "orbit_voltage")])
    span = abs(case["stop"] - case["start"])

    def scaled(k):
        point = ds.isel(point=k)
        return np.concatenate([[float(point[n]) for n in ORBIT] / scale,
                               [float(point[name]) / span]])

    def residual(z):
        p = _parameters(case, z[3] * span)
        y = z[:3] * scale
        image = Reference(p).integrate(y, 0.0, 1.0 / p["frequency"])[0][:3]
        return (image - y) / scale

    fold = scaled(i)
    tangent = scaled(i + 1) - scaled(i - 1)
    tangent /= np.linalg.norm(tangent)
    values = []
    for s in (-h, 0.0, h):
        origin = fold + s * tangent
        z = origin.copy()
        jacobian = np.empty((4, 4))
        for j in range(4):  # (one Jacobian: chord steps converge, as it is regular here)
            d = np.zeros(4)
            d[j] = 1e-6
            jacobian[:3, j] = (residual(z + d) - residual(z - d)) / 2e-6
        jacobian[3] = tangent
        for _ in range(20):
            step = np.linalg.solve(jacobian, -np.concatenate([residual(z),
                                                              [tangent @ (z - origin)]]))
            z = z + step
            if np.max(np.abs(step)) < 1e-13:
                break
        values.append(z[3] * span)
    a, b, c = np.polyfit([-h, 0.0, h], values, 2)
    return c - b * b / (4 * a)


def reference_period_doubling(case, ds, i, width):
    """The parameter where the reference's det(I + M) vanishes near point ``i`` (the
    secant method from +-``width`` about it, each value's orbit by Newton), and the
    reference's monodromy there."""
    name = case["parameter"]
    point = ds.isel(point=i)
    periods = int(point["orbit_period"])
    y = np.array([float(point[n]) for n in ORBIT])

    def det(value, y):
        y, jacobian = reference_orbit(_parameters(case, value), y, periods)
        return np.linalg.det(np.eye(3) + jacobian), y, jacobian

    return secant(det, float(point[name]) - width, float(point[name]) + width, y)


@pytest.mark.parametrize("case", [GAP_BRANCH, PD_BRANCH,
                                  dict(preset="strong_coupling", parameter="resistance",
                                       start=100.0, stop=1e7, fixed={"frequency": 140.0})],
                         ids=["paper-gap", "strong_coupling-frequency",
                              "strong_coupling-resistance"])
def test_every_estimate_meets_the_accuracy_target(case, gap_branch, pd_branch):
    """Every point's estimate at or below accuracy (1e-7), every located bifurcation's
    change at 3/2 and twice the steps within 1e-7 of its value, and the branch ends where
    the range does (the resistance branch stalled at 4.86 kOhm before its V was scaled
    over the range)."""
    ds = {id(GAP_BRANCH): gap_branch, id(PD_BRANCH): pd_branch}.get(id(case))
    ds = _branch(case) if ds is None else ds
    accuracy = resolve_parameters(case["preset"])["accuracy"]
    error = ds["error_estimate"].values
    assert np.all(np.isfinite(error)) and np.all(error <= accuracy), error.max()
    assert ds.attrs["ends"].startswith("left the range")
    assert np.all(ds["steps_per_period"].values >= ds.attrs["steps_per_period"])
    name = case["parameter"]
    located = np.flatnonzero(ds["bifurcation"].values)
    shift = ds[f"{name}_shift"].values[located]
    assert np.all(np.abs(shift) <= accuracy * np.abs(ds[name].values[located])), shift


def test_points_are_within_twice_their_estimate(gap_branch):
    """The most estimated points of the gap branch (near its upper fold, refined to up to
    2544 steps per period), every 25th (stable and unstable) and the last one before the
    grazing, against the reference's orbit at their gap: measured 1.01-1.12 times their
    estimate. Located folds are left to the test below: at a fold the orbit at the same
    value is not a measure (its estimate is taken normal to the branch)."""
    error = gap_branch["error_estimate"].values
    regular = np.flatnonzero(gap_branch["bifurcation"].values == 0)
    grazing = np.flatnonzero(gap_branch["bifurcation"].values == GRAZING)[0]
    chosen = (set(regular[np.argsort(-error[regular])[:3]]) | set(regular[::25])
              | {grazing - 1})  # (0.3 nm into the stop: the reference's steps capped)
    for i in sorted(chosen):
        measured = point_error(GAP_BRANCH, gap_branch, i)
        assert measured <= 2 * error[i] + 1e-10, (i, measured, error[i])
    assert any(not gap_branch["stable"].values[i] for i in chosen)


def test_folds_are_within_twice_their_shift(gap_branch):
    """Both folds of the gap branch against the reference's: the upper one located at
    1248 steps per period (at the branch's 688 its shift was 3.1e-7 of the gap), off by
    1.09 times its shift, the lower one (a sharp fold 2.7 nm from the grazing) by 1.13."""
    folds = np.flatnonzero(gap_branch["bifurcation"].values == FOLD)
    assert folds.size == 2
    for i in folds:
        value = float(gap_branch["gap"][i])
        shift = abs(float(gap_branch["gap_shift"][i]))
        width = float(gap_branch["gap_precision"][i])
        off = abs(value - reference_fold(GAP_BRANCH, gap_branch, i))
        assert off <= 2 * shift + 0.5 * width, (value, off, shift, width)


def test_period_doubling_is_within_twice_its_shift(pd_branch):
    """The strong-coupling preset's period doubling near 145.32 Hz (gap 3 um) against the
    reference's, where det(I + M) of its orbit vanishes: off by 0.77 times its shift
    (3.5e-6 Hz, the shift 4.6e-6 Hz; the location at 1088 steps meets 1e-7 relative). Its
    other multipliers are within twice their change at 3/2 and twice the steps of the
    reference's at the reference's doubling (measured 0.05 and 0.15 times), and the one at
    -1 is -1 to the location's bracket."""
    (i,) = np.flatnonzero(pd_branch["bifurcation"].values == PERIOD_DOUBLING)
    value = float(pd_branch["frequency"][i])
    shift = abs(float(pd_branch["frequency_shift"][i]))
    width = float(pd_branch["frequency_precision"][i])
    reference, jacobian = reference_period_doubling(PD_BRANCH, pd_branch, i, 1e-4)
    off = abs(value - reference)
    assert off <= 2 * shift + 0.5 * width, (value, off, shift, width)
    point = pd_branch.isel(point=i)
    engine = (point["floquet_multipliers_real"].values
              + 1j * point["floquet_multipliers_imag"].values)
    ref = np.linalg.eigvals(jacobian)
    ref = ref[[int(np.argmin(np.abs(ref - mu))) for mu in engine]]
    change = point["floquet_multipliers_shift"].values
    critical = int(np.argmin(np.abs(engine + 1)))
    assert abs(engine[critical] + 1) < 1e-6
    others = np.arange(len(engine)) != critical
    assert np.all(np.abs(engine - ref)[others] <= 2 * change[others]), (engine, ref, change)


#: The strong-coupling frequency branch switched onto its doubled branches (period 1 to 8
#: between 150 and 135 Hz at gap 3 um).
PD_SWITCH = dict(preset="strong_coupling", parameter="frequency", start=150.0, stop=135.0,
                 fixed={"gap": 3e-6})


def test_doubled_branches_meet_the_accuracy_target():
    """With period_doubling="switch", every estimate at or below accuracy, and the point
    nearest a doubling's birth (the period-2 branch's first, 2e-4 Hz from the doubling at
    145.32 Hz, refined to 10944 steps a period) within twice its estimate of the
    reference's period-2 orbit at its frequency (measured 0.48 times; the next two 0.48
    and 1.17). Before, that point stayed at 1.1e-7 after three refinements, and a doubled
    branch that met the orbit it doubles went on along it as a fixed point of twice its
    period (542 points, 2 above 1e-7 up to 1.1e-6, all on such stretches; to 130 Hz 1696
    and 15 up to 2.0e-6)."""
    ds = continue_branch(PD_SWITCH["preset"], PD_SWITCH["parameter"], PD_SWITCH["start"],
                         PD_SWITCH["stop"], period_doubling="switch", **PD_SWITCH["fixed"])
    accuracy = resolve_parameters(PD_SWITCH["preset"])["accuracy"]
    error = ds["error_estimate"].values
    assert np.all(np.isfinite(error)) and np.all(error <= accuracy), error.max()
    assert "back on a period-4 orbit" in ds.attrs["ends"]  # (period-8 branches that met it)
    branches = ds["branch"].values
    doublings = ds["frequency"].values[ds["bifurcation"].values == PERIOD_DOUBLING]
    # each doubled branch is followed once: no doubling located twice (the period-4 branch
    # between the period-2 branch's two doublings was followed from each, once round its
    # loop, and the period-8 branch born on it twice: 228 points, 143.424 and 135.832 Hz
    # three times each)
    located = np.sort(doublings)
    assert np.all(np.diff(located) > 1e-6 * located[1:]), located
    assert sorted(set(ds["orbit_period"].values)) == [1, 2, 4, 8]
    heads = [np.flatnonzero(branches == n)[0] for n in np.unique(branches)[1:]]
    born = [np.min(np.abs(doublings - float(ds["frequency"][i]))) for i in heads]
    i = heads[int(np.argmin(born))]
    assert min(born) < 1e-3 and int(ds["orbit_period"][i]) == 2
    measured = point_error(PD_SWITCH, ds, i)
    assert measured <= 2 * error[i] + 1e-10, (i, measured, error[i])
