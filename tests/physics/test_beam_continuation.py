"""Branches of the beam's orbits: the one-mode beam at its tip is the tip-mass model, so
its folds and grazing must be where the lane engine's own continuation (plain RK4 on the
reduced tip-mass model, its own corrector and location) puts them."""

from __future__ import annotations

import numpy as np
import pytest

from harvester_sweep import NoOrbitError, continue_branch, run_scene
from harvester_sweep import bimorph as bm
from harvester_sweep.beam_continuation import continue_beam_branch
from harvester_sweep.beam_parameters import bimorph, resolve_beam_parameters
from harvester_sweep.cli import main
from harvester_sweep.outputs import BIFURCATIONS
from harvester_sweep.parameters import ParameterError


def _located(ds, parameter="frequency"):
    names = list(BIFURCATIONS)
    return sorted((names[int(flag)], float(value)) for flag, value
                  in zip(ds["bifurcation"].values, ds[parameter].values) if flag)


@pytest.fixture(scope="module")
def branches():
    """The one-mode beam's frequency branch through both folds, and the reduced tip-mass
    model's on the lane engine."""
    beam = continue_beam_branch("frequency", 200.0, 280.0, "bimorph_tip", n_modes=1,
                                step=0.02)
    p = resolve_beam_parameters("bimorph_tip", n_modes=1)
    reduced = bm.as_tip_mass_parameters(bimorph(p))
    tip = continue_branch("paper", "frequency", 200.0, 280.0, **reduced)
    return beam, tip.dataset if hasattr(tip, "dataset") else tip, reduced


def test_the_one_mode_beams_folds_and_grazing_are_the_tip_mass_models(branches):
    beam, tip, _ = branches
    found, expected = _located(beam), _located(tip)
    assert [kind for kind, _ in found] == [kind for kind, _ in expected] \
        == ["fold", "fold", "grazing"]
    for (_, f_beam), (_, f_tip) in zip(found, expected):
        assert f_beam == pytest.approx(f_tip, rel=1e-7)
    # each located again at twice its steps moved by its reported shift: the two engines'
    # locations differ by no more than twice the two shifts
    shifts = [sorted(zip(ds["frequency"].values[ds["bifurcation"].values > 0],
                         ds["frequency_shift"].values[ds["bifurcation"].values > 0]))
              for ds in (beam, tip)]
    for (f_beam, s_beam), (f_tip, s_tip) in zip(*shifts):
        assert abs(f_beam - f_tip) <= 2 * (abs(s_beam) + abs(s_tip))
        assert abs(s_beam) <= 1e-7 * f_beam  # (located to the accuracy target)
    # the branch between its folds is unstable, outside them stable
    folds = sorted(f for kind, f in found if kind == "fold")
    inside = (beam["frequency"] > folds[0] + 1) & (beam["frequency"] < folds[1] - 1)
    assert set(beam["stable"].values[inside.values]) >= {0}
    assert beam["frequency"].values[-1] >= 280.0
    # every point is measured on its own orbit, the unstable ones too (a measurement
    # that ran on to the attractor jumped to the other branch's power)
    power = beam["power"].values
    assert np.abs(np.diff(power)).max() <= 0.2 * (power.max() - power.min())


def test_branch_points_meet_the_accuracy_and_are_within_twice_their_estimates(branches):
    """Every point's estimate is at or below the accuracy asked; where the orbit is the
    only one (below the lower fold, above the upper), the reduced tip-mass model solved by
    the lane engine at 1e-10 agrees with each point within twice its estimate."""
    beam, _, reduced = branches
    estimate = beam["error_estimate"].values
    assert np.isfinite(estimate).all() and estimate.max() <= 1e-7
    f = beam["frequency"].values
    alone = np.flatnonzero((beam["stable"].values == 1) & ((f < 223.0) | (f > 262.0)))
    for k in alone[::max(1, len(alone) // 6)]:
        m = run_scene("paper", **reduced, frequency=float(f[k]), accuracy=1e-10).metrics
        reach = max(abs(m["x_max"]), abs(m["x_min"]))
        for name, size in (("power", abs(m["power"])), ("v_peak", m["v_peak"]),
                           ("x_max", reach), ("x_min", reach)):
            assert abs(float(beam[name][k]) - m[name]) <= 2 * estimate[k] * size + 1e-12 * size


@pytest.mark.parametrize("kwargs, words", [
    (dict(parameter="n_modes"), "parameter"),
    (dict(step=0.5), "step"),
    (dict(max_points=1), "max_points"),
    (dict(start=-1.0), "frequency"),
    (dict(stop=140.0), r"stop \[Hz\] = 140.0: must differ from start"),  # (it divided by 0)
    # (the branch ran to the beam's length and ended there, unsaid)
    (dict(parameter="contact_position", start=0.025, stop=0.05),
     r"^stop: contact_position \[m\] = 0.05: must be in \(0, length"),
    # (it raised TypeError: got multiple values for keyword argument 'frequency')
    (dict(frequency=240.0), "^frequency: continued, so it cannot also be fixed"),
])
def test_bad_branch_options_are_refused(kwargs, words):
    options = dict(parameter="frequency", start=140.0, stop=150.0) | kwargs
    with pytest.raises(ParameterError, match=words):
        continue_beam_branch(options.pop("parameter"), options.pop("start"),
                             options.pop("stop"), "bimorph_tip", n_modes=1, **options)


def test_a_start_without_an_orbit_of_one_period_is_no_result_as_continues(tmp_path, capsys):
    """Two modes at 200 Hz settle on an orbit of five periods: no branch of period one
    starts there. As the tip-mass continue says of a start with no orbit: NoOrbitError,
    exit status 3 (beam-continue said it was bad input, exit 2)."""
    with pytest.raises(NoOrbitError, match="no settled orbit of one forcing period"):
        continue_beam_branch("frequency", 200.0, 280.0, "bimorph_tip", n_modes=2)
    argv = ["beam-continue", "frequency", "200", "280", "--set", "n_modes=2", "--output",
            str(tmp_path / "b.nc")]
    assert main(argv) == 3
    err = [line for line in capsys.readouterr().err.splitlines()
           if "compiling" not in line]  # (a cold cache's note comes first)
    assert len(err) == 1 and "no settled orbit" in err[0]


def test_a_period_doubling_switches_to_the_tip_mass_models_doubled_orbits():
    """The one-mode beam at its tip 0.5 um from the stop doubles its period at two
    frequencies; switched there, the branch of doubled orbits born at one ends at the
    other (followed once), and its orbits are the lane engine's of the reduced tip-mass
    model: both doublings within twice the two engines' shifts of the lane engine's, the
    doubled orbits' outputs within twice their estimates of its orbits at 1e-10."""
    beam = continue_beam_branch("frequency", 140.0, 165.0, "bimorph_tip", n_modes=1,
                                gap=0.5e-6, step=0.02, period_doubling="switch")
    p = resolve_beam_parameters("bimorph_tip", n_modes=1, gap=0.5e-6)
    reduced = dict(bm.as_tip_mass_parameters(bimorph(p)), gap=0.5e-6)
    tip = continue_branch("paper", "frequency", 140.0, 165.0, **reduced)
    tip = tip.dataset if hasattr(tip, "dataset") else tip
    assert sorted(set(beam["branch"].values)) == [0, 1]
    first = beam.where(beam["branch"] == 0, drop=True)
    found = _located(first)
    assert [kind for kind, _ in found] == [kind for kind, _ in _located(tip)] \
        == ["period_doubling", "period_doubling"]
    flagged = first["bifurcation"].values > 0
    pairs = zip(sorted(zip(first["frequency"].values[flagged],
                           first["frequency_shift"].values[flagged])),
                sorted(zip(tip["frequency"].values[tip["bifurcation"].values > 0],
                           tip["frequency_shift"].values[tip["bifurcation"].values > 0])))
    for (f_beam, s_beam), (f_tip, s_tip) in pairs:
        assert abs(f_beam - f_tip) <= 2 * (abs(s_beam) + abs(s_tip))
    doubled = beam.where(beam["branch"] == 1, drop=True)
    assert set(doubled["orbit_period"].values.astype(int)) == {2}
    births = sorted(f for _, f in found)
    assert doubled["frequency"].min() == pytest.approx(births[0], abs=0.5)
    assert doubled["frequency"].max() == pytest.approx(births[1], abs=0.5)
    stable = np.flatnonzero(doubled["stable"].values == 1)
    assert len(stable) > 10
    for k in stable[len(stable) // 4::len(stable) // 4][:3]:
        f = float(doubled["frequency"][k])
        m = run_scene("paper", **reduced, frequency=f, accuracy=1e-10).metrics
        assert m["orbit_period"] == 2
        estimate = float(doubled["error_estimate"][k])
        reach = max(abs(m["x_max"]), abs(m["x_min"]))
        for name, size in (("power", m["power"]), ("v_peak", m["v_peak"]),
                           ("x_max", reach)):
            assert abs(float(doubled[name][k]) - m[name]) <= 2 * estimate * size
