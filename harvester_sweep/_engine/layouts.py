"""Every row layout of the engine, declared once from named fields.

A layout is a named tuple of offsets: ``PARAM.gap`` is the gap's index in a point's
parameter row, ``LANE.x + j`` the displacement of lane ``j`` in the lane table. numba
reads a global named tuple as a constant, so that each offset is a constant in the
compiled code (what lets LLVM see that the lane loop's loads and stores never overlap,
and vectorize it). Sizes are ``len(LAYOUT)``, never written out.

Pure Python; the state's fields come from the model's declaration (harvester_sweep.models),
the layer below. The layers above read the same layouts.
"""

from __future__ import annotations

from collections import namedtuple

from ..models import tip_mass
from ..models.state import describe


def layout(name: str, fields: tuple, stride: int = 1):
    """A named tuple of the offsets ``i * stride`` of ``fields`` ((name, meaning) pairs)."""
    names = tuple(field for field, _ in fields)
    cls = namedtuple(name, names)
    cls.__doc__ = "Offsets of " + name + ":\n" + "\n".join(
        f"- {field}: {meaning}" for field, meaning in fields)
    return cls(*range(0, len(names) * stride, stride))


#: A point's state (the model's, then a moving stop's, then the latched velocity); also the
#: columns of a stroboscopic sample (all but the last).
STATE = layout("State", describe(tip_mass.STATE + tip_mass.STOP_STATE + (tip_mass.LATCHED,)))
#: Columns of a stroboscopic sample y(nT): the state without the latched velocity.
N_STROBE = len(tip_mass.STATE) + len(tip_mass.STOP_STATE)
#: Components of the period map of a point with a rigid stop: the model's (its stop stays
#: at 0).
N_RIGID = len(tip_mass.STATE)

#: A point's parameter row, as the engine reads it (made by harvester_sweep.packing).
PARAM = layout("ParameterRow", (
    ("amplitude", "base acceleration amplitude A [m/s^2]"),
    ("wn2", "k/m = wn^2 [1/s^2]"),
    ("cm", "c/m = 2 zeta wn [1/s]"),
    ("thm", "theta/m [N/(V kg)]"),
    ("khm", "k_h/m [N/(m^1.5 kg)]"),
    ("mass", "mass m [kg]"),
    ("gap", "gap g [m]"),
    ("ch", "contact damping c_h in fixed mode [s/m]"),
    ("latch", "factor c_h v_imp of the latched law, 0 in fixed mode [-]"),
    ("irc", "1/(R C_p) [1/s]"),
    ("thc", "theta/C_p [V s/m]"),
    ("resistance", "load resistance R [Ohm]"),
    ("period", "forcing period T [s]"),
    ("steps", "steps per period [-]"),
    ("max_periods", "budget of periods; 0: refused before integration (too stiff) [-]"),
    ("tolerance", "settle tolerance [-]"),
    ("x_limit", "|x| beyond this is divergence [m]"),
    ("locate", "1: locate contact switches inside the step, 0: plain fixed steps [-]"),
    ("v_per_x", "velocity scale per displacement, w [1/s] (settle test)"),
    ("voltage_per_x", "voltage scale per displacement, theta/C_p min(1, w R C_p) [V/m]"),
    ("phase", "forcing phase phi at each period's start: A sin(w t + phi), t from it [rad]"),
    # the lower stop at x = -lower_gap: NO_STOP when there is none
    ("lower_gap", "distance from rest to the lower stop g_l [m]"),
    ("lower_khm", "k_hl/m of the lower stop [N/(m^1.5 kg)]"),
    ("lower_ch", "contact damping of the lower stop in fixed mode [s/m]"),
    ("lower_latch", "factor c_h v_imp of the lower stop's latched law, 0 in fixed mode [-]"),
    # a stop on a spring (moving): stop_ratio 0 for a rigid stop
    ("stop_wn2", "k_s/m_s of the stop's support [1/s^2]"),
    ("stop_cm", "c_s/m_s of the stop's support [1/s]"),
    ("stop_ratio", "m/m_s, tip mass over stop mass; 0: a rigid stop [-]"),
    ("book", "1: every metric booked; 0: only the power, impacts and end state (see "
             "BOOKED_METRICS) [-]"),
    ("tangents", "1: the run carries the derivative of its end state by its start state, "
                 "the monodromy (lanes that can: tangents.carried), 0: not [-]"),
    ("multi", "steps a lane takes at once clear of the stops (lanes.resume; lanes that "
              "can: lanes.multi_steps), 1 or 0: one at a time [-]"),
))
#: PARAM.lower_gap of a point without a lower stop [m]: far beyond any motion, finite
#: (the kernel's arithmetic stays finite).
NO_STOP = 1e300

#: A point's metrics, in the engine's order; the names are the public ones
#: (harvester_sweep.outputs describes each).
METRIC = layout("MetricRow", (
    ("power", "mean V^2/R over the orbit [W]"),
    ("v_rms", "RMS voltage [V]"),
    ("v_peak", "peak |V| [V]"),
    ("power_peak", "v_peak^2/R [W]"),
    ("x_max", "largest displacement [m]"),
    ("x_min", "smallest displacement [m]"),
    ("contact_force_max", "peak contact force [N]"),
    ("impacts_per_period", "first touches per forcing period [-]"),
    ("approach_velocity", "mean velocity at first touch [m/s]"),
    ("impacts_per_period_lower", "first touches of the lower stop per forcing period [-]"),
    ("contact_force_max_lower", "peak contact force of the lower stop [N]"),
    ("stop_displacement_max", "largest |x_s| of the (upper) stop [m]"),
    ("contact_force_spread", "largest minus smallest peak force of the impacts [N]"),
    ("near_miss", "smallest distance a swing's top stays short of a rigid stop [m]"),
    ("approach_velocity_min", "smallest approach velocity at first touch of a stop [m/s]"),
    ("orbit_period", "forcing periods per orbit, 0 when not settled [-]"),
    ("status", "outcome, a code of STATUS [-]"),
    ("periods_run", "forcing periods integrated [-]"),
))
#: The metrics that are NaN for a point without a trustworthy orbit (diverged, refused).
N_VALUES = METRIC.orbit_period

#: The metrics a point booked without its extrema and force peaks (PARAM.book 0) lacks,
#: NaN: each is placed inside a step that the lane loop marks for scalar code. Runs whose
#: end states alone are read (a Newton iterate's perturbed copies) skip them.
BOOKED_METRICS = (METRIC.v_peak, METRIC.power_peak, METRIC.x_max, METRIC.x_min,
                  METRIC.contact_force_max, METRIC.contact_force_max_lower,
                  METRIC.contact_force_spread, METRIC.near_miss)

#: Outcome codes of a point (metric ``status``).
STATUS = namedtuple("Status", ("settled", "not_settled", "diverged", "too_stiff"))(0, 1, 2, 3)

#: A recorded series: one row per step boundary.
SERIES = layout("SeriesRow", (
    ("x", "tip displacement [m]"),
    ("v", "tip velocity [m/s]"),
    ("voltage", "voltage across the load [V]"),
    ("contact_force", "contact force of the stop [N]"),
    ("stop_displacement", "displacement of the (upper) stop [m]"),
    ("stop_velocity", "velocity of the (upper) stop [m/s]"),
))

#: Per-period accumulators, kept for the last MAX_ORBIT_PERIOD periods.
ACC = layout("Accumulators", (
    ("q", "int V^2 dt over the period [V^2 s]"),
    ("x_max", "largest x [m]"),
    ("x_min", "smallest x [m]"),
    ("v_max", "largest |v| [m/s]"),
    ("v_peak", "largest |V| [V]"),
    ("fc_max", "largest contact force [N]"),
    ("impacts", "first touches [-]"),
    ("sum_vimp", "sum of the approach velocities at first touch [m/s]"),
    ("impacts_lower", "first touches of the lower stop [-]"),
    ("fc_max_lower", "largest contact force of the lower stop [N]"),
    ("stop_x_max", "largest |x_s| [m]"),
    ("fc_peak_min", "smallest located peak of the upper stop's contact force [N]"),
    ("fc_peak_max", "largest located peak of the upper stop's contact force [N]"),
    ("near_miss", "smallest distance a swing's top stayed short of a rigid stop [m]"),
    ("vimp_min", "smallest approach velocity at first touch of a stop [m/s]"),
))

#: The lane table's rows a step reads that differ between one step and a multi-step
#: (lanes.resume): the contact-free map, the forcing's rotation, the lengths int V^2 dt is
#: taken over and whether the turns of v and V mark the step; each has an alt_ row.
MULTI_ROWS = ("mxx", "mxv", "mxe", "mxs", "mxc", "mvx", "mvv", "mve", "mvs", "mvc",
              "mex", "mev", "mee", "mes", "mec", "cos_step", "sin_step", "half_h", "h2_6",
              "turn_floor")

#: Points stepped together by one thread, and lanes that take the contact-free code together
#: (lanes.lane_steps writes out 2 groups).
LANES = 16
GROUP = 8
assert LANES == 2 * GROUP
#: Lanes of one vector: quarter steps run on whole blocks of packed lanes.
BLOCK = 4

#: The lane table: one flat array of rows of LANES values, one row per field.
LANE = layout("LaneTable", (
    # the state of each lane's point...
    ("x", "displacement [m]"),
    ("v", "velocity [m/s]"),
    ("voltage", "voltage [V]"),
    ("vimp", "latched approach velocity [m/s]"),
    ("ch", "contact damping in use [s/m]"),
    ("on", "1 in contact, 0 not"),
    ("fine", "quarter steps left after a touch"),
    ("q", "int V^2 dt over the period so far [V^2 s]"),
    ("x_max", "largest x over the period [m]"),
    ("x_min", "smallest x over the period [m]"),
    ("v_max", "largest |v| over the period [m/s]"),
    ("v_peak", "largest |V| over the period [V]"),
    ("fc_previous", "contact force a step before fc [N]"),
    ("fc", "contact force at the step's start [N]"),
    ("fc_max", "largest contact force over the period [N]"),
    ("impacts", "first touches over the period"),
    ("sum_vimp", "sum of approach velocities over the period [m/s]"),
    ("k0", "lane-loop iteration of the period's first step"),
    ("k_end", "iteration at whose end the lane stops (resync or period end)"),
    ("periods", "periods finished"),
    ("sin", "sin of the forcing phase at the step's start"),
    ("cos", "cos of the forcing phase at the step's start"),
    # ... the trial step of the lane loop and whether a lane needs scalar work ...
    ("x_trial", "x after the trial step [m]"),
    ("v_trial", "v after the trial step [m/s]"),
    ("voltage_trial", "V after the trial step [V]"),
    ("need", "1: the step is finished in scalar code"),
    ("x_contact", "x after the trial step with the contact force [m]"),
    ("v_contact", "v after the trial step with the contact force [m/s]"),
    ("voltage_contact", "V after the trial step with the contact force [V]"),
    # ... the parameters the lane loop reads ...
    ("amplitude", "A [m/s^2]"),
    ("wn2", "wn^2 [1/s^2]"),
    ("cm", "c/m [1/s]"),
    ("thm", "theta/m"),
    ("khm", "k_h/m"),
    ("kh", "k_h [N/m^1.5]"),
    ("gap", "g [m]"),
    ("latch", "c_h v_imp of the latched law, 0 in fixed mode"),
    ("irc", "1/(R C_p) [1/s]"),
    ("thc", "theta/C_p"),
    ("h", "step [s]"),
    ("half_h", "h/2 [s]"),
    ("h2_6", "h^2/6 [s^2]"),
    ("cos_half", "cos of half a step's phase"),
    ("sin_half", "sin of half a step's phase"),
    ("cos_step", "cos of a step's phase"),
    ("sin_step", "sin of a step's phase"),
    ("cos_eighth", "cos of an eighth of a step's phase"),
    ("sin_eighth", "sin of an eighth of a step's phase"),
    ("steps", "steps per period"),
    ("locate", "1: contact switches located"),
    ("flip_below", "the lane mirrors when x falls below this: half way to the other stop [m]"),
    # whether the lane books extrema and force peaks (PARAM.book): a step is marked for an
    # extremum where v vn or dV/dt dVn/dt is at most turn_floor, for a force peak where
    # the force a step before the peak exceeds -turn_floor
    ("turn_floor", "0: extrema and force peaks booked; -inf: not"),
    # ... the contact-free step as the linear map it is (tip_mass.free_step_map): the
    # increments of x, v, V (rows) from (x, v, V, sin, cos) at its start (columns) ...
    ("mxx", ""), ("mxv", ""), ("mxe", ""), ("mxs", ""), ("mxc", ""),
    ("mvx", ""), ("mvv", ""), ("mve", ""), ("mvs", ""), ("mvc", ""),
    ("mex", ""), ("mev", ""), ("mee", ""), ("mes", ""), ("mec", ""),
    # ... and the lanes that take quarter steps, packed (lanes.quarter_steps): their
    # lane, state, forcing phase and parameters.
    ("q_lane", ""), ("q_x", ""), ("q_v", ""), ("q_voltage", ""), ("q_sin", ""), ("q_cos", ""),
    ("q_amplitude", ""), ("q_cos_eighth", ""), ("q_sin_eighth", ""), ("q_dt", ""),
    ("q_wn2", ""), ("q_cm", ""), ("q_thm", ""), ("q_khm", ""), ("q_gap", ""), ("q_ch", ""),
    ("q_irc", ""), ("q_thc", ""),
    # ... and, out of the lane loop's way, rows read only at a period's start and end: the
    # forcing phase a period starts at, and a second stop: the lane holds the state
    # mirrored, (-x, -v, -V) under the forcing -A sin, while the lower stop is the nearer
    # (see lanes.mirror), and the rows of the stop not in use wait in the *_other rows.
    ("phase", "forcing phase at each period's start [rad]"),
    ("sign", "+1: the state as it is, the upper stop in use; -1: mirrored, the lower"),
    ("gap_other", "gap of the stop not in use [m]"), ("kh_other", ""), ("khm_other", ""),
    ("ch_other", ""), ("latch_other", ""), ("vimp_other", ""), ("impacts_other", ""),
    ("sum_vimp_other", ""), ("fc_max_other", ""),
    # ... the peaks of the upper stop's contact force over the period ...
    ("fc_peak_min", "smallest located peak of the upper stop's force [N]"),
    ("fc_peak_max", "largest located peak of the upper stop's force [N]"),
    # ... and how near the swings came to a grazing of a rigid stop (booking) ...
    ("near_miss", "smallest distance a swing's top stayed short of the stop [m]"),
    ("vimp_min", "smallest approach velocity at first touch [m/s]"),
    # ... and a moving stop (stop_motion): a lane with one takes every step in scalar code.
    ("stop_x", "stop displacement [m]"), ("stop_v", "stop velocity [m/s]"),
    ("stop_on", "1: in contact with the moving stop"),
    ("stop_wn2", "k_s/m_s [1/s^2]"), ("stop_cm", "c_s/m_s [1/s]"),
    ("stop_ratio", "m/m_s; 0: rigid stop"),
    ("stop_x_max", "largest |x_s| over the period [m]"),
    # ... and the derivative of the state by the run's start state (tangents): its entry
    # (r, c), the change of component r from a change of component c at the start, in
    # the row LANE.txx + (3 r + c) LANES, the contact-free steps since t_since not yet
    # carried into it.
    ("tangents", "1: the lane carries the derivative of its state by its start state"),
    ("t_since", "iteration of the first contact-free step not yet in the derivative"),
    ("t_x", "x at the start of a plain step in contact, for its derivative [m]"),
    ("t_v", "v at its start [m/s]"), ("t_voltage", "V at its start [V]"),
    ("t_sin", "sin of the forcing phase at its start"),
    ("t_cos", "cos of the forcing phase at its start"),
    ("txx", ""), ("txv", ""), ("txe", ""),
    ("tvx", ""), ("tvv", ""), ("tve", ""),
    ("tex", ""), ("tev", ""), ("tee", ""),
    # ... and the multi-step: clear of the stops a lane may take PARAM.multi steps an
    # iteration, the composition of as many contact-free steps (lanes.resume), with its
    # own rows of those a step reads (MULTI_ROWS); the rows of the mode not in use wait
    # in the alt_ rows.
    ("multi", "steps a multi-step takes; 1: the lane takes one step at a time"),
    ("mode", "1: the lane takes multi-steps, its rows of MULTI_ROWS a multi-step's"),
    ("multi_since", "iteration of the lane's first multi-step since it last took one step"),
    ("hold", "iteration up to which the lane takes single steps after a multi-step it "
             "took apart"),
) + tuple(("alt_" + name, "") for name in MULTI_ROWS), stride=LANES)
