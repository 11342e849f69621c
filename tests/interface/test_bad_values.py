"""Any value a TOML sweep file can hold is either accepted or refused with a ParameterError
(issue 22): a boolean, string, date, array or table is never taken for a number."""

from __future__ import annotations

import datetime
import math
import numbers
import warnings
from unittest import mock

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from harvester_sweep import cli, sweep_file
from harvester_sweep.parameters import PARAMETERS, ParameterError, resolve_parameters
from harvester_sweep.sweep_file import SweepSpec, load_sweep

# What tomllib can give for a value: scalars, arrays and tables of them, nested (small).
SCALARS = st.one_of(
    st.booleans(),
    st.integers(),  # (tomllib reads integers of any size)
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
    st.datetimes(timezones=st.none() | st.just(datetime.timezone.utc)),
    st.dates(),
    st.times(),
)
TOML_VALUES = st.recursive(
    SCALARS,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner,
                                                                max_size=3),
    max_leaves=6,
)
NUMERIC = [name for name, p in PARAMETERS.items() if p.kind in ("float", "int")]
NOT_NUMBERS = [True, False, "1e-3", "", datetime.date(2020, 1, 1), datetime.time(12, 0),
               datetime.datetime(2020, 1, 1, 12, 0), [1.0], [], {"value": 1.0}, {}]


def _unit(name: str) -> str:
    unit = PARAMETERS[name].unit
    return f"[{'-' if unit == '1' else unit}]"


def _with_grid(parameters: dict) -> dict:
    """A one-point sweep setting ``parameters``, on an axis none of them names."""
    axis = "gap" if "frequency" in parameters else "frequency"
    return {"parameters": parameters, "grid": {axis: [1e-6 if axis == "gap" else 140.0]}}


def _spec_or_parameter_error(source):
    """load_sweep(source): the spec, or the ParameterError; any other exception fails."""
    with warnings.catch_warnings():  # (a StabilityWarning is an answer too)
        warnings.simplefilter("ignore")
        try:
            spec = load_sweep(source)
        except ParameterError as error:
            assert "\n" not in str(error), str(error)
            return error
    assert isinstance(spec, SweepSpec)
    return spec


def _is_number(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


@settings(max_examples=300, deadline=None)
@given(name=st.sampled_from(list(PARAMETERS)), value=TOML_VALUES)
@example(name="mass", value=True)
@example(name="steps_per_period", value=True)
@example(name="frequency", value="140")
@example(name="gap", value=datetime.date(2020, 1, 1))
@example(name="locate_switches", value=1)
@example(name="locate_switches", value=0.0)
@example(name="contact_law", value=["flores"])
@example(name="tip_material", value={"name": "steel"})
@example(name="mass", value=10**400)
@example(name="steps_per_period", value=10**400)
@example(name="resistance", value=1e300)
@example(name="natural_frequency", value=1e300)
def test_any_toml_value_of_a_parameter_is_accepted_or_refused_in_one_line(name, value):
    result = _spec_or_parameter_error(_with_grid({name: value}))
    kind = PARAMETERS[name].kind
    if kind in ("float", "int") and not _is_number(value):
        assert isinstance(result, ParameterError), f"{name} = {value!r} taken as a number"
        message = str(result)
        assert message.startswith(f"{name} {_unit(name)} = ") and "must be" in message
    if kind == "bool" and not isinstance(value, (bool, str)):
        assert isinstance(result, ParameterError), f"{name} = {value!r} taken as a boolean"
        assert str(result).startswith(f"{name} [-] = ") and "true or false" in str(result)
    if kind == "choice" and value not in PARAMETERS[name].choices:
        assert isinstance(result, ParameterError), f"{name} = {value!r} taken as a choice"


@pytest.mark.parametrize("name", NUMERIC)
def test_no_toml_non_number_is_taken_for_a_number(name):
    for value in NOT_NUMBERS:
        with pytest.raises(ParameterError) as info:
            load_sweep(_with_grid({name: value}))
        message = str(info.value)
        assert message.startswith(f"{name} {_unit(name)} = {value!r} is not a number: must be "
                                  f"{PARAMETERS[name].range_text()}"), message


def test_remembered_checks_tell_bools_from_numbers():
    """The checks are remembered by value: 1 and True are equal keys but not the same input."""
    assert resolve_parameters("paper", mass=1)["mass"] == 1.0
    with pytest.raises(ParameterError, match=r"mass \[kg\] = True is not a number"):
        resolve_parameters("paper", mass=True)
    assert resolve_parameters("paper", locate_switches=True)["locate_switches"] is True
    assert resolve_parameters("paper", locate_switches="No")["locate_switches"] is False
    assert resolve_parameters("paper", locate_switches=np.bool_(False))["locate_switches"] is False
    for value in (1, 0, 1.0, np.int64(1)):
        with pytest.raises(ParameterError, match="must be true or false"):
            resolve_parameters("paper", locate_switches=value)
    # numpy numbers are numbers (a grid's values reach the checks as numpy scalars)
    assert resolve_parameters("paper", steps_per_period=np.int64(2048))["steps_per_period"] == 2048
    assert resolve_parameters("paper", gap=np.float32(1e-6))["gap"] == pytest.approx(1e-6)
    # an optional parameter's None is "unset", a required one's is not a number
    assert resolve_parameters("paper", contact_damping=None)["contact_damping"] is None
    with pytest.raises(ParameterError, match=r"mass \[kg\] = None is not a number"):
        resolve_parameters("paper", mass=None)


@pytest.mark.parametrize("overrides, words", [
    # c_h k_h v overflows: the damping's penetration taken apart, its rate ~ c_h^0.4
    (dict(contact_damping=1e300), "too stiff: the contact damping"),
    (dict(contact_damping=1.7e308), "too stiff: the contact damping"),
    # c_h = 3 (1 - e^2) / (4 v_imp) is inf: no rate to take a step from
    (dict(impact_velocity=5e-324), "beyond double precision"),
    (dict(contact_law="flores", impact_velocity=1e-320), "beyond double precision"),
])
def test_a_contact_damping_beyond_double_precision_is_refused_before_integration(
        overrides, words):
    """Each value in its range, the contact damping rate they make overflows: the point is
    refused in one line before any integration, not given the coarsest step (64 a period)
    at which it diverges (exit 3)."""
    from harvester_sweep.packing import check_runnable

    with pytest.raises(ParameterError) as info:
        check_runnable(resolve_parameters("paper", **overrides))
    assert words in str(info.value) and "\n" not in str(info.value)


SWEEP_KEYS = ("directions", "outputs", "samples", "chunk_size", "error_estimate")


@settings(max_examples=300, deadline=None)
@given(where=st.sampled_from(("preset", "parameters", "axis", "range") + SWEEP_KEYS),
       value=TOML_VALUES,
       part=st.sampled_from(("start", "stop", "num", "scale")))
@example(where="preset", value=["a"], part="start")
@example(where="preset", value={"x": 1}, part="start")
@example(where="preset", value=True, part="start")
@example(where="parameters", value={"preset": "paper"}, part="start")
@example(where="axis", value=[[140.0, 150.0]], part="start")
@example(where="axis", value={"a\nkey": 1.0}, part="start")  # (one line)
@example(where="range", value=10**400, part="start")
@example(where="range", value=2**70, part="stop")
@example(where="range", value=10**12, part="num")
@example(where="outputs", value=[["power"]], part="start")
@example(where="error_estimate", value={"x": 1}, part="start")
def test_any_toml_value_anywhere_in_a_sweep_is_accepted_or_refused(where, value, part):
    if where == "preset":
        source = {"preset": value, "grid": {"frequency": [140.0]}}
    elif where == "parameters":
        source = {"parameters": value, "grid": {"frequency": [140.0]}}
    elif where == "axis":
        source = {"grid": {"frequency": value}}
    elif where == "range":
        entry = {"start": 100.0, "stop": 200.0, "num": 3, part: value}
        source = {"grid": {"frequency": entry}}
    else:
        outputs = {"outputs": ["power", "strobe"]} if where == "samples" else {}
        source = {"grid": {"frequency": [140.0]}, "sweep": {**outputs, where: value}}
    # (a shorter longest axis: the refusal of a long one is what is tested, not its checks)
    with mock.patch.object(sweep_file, "MAX_AXIS_POINTS", 1000):
        result = _spec_or_parameter_error(source)
    if where == "preset" and value not in ("paper", "strong_coupling"):
        assert isinstance(result, ParameterError)
    if where == "range" and part in ("start", "stop", "num") and not _is_number(value):
        assert isinstance(result, ParameterError)


def test_the_cli_refuses_a_boolean_mass_in_one_line(tmp_path, capsys):
    toml = tmp_path / "sweep.toml"
    toml.write_text("[parameters]\nmass = true\n[grid]\nfrequency = [140.0]\n")
    out = tmp_path / "out.nc"
    assert cli.main(["run", str(toml), "--output", str(out), "--quiet"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.count("\n") == 1 and captured.err.endswith("\n")
    assert captured.err.startswith("harvester-sweep: error: mass [kg] = True is not a number")
    assert not out.exists() and not (tmp_path / "out.nc.partial").exists()


def test_large_toml_integers_are_refused_not_overflowed(tmp_path):
    """tomllib reads integers of any size; float() of a huge one raises OverflowError."""
    toml = tmp_path / "sweep.toml"
    toml.write_text(f"[parameters]\nmass = {10**400}\n[grid]\nfrequency = [140.0]\n")
    with pytest.raises(ParameterError, match=r"mass \[kg\] = 1000.*must be a finite number"):
        load_sweep(toml)
    toml.write_text(f"[parameters]\nmass = {'9' * 5000}\n[grid]\nfrequency = [140.0]\n")
    with pytest.raises(ParameterError, match="not valid TOML"):
        load_sweep(toml)
    assert math.isfinite(load_sweep({"grid": {"frequency": [140]}}).grid["frequency"][0])
