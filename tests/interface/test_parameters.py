"""Bad input fails before any integration, naming the parameter, its unit and its range."""

import math
import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harvester_sweep import (
    PARAMETERS,
    ParameterError,
    TooStiffError,
    resolve_parameters,
    run_scene,
    timescales,
)
from harvester_sweep.materials import MATERIALS, hertz_stiffness_from_bodies
from harvester_sweep.packing import check_runnable, refusal
from harvester_sweep.parameters import StabilityWarning

FLOATS = [name for name, spec in PARAMETERS.items() if spec.kind == "float"]


@pytest.mark.parametrize(
    "name, value, unit",
    [("mass", 0.0, "[kg]"), ("mass", -1e-3, "[kg]"), ("restitution", 0.0, "[-]"),
     ("restitution", 1.01, "[-]"), ("frequency", -5.0, "[Hz]"), ("capacitance", 0.0, "[F]"),
     ("hertz_stiffness", -1.0, "[N/m^1.5]"), ("steps_per_period", 8, "[-]"),
     ("steps_per_period", 100.5, "[-]"), ("contact_law", "plastic", "[-]")],
)
def test_out_of_range_names_parameter_unit_and_range(name, value, unit):
    with pytest.raises(ParameterError) as info:
        run_scene("paper", **{name: value})
    message = str(info.value)
    assert message.startswith(f"{name} {unit}") and "must be" in message
    assert "\n" not in message


@settings(max_examples=40, deadline=None)
@given(name=st.sampled_from(FLOATS), value=st.sampled_from([math.nan, math.inf, -math.inf]))
def test_non_finite_values_are_refused(name, value):
    with pytest.raises(ParameterError, match=name):
        resolve_parameters("paper", **{name: value})


def test_unknown_names_are_refused():
    with pytest.raises(ParameterError, match="unknown parameter 'gapp'"):
        run_scene("paper", gapp=1e-6)
    with pytest.raises(ParameterError, match="preset 'papr'"):
        run_scene("papr")


def test_step_too_coarse_for_forcing_or_circuit():
    with pytest.raises(ParameterError, match="steps_per_period .* >= 18"):
        resolve_parameters("paper", frequency=140.0, natural_frequency=150.0, steps_per_period=16)
    with pytest.raises(ParameterError, match="stability bound .* load circuit"):
        resolve_parameters("paper", resistance=10.0, steps_per_period=1024)


def test_automatic_step_respects_every_bound():
    """Unset steps_per_period: resolved per point within the circuit and contact bounds."""
    p = resolve_parameters("paper", resistance=10.0)
    step = 1 / (p["frequency"] * p["steps_per_period"])
    assert step <= 2.5 * 10.0 * 100e-9
    stiff = resolve_parameters("paper", hertz_stiffness=9.03e11)
    assert stiff["steps_per_period"] > 8 * resolve_parameters("paper")["steps_per_period"]
    default = resolve_parameters("paper")["steps_per_period"]
    assert resolve_parameters("paper", accuracy=1e-9)["steps_per_period"] > 2 * default


def test_explicit_step_beyond_contact_bound_warns():
    with pytest.warns(StabilityWarning, match="stability bound .* contact"):
        resolve_parameters("paper", hertz_stiffness=9.03e11, steps_per_period=512)


def test_an_absurd_stiffness_is_refused_in_a_readable_line():
    """A tip mass of 1e-300 kg asks 6e145 steps per period: the line printed that count and
    its time in seconds in full, 150 digits each."""
    with pytest.raises(TooStiffError,
                       match=r" \d\.\d+e\+\d+ steps per period, about \d\.\d+e\+\d+ s "):
        run_scene("paper", mass=1e-300)


def test_too_stiff_is_refused_with_step_and_time():
    """Resolved (its step chosen), then refused by packing before any integration."""
    p = resolve_parameters("paper", contact_damping=1.07e11, max_steps_per_period=100_000)
    assert p["steps_per_period"] > 100_000
    with pytest.raises(TooStiffError, match=r"too stiff: .* needs a step <= .* s, \d+ steps "
                       r"per period, about [\d.]+ s per point"):
        run_scene("paper", contact_damping=1.07e11, max_steps_per_period=100_000)


def test_a_refusal_says_a_short_time_and_which_step_it_refuses():
    """A point refused at a low max_steps_per_period said "about 0 s per point" (its time
    rounded to whole seconds); a step asked for above max_steps_per_period was refused in
    words about the contact damping, which had not set it."""
    low = resolve_parameters("paper", max_steps_per_period=16)
    said = float(re.search(r"about ([\d.e+-]+) s per point", refusal(low)).group(1))
    assert said == pytest.approx(timescales.run_time_estimate(low["steps_per_period"]),
                                 rel=0.05)
    assert said > 0
    asked = resolve_parameters("paper", steps_per_period=5000, max_steps_per_period=2000)
    with pytest.raises(TooStiffError, match=r"^too stiff: steps_per_period \[-\] asks 5000 "
                       r"steps per period, above max_steps_per_period, about [\d.]+ s per "
                       r"point; raise max_steps_per_period \[-\] \(now 2000\)"):
        check_runnable(asked)
    assert "contact damping" not in refusal(asked)


def test_paper_preset_states_its_assumptions():
    p = resolve_parameters("paper")
    k = p["mass"] * (2 * math.pi * p["natural_frequency"]) ** 2
    assert p["coupling"] == pytest.approx(k * 190e-12)
    assert p["capacitance"] == 100e-9
    notes = " ".join(run_scene("paper", max_periods=1).notes)
    assert "100 nF is assumed" in notes


def test_hertz_stiffness_matches_johnson_form():
    """Goldsmith's form (MODEL.md) equals Johnson's k = 4/3 E* sqrt(R*)."""
    cu, steel = MATERIALS["copper"], MATERIALS["steel"]
    r1 = (3 * 2.5e-3 / (4 * math.pi * cu.density)) ** (1 / 3)
    r2 = (3 * 0.05 / (4 * math.pi * steel.density)) ** (1 / 3)
    e_star = 1 / ((1 - cu.poissons_ratio**2) / cu.youngs_modulus
                  + (1 - steel.poissons_ratio**2) / steel.youngs_modulus)
    expected = 4 / 3 * e_star * math.sqrt(r1 * r2 / (r1 + r2))
    assert hertz_stiffness_from_bodies(2.5e-3, "copper", 0.05, "steel") == pytest.approx(
        expected, rel=1e-12)
    p = resolve_parameters("paper", stop_mass=0.05)
    assert p["hertz_stiffness"] == pytest.approx(expected, rel=1e-12)
    with pytest.raises(ParameterError, match="not both"):
        resolve_parameters("paper", stop_mass=0.05, hertz_stiffness=1e9)


def test_a_replaced_preset_is_checked_again(monkeypatch):
    # A preset's values are checked once and kept (a sweep resolves every point from it):
    # a preset put in PRESETS later, or replaced, is checked as itself; the built-in ones
    # are read-only.
    from harvester_sweep import PRESETS

    assert resolve_parameters("paper")["mass"] == PRESETS["paper"]["mass"]
    with pytest.raises(TypeError):
        PRESETS["paper"]["mass"] = 1.0
    monkeypatch.setitem(PRESETS, "paper", {**PRESETS["paper"], "mass": -1.0})
    with pytest.raises(ParameterError, match=r"mass \[kg\] = -1"):
        resolve_parameters("paper")
    monkeypatch.setitem(PRESETS, "mine", {**PRESETS["strong_coupling"], "mass": 2e-3})
    assert resolve_parameters("mine", gap=2e-6)["mass"] == 2e-3


@settings(max_examples=60, deadline=None)
@given(gaps=st.lists(st.sampled_from([-3e-6, -1e-7, 0.0, 1e-7, 2e-6, 4e-5, 3e-4, 1e-3, 1.0]),
                     min_size=2, max_size=4),
       frequency=st.sampled_from([60.0, 140.0, 150.0, 400.0]),
       stops=st.sampled_from([{}, {"lower_gap": 2e-6}, {"impact_velocity_mode": "latched"},
                              {"stop_support_stiffness": 2e4, "stop_mass": 1e-3,
                               "stop_support_damping": 0.05}]))
def test_what_is_remembered_across_gaps_is_what_each_gap_derives(gaps, frequency, stops):
    """Points that differ in their gap alone share their remembered time scales where the
    gap does the same to them (timescales._remembered): each point's time scales, step
    and budget are those derived afresh for its own gap, whichever gaps came before."""
    from harvester_sweep import timescales

    for gap in gaps:
        try:
            p = resolve_parameters("paper", gap=gap, frequency=frequency, **stops)
        except ParameterError:  # (a lower stop beside a preloaded upper one)
            continue
        # (and not on the step and budget chosen from them, which the key leaves out)
        chosen = {**p, "steps_per_period": 2 * p["steps_per_period"],
                  "max_periods": 3 * p["max_periods"]}
        for derive in (timescales.time_scales, timescales.auto_steps_per_period,
                       timescales.auto_max_periods, timescales.stability_steps):
            assert derive(p) == derive.__wrapped__(p) == derive.__wrapped__(chosen), (
                derive.__name__, gap)
