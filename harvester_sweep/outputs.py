"""The one registry of outputs: every metric, status and recorded variable, with its
name, CF units, long name and dtype.

Everything that names an output is made from here: the engine's metric row is read
through :func:`metric_index` (its order is the engine's, layouts.METRIC), the datasets'
attributes, the CF ``flag_values``/``flag_meanings`` of ``status``, the scene's table and
JSON, the command line's counts, the plots' labels and the guide's table of outputs
(:func:`markdown_table`). The names are the public interface: chosen once, kept.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._engine import MAX_ORBIT_PERIOD, METRIC, STATE, STATUS


@dataclass(frozen=True)
class Output:
    """One output variable.

    Attributes
    ----------
    name : str
        Its name in datasets, JSON and tables.
    units : str
        CF units (``"1"`` for a dimensionless number).
    long_name : str
        CF long name.
    dtype : str
        numpy dtype of the dataset variable.
    comment : str
        CF comment: when the value is missing, or how it is made.
    where : str
        ``"engine"`` (a column of the engine's metric row), ``"run"`` (made around the
        engine by the periodic-orbit solver: error estimate, multipliers, work done),
        ``"scene"`` (a scene's only), ``"sweep"``, ``"basin"`` (basins of attraction,
        :mod:`harvester_sweep.basins`) or ``"branch"`` (a branch of orbits,
        :mod:`harvester_sweep.continuation`).
    dims : tuple of str
        Its own dimensions, after those of the point (``multiplier``).
    """

    name: str
    units: str
    long_name: str
    dtype: str = "float64"
    comment: str = ""
    where: str = "engine"
    dims: tuple = ()

    @property
    def attrs(self) -> dict:
        """CF attributes of the dataset variable."""
        attrs = {"units": self.units, "long_name": self.long_name}
        if self.comment:
            attrs["comment"] = self.comment
        if self.name == "status":
            attrs.update(STATUS_FLAGS)
        if self.name == "bifurcation":
            attrs.update(BIFURCATION_FLAGS)
        return attrs

    def label(self, prefix: str = "") -> str:
        """Axis label ``name [unit]``, the unit with an SI ``prefix``."""
        return f"{self.name} [{prefix}{'-' if self.units == '1' else self.units}]"


@dataclass(frozen=True)
class Status:
    """One outcome of a point: its code (the engine's), name and what it means."""

    code: int
    name: str
    meaning: str

    @property
    def flag(self) -> str:
        """Its CF flag meaning (a word, no spaces)."""
        return self.name.replace(" ", "_")


STATUSES: tuple[Status, ...] = (
    Status(STATUS.settled, "settled", "steady state found"),
    Status(STATUS.not_settled, "not settled",
           "no steady state within max_periods: metrics over the last periods run, "
           f"{MAX_ORBIT_PERIOD} at most"),
    Status(STATUS.diverged, "diverged",
           "the integration diverged (step too coarse for the contact): no metrics"),
    Status(STATUS.too_stiff, "too stiff",
           "refused before integration: its step would exceed max_steps_per_period"),
)
assert [s.code for s in STATUSES] == list(STATUS)
STATUS_NAMES = tuple(s.name for s in STATUSES)
STATUS_FLAGS = {"flag_values": np.array([s.code for s in STATUSES], dtype="i1"),
                "flag_meanings": " ".join(s.flag for s in STATUSES)}

#: What happens to a branch of orbits at a point (harvester_sweep.continuation): the flag
#: values are the positions, 0 for none.
BIFURCATIONS = {
    "none": "a regular point of the branch",
    "fold": "the branch turns back in the parameter: a Floquet multiplier passes +1",
    "period_doubling": "a Floquet multiplier passes -1: an orbit of twice the period is born",
    "neimark_sacker": "a complex pair of Floquet multipliers passes the unit circle",
    "grazing": "the orbit's x_max reaches a rigid stop's gap, or its x_min the lower stop: "
               "contact switches on or off",
}
BIFURCATION_FLAGS = {"flag_values": np.arange(len(BIFURCATIONS), dtype="i1"),
                     "flag_meanings": " ".join(BIFURCATIONS)}

_NO_IMPACT = "NaN when the orbit has no impact (impacts_per_period = 0)"
_NOT_SETTLED = "NaN where the point did not settle"
_PEAK = ("the top of the quartic through the force at three step ends and its rate at two: "
         "its error falls as RK4's; not in error_estimate, as near a grazing the force "
         "tends to 0 (docs/numerics.md)")
_APPROACH = ("not in error_estimate: at a slow impact its error can be far larger "
             "(docs/numerics.md)")
_OUTPUTS = (
    # the engine's metric row, in its order
    Output("power", "W", "mean electrical power V_rms^2/R over the orbit"),
    Output("v_rms", "V", "root mean square voltage over the orbit"),
    Output("v_peak", "V", "peak absolute voltage over the orbit"),
    Output("power_peak", "W", "peak instantaneous electrical power v_peak^2/R"),
    Output("x_max", "m", "largest tip displacement (positive towards the stop)"),
    Output("x_min", "m", "smallest tip displacement"),
    Output("contact_force_max", "N", "peak contact force of the (upper) stop", comment=_PEAK),
    Output("impacts_per_period", "1", "impacts on the (upper) stop per forcing period"),
    Output("approach_velocity", "m/s", "mean tip velocity at first touch of the (upper) stop",
           comment=f"{_NO_IMPACT}; {_APPROACH}"),
    Output("impacts_per_period_lower", "1", "impacts on the lower stop per forcing period "
           "(0 without one)"),
    Output("contact_force_max_lower", "N", "peak contact force of the lower stop (0 without "
           "one)", comment=_PEAK),
    Output("stop_displacement_max", "m", "largest displacement |x_s| of the (upper) stop "
           "relative to the base (0 for a rigid stop)"),
    Output("contact_force_spread", "N", "impact-to-impact spread of the (upper) stop's peak "
           "contact force over the orbit: largest minus smallest peak",
           comment="0 without impacts; NaN where no contact lasted three steps (no peak "
                   "located)"),
    Output("near_miss", "m", "smallest distance by which the top of one of the orbit's swings "
           "stays short of a rigid stop: the gap less the largest x of a swing that does not "
           "touch (0 at a grazing)",
           comment="NaN where every swing touches, or without a rigid stop"),
    Output("approach_velocity_min", "m/s", "smallest tip velocity relative to the stop at "
           "the first touch of an impact over the orbit, either stop (0 at a grazing)",
           comment=f"NaN when the orbit has no impact on either stop; {_APPROACH}"),
    Output("orbit_period", "1", "forcing periods per orbit (0 when not settled)", "int32"),
    Output("status", "1", "outcome of the run", "int8",
           comment="; ".join(f"{s.code} {s.name}: {s.meaning}" for s in STATUSES)),
    Output("periods_run", "1", "forcing periods of the motion integrated before its orbit "
           "was found (the Newton iterates and their perturbed copies not counted)", "int32"),
    # made around the engine by the periodic-orbit solver
    Output("error_estimate", "1", "estimated relative error of power, v_peak, x_max, "
           "x_min and a moving stop's stop_displacement_max (the beam: root_strain_max and "
           "stop_face_max too): their change when the orbit is solved again at twice the "
           "steps per period (the beam: and half the contact step)",
           comment="NaN where not estimated or not settled", where="run"),
    Output("spectral_radius", "1", "largest modulus of the Floquet multipliers: the orbit "
           "is stable below 1", comment=_NOT_SETTLED, where="run"),
    Output("floquet_multipliers_real", "1", "real parts of the Floquet multipliers, the "
           "eigenvalues of the monodromy matrix over orbit_period forcing periods, largest "
           "modulus first", comment=_NOT_SETTLED, where="run", dims=("multiplier",)),
    Output("floquet_multipliers_imag", "1", "imaginary parts of the Floquet multipliers, in "
           "the order of floquet_multipliers_real", comment=_NOT_SETTLED, where="run",
           dims=("multiplier",)),
    Output("steps_per_period", "1", "RK4 steps per forcing period of the orbit reported "
           "(finer than chosen where the accuracy target asked for it)", "int64", where="run"),
    Output("rk4_steps", "1", "RK4 steps taken for the point: its motion, the Newton iterates "
           "with their perturbed copies, the error estimate and any re-solve", "int64",
           where="run"),
    Output("converged", "1", "steady state reached within the budget of periods (1) or not "
           "(0)", "int8", where="scene"),
    Output("run_time", "s", "wall-clock integration time", where="scene"),
    # the basins of one point's coexisting attractors
    Output("basin_fraction", "1", "fraction of the initial states drawn that reach this "
           "attractor", where="basin"),
    Output("basin_fraction_error", "1", "binomial standard error of basin_fraction, "
           "sqrt(f (1 - f) / samples)", where="basin"),
    Output("impact_basin_fraction", "1", "fraction of the initial states that reach an orbit "
           "striking the stop (NaN where none reaches an orbit)", where="basin"),
    Output("impact_basin_fraction_error", "1", "binomial standard error of "
           "impact_basin_fraction", where="basin"),
    Output("fraction_not_settled", "1", "fraction of the initial states whose motion did "
           "not settle within max_periods", where="basin"),
    Output("fraction_diverged", "1", "fraction of the initial states whose integration "
           "diverged", where="basin"),
    # a branch of orbits (harvester_sweep.continuation), along point
    Output("stable", "1", "the orbit is stable (1: spectral radius below 1) or not (0)",
           "int8", where="branch"),
    Output("bifurcation", "1", "bifurcation located at this point of the branch",
           "int8", comment="; ".join(f"{k} {name}: {meaning}" for k, (name, meaning)
                                     in enumerate(BIFURCATIONS.items())), where="branch"),
    Output("branch", "1", "branch of the point: 0 from rest at start, then the branches "
           "switched to at period doublings, in the order found", "int16", where="branch"),
    Output("arclength", "1", "pseudo-arclength from the branch's first point, in the "
           "scaled components (x, v, V by the start orbit's amplitudes, the parameter by "
           "the range)", where="branch"),
    Output("orbit_displacement", "m", "tip displacement x on the orbit at forcing phase 0 "
           "(t = nT): where the branch's period map is solved", where="branch"),
    Output("orbit_velocity", "m/s", "tip velocity dx/dt on the orbit at forcing phase 0",
           where="branch"),
    Output("orbit_voltage", "V", "voltage across the load V on the orbit at forcing phase 0",
           where="branch"),
    # a sweep's stroboscopic samples and a scene's recorded orbit
    Output("strobe_displacement", "m", "tip displacement x at the last forcing period "
           "boundaries y(nT)", where="sweep"),
    Output("strobe_voltage", "V", "voltage across the load V at the last forcing period "
           "boundaries y(nT)", where="sweep"),
    # the beam model's own (harvester_sweep.beam_runs); it books the metrics above that
    # it shares, where="engine" and "run", under the same names
    Output("contact_displacement_max", "m", "largest displacement of the beam at the contact "
           "position (positive towards the stop)", where="beam"),
    Output("contact_displacement_min", "m", "smallest displacement of the beam at the contact "
           "position", where="beam"),
    Output("root_strain_max", "1", "largest magnitude of the bending strain at the root's "
           "outer piezo surface over the orbit", where="beam"),
    Output("root_stress_piezo", "Pa", "largest magnitude of the bending stress at the root's "
           "outer piezo surface, Y_p times root_strain_max", where="beam"),
    Output("root_stress_substrate", "Pa", "largest magnitude of the bending stress at the "
           "root's outer substrate surface", where="beam"),
    Output("modal_amplitude", "m kg0.5", "largest magnitude of each bending mode's "
           "mass-normalised coordinate over the orbit", where="beam", dims=("mode",)),
    Output("stop_face_max", "m", "largest displacement of the rod stop's contact face "
           "towards its base (absent with a rigid stop)", where="beam"),
    Output("contact_step", "s", "RK4 sub-step in contact of the orbit reported", where="beam"),
)
OUTPUTS: dict[str, Output] = {o.name: o for o in _OUTPUTS}

#: The engine's metrics, in the order of its metric row.
ENGINE_METRICS = tuple(o.name for o in _OUTPUTS if o.where == "engine")
assert ENGINE_METRICS == METRIC._fields, "the registry and the engine's metric row differ"

#: The solver's outputs every sweep stores beside its metrics (the error estimate is stored
#: as sweep.error_estimate says).
RUN_OUTPUTS = tuple(o.name for o in _OUTPUTS if o.where == "run" and o.name != "error_estimate")

#: A scene's outputs (table, JSON, dataset): the engine's, the solver's and its own.
SCENE_OUTPUTS = tuple(o.name for o in _OUTPUTS if o.where in ("engine", "run", "scene"))

#: The stroboscopic samples a sweep keeps, in the order of a chunk's ``strobe`` columns:
#: dataset variable -> column of the engine's samples (layouts.STATE).
STROBES = {"strobe_displacement": STATE.x, "strobe_voltage": STATE.voltage}

#: A scene's recorded orbit: the columns of the engine's series (layouts.SERIES), in order,
#: then the instantaneous power V^2/R.
SERIES = {
    "displacement": Output("displacement", "m", "tip displacement relative to the base x"),
    "velocity": Output("velocity", "m/s", "tip velocity dx/dt"),
    "voltage": Output("voltage", "V", "voltage across the load V"),
    "contact_force": Output("contact_force", "N", "contact force of the stops: the upper "
                            "stop's F_c positive, a lower stop's negative"),
    "stop_displacement": Output("stop_displacement", "m", "displacement of the (upper) stop "
                                "relative to the base x_s (0 for a rigid stop)"),
    "stop_velocity": Output("stop_velocity", "m/s", "velocity of the (upper) stop dx_s/dt"),
    "instantaneous_power": Output("instantaneous_power", "W",
                                  "instantaneous electrical power V^2/R"),
}


def metric_index(name: str) -> int:
    """Column of metric ``name`` in the engine's metric row."""
    return getattr(METRIC, name)


def markdown_table() -> str:
    """The table of outputs in docs/guide.md: name, units, meaning, when missing."""
    rows = ["| name | unit | meaning |", "| --- | --- | --- |"]
    for o in _OUTPUTS:
        meaning = o.long_name + (f" ({o.comment})" if o.comment and o.name != "status" else "")
        if o.name == "status":
            meaning += ": " + ", ".join(f"{s.code} {s.name}" for s in STATUSES)
        scope = {"scene": " (scene only)", "sweep": " (sweep, over `sample`)",
                 "basin": " (`basin_fractions`, `basin_map`)",
                 "branch": " (`continue_branch`)",
                 "beam": " (beam model)"}.get(o.where, "")
        rows.append(f"| `{o.name}` | {'-' if o.units == '1' else o.units} | {meaning}{scope} |")
    return "\n".join(rows)


if __name__ == "__main__":  # python -m harvester_sweep.outputs: the guide's table
    print(markdown_table())
