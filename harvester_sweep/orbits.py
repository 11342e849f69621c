"""Periodic orbits of the RK4 period map: how every point reaches its steady state.

A point's steady state is a fixed point ``y* = P^p(y*)`` of the p-period stroboscopic map
``P^p: y(0) -> y(pT)`` of the engine's own fixed-step RK4 with located contact switches,
so it is the RK4 solution's own periodic orbit. :func:`solve_orbits` finds it by Newton's
method from the state the motion has reached, and gives every point its Floquet
multipliers (the eigenvalues of the monodromy matrix ``dP^p/dy``).

How, and why (docs/numerics.md, "Periodic orbits"):

- **The monodromy matrix, carried along.** Each Newton iterate is run for p periods in
  one lane that carries the map's derivative with its state (the variational equations
  of the engine's own steps, switches and their moves included: _engine.tangents), where
  the engine can (switches located, rigid stops, a fixed approach velocity). Elsewhere
  (a moving stop, a latched law, plain fixed steps) it runs in three more lanes, from
  it moved by ``PERTURBATION`` of each component's scale, the forward differences the
  columns of the monodromy; there a converged orbit is judged, and its multipliers given,
  on central differences (``CENTRAL``, six copies), where its map is not affine: near
  grazing the map bends too sharply for the forward ones. An iterate a small Newton step
  (``LAST_STEP``) from the last runs its copies both ways at once, as it is likely the
  orbit.
- **Chord steps.** An iterate reuses the last monodromy and runs its centre lane alone
  where that monodromy is still the map's: no lane of its run touched a stop (the map is
  affine off the stop), or, for a point that takes copies, the iterate moved less than
  ``CHORD`` from where it was taken (a carried monodromy costs one to two periods more, and
  a fixed point is then judged on its own run's).
  Where the run Newton starts from is expected to stay clear of the stops (the last run
  did; from rest, the motion without the stops says so: period_map.contact_free_extent), its first
  iterate is a chord step too, with the contact-free map's monodromy in closed form
  (period_map.free_monodromy_into); if it touched after all, it is run again, its
  monodromy carried or by copies.
- **Newton only accelerates.** An attempt starts from the trajectory's state ``t``; its
  first evaluation is also the trajectory's next p periods. A converged fixed point is
  taken only when it is stable (spectral radius below 1, by central differences) and the
  trajectory is on its way to it:
  * an orbit that never reaches the stop is the fixed point of an affine map, found in
    one Newton step; it is taken only once it is proved that the trajectory from ``t``
    never reaches the stop either: the homogeneous part of a linear motion loses energy
    ``E = (k x^2 + m v^2 + C_p V^2) / 2`` (``dE/dt = -c v^2 - V^2/R``), so
    ``x(t) <= x*_max + sqrt(2 E(t - y*) / k)`` for all later times (and
    ``x(t) >= x*_min - sqrt(2 E / k)`` against a lower stop);
  * an orbit with contact is taken when ``t`` is in its linear regime: within ``NEAR``
    of it, the monodromy predicts ``P^p(t)`` (to ``LINEAR_REGIME``), and its prediction
    from there stays within ``NEAR`` (:func:`on_its_way`);
    an attempt whose first monodromy, at ``t``, expands ends at once (``EXPANDING``).
  Otherwise the trajectory is integrated on (a chunk as long as all it has run so far,
  at least ``FIRST_CHUNK`` periods) and Newton tried again from where it got to; a point
  that never settles (chaos, a budget too short) is still reported as not settled.
- **Continuation.** A point that follows another on a line (frequency continuation)
  starts from the orbit that point settled on, with its orbit period as the first guess.
- **Accuracy met.** A point given an error estimate is solved again at twice the steps
  per period, by Newton from its orbit with the same monodromy (two short runs); when the
  step was chosen automatically and the estimate is above ``accuracy``, the point is
  solved again at the step RK4's fourth order asks for, up to ``REFINEMENTS`` times.

Every decision depends on the point's own numbers only, and the engine gives a point the
same bits in any lane: a point's result does not depend on the other points, the thread
count or the chunking.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from collections import namedtuple
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from . import acceptance, accuracy, dense, period_map
from ._engine import MAX_ORBIT_PERIOD, METRIC, N_RIGID, NO_STOP, PARAM, STATE, STATUS, cache
from ._engine.layouts import layout
from ._engine.scheduler import run_watched
from .acceptance import (
    NEAR,
    closing_period,
    never_reaches,
    norm,
    on_its_way,
    periods_to_near,
    reach,
    reaches_a_stop,
    suggested_period,
)
from .accuracy import REFINEMENTS, STEPS_QUANTUM, halving_error, refined_steps
from .jit import SOLVER_JIT, njit
from .models import tip_mass
from .period_map import (
    BOTH_WAYS,
    FORWARD,
    PERTURBATION,
    ROUNDING,
    carries_tangents,
    copies_monodromy,
    estimating_row,
    free_monodromy_into,
    perturb,
    run_lanes,
    sane_run,
    sorted_multipliers,
    state_size,
)

#: A Newton iterate this near the one its monodromy was taken at (relative to the scales)
#: reuses that monodromy (a chord step: its centre lane alone): the monodromy changes by
#: no more than its own forward differences span [-].
CHORD = PERTURBATION
#: A Newton step below this (relative to the scales) likely brings the iterate within the
#: floor of the orbit: the next iterate's copies run both ways, so that the monodromy by
#: central differences the orbit is judged on (see _newton) needs no run of its
#: own [-].
LAST_STEP = 1e-3
#: Newton iterations of one attempt before it is given up [-].
MAX_NEWTON = 8
#: A spectral radius above this of an attempt's first run's monodromy says the motion
#: at the attempt's start is not in the linear regime of a stable orbit (a
#: chaotic motion, or one passing near an orbit it does not reach), and the attempt ends
#: at once rather than pay the iterations to an orbit it could not take
#: (docs/numerics.md) [-].
EXPANDING = 1.0
#: An attempt's iterates whose orbit has contact end once Newton is within this
#: of it (relative to the scales, each step at most half the last) and it lies beyond
#: NEAR of the motion's state at the attempt's start, by more than the step: that orbit
#: could not be taken. A first run that does not touch (a contact the motion makes only now
#: and then) takes the iterates through the contact-free map's fixed point to such orbits:
#: they converged to them, six runs an attempt, again at every attempt of a motion that
#: never settles (docs/numerics.md) [-].
SETTLING = 1e-2
#: Steps per period of the linear motion that guesses whether a motion no run has taken
#: yet will touch a stop in its first period (period_map.contact_free_extent) [-].
GUESS_STEPS = 64
#: The first chunk of trajectory integrated after a failed attempt [periods].
FIRST_CHUNK = 8
#: The most periods of trajectory one round runs for a point [periods]: a longer chunk
#: goes on in the next rounds, so that no round waits long for one lane.
SLICE = 64
#: The error estimate's run at twice the steps may stop short of that orbit by this share
#: of the change it measures, relative to the scales: power, the square of the amplitudes,
#: is then off the orbit's by a tenth of the change at most [-].
LOCATED = 0.05
#: Runs of the error estimate at twice the steps before it is given up [-].
ESTIMATE_RUNS = 4
#: A component's scale, the orbit's amplitude, is kept at least this share of its first
#: one (from the motion without the stop, the gap's thousandth at least): an unforced
#: device's orbit is rest, whose own amplitudes are 0, and a motion decaying to it was
#: measured against its own size, shrinking with it, so that it never settled [-].
SCALE_FLOOR = 1e-6
SAMPLES = MAX_ORBIT_PERIOD + 1  # stroboscopic samples read back from each run

# A point's phase: what its next run is. A phase that runs has one function that takes a
# point's run and returns its next phase (_newton, _transient, _estimate; _converged and
# _give_up return theirs for the point they are handed); a point is set up for a phase's
# run where that next phase is chosen (_attempt, _chunk, _estimate, _refine), and _enter
# moves it on.
_WAITING, _NEWTON, _TRANSIENT, _ESTIMATE, _DONE = range(5)

#: What a point's RK4 steps were run for (Orbits.work_by_kind): the pieces of trajectory
#: between attempts, Newton's centre lanes (an attempt's first run, which is also the
#: trajectory's next p periods, included; the monodromy they carry, where they do, is not
#: counted apart), the monodromy's forward and central copies, the error estimate's runs at
#: twice the steps.
WORK = ("trajectory", "newton", "forward_copies", "central_copies", "estimate")
_TRAJECTORY_WORK, _NEWTON_WORK, _FORWARD_WORK, _CENTRAL_WORK, _ESTIMATE_WORK = range(len(WORK))

# The points of one solve, each a small state machine (its phase) advanced one round of
# engine runs at a time by compiled code; every array is indexed by point, and every
# transition acts on each point apart, so that a point's result depends on its own numbers
# only. A point's numbers are rows of a few arrays, each laid out here once from named
# fields: a compiled function takes the whole table, and numba compiles and calls a named
# tuple of a few arrays much faster than one of a field per array.
#: A point's real numbers (_Points.reals).
_REAL = layout("RealRow", (
    ("run", "trajectory periods run"),
    ("left", "periods of the trajectory's chunk still to run"),
    ("hint", "periods the trajectory should run next (0: no idea)"),
    ("last", "size of the last Newton correction [-]"),
    ("floor", "Newton's floor at the orbit taken [-]"),
    ("steps", "steps per period of the runs"),
    ("orbit_steps", "steps per period of the orbit taken"),
    ("errors", "step-halving error estimate [-]"),
    ("accuracy", "error target [-], NaN where the step was given"),
    ("max_steps", "most steps per period of a re-solve"),
    ("coarser_steps", "steps per period of the last solve"),
    ("coarser_error", "... and its error estimate [-]"),
    ("settling", "Newton's nearness that ends an attempt at an orbit it cannot take [-]"),
))
#: A point's whole numbers (_Points.counts).
_COUNT = layout("CountRow", (
    ("phase", "what the next run is (_WAITING ... _DONE)"),
    ("rounds", "the round the point was done in"),
    ("p", "orbit period tried"),
    ("iteration", "Newton iteration of the attempt, or run of the estimate"),
    ("refine", "re-solves at a finer step so far"),
    ("t1_periods", "periods from t0 to t1"),
    ("refused", "period of the stable orbit with contact last turned away (0: none)"),
    ("status", "outcome (STATUS)"),
    ("successors", "the point that starts from the point's orbit, -1 for none"),
))
#: A point's flags (_Points.flags).
_FLAG = layout("FlagRow", (
    ("estimated", "given an error estimate"),
    ("released", "successor started"),
    ("tested", "the engine's steady-state test passed"),
    ("retry", "the attempt is at the period of the orbit last turned away"),
    ("chord", "the next iterate reuses the newton monodromy"),
    ("affine", "... taken where no lane touched a stop"),
    ("central", "the next copies run both ways"),
    # the newton monodromy is one to judge an orbit on: by central differences, or of a map
    # affine where it was taken (where forward differences are exact)
    ("exact", "the newton monodromy may judge an orbit"),
    # before any run: the linear motion's first period says whether it will
    ("touched", "the run Newton starts from touched a stop"),
    ("recheck", "the attempt's first run, again with its monodromy"),
))
#: A point's states (_Points.states: (n, 4, len(STATE))).
_STATES = layout("States", (
    ("begin", "start state: rest, or the predecessor's orbit"),
    ("traj", "the trajectory's state"),
    ("y", "Newton iterate, or the orbit under estimate"),
    ("finals", "the state the point ended at"),
))
#: A point's vectors of the map's components (_Points.components: (n, 3, D)).
_COMPONENTS = layout("Components", (
    ("t0", "trajectory state at the attempt's start"),
    ("t1", "... and t1_periods periods later"),
    ("scale", "component scales"),
    ("floor", "the least each scale may be: SCALE_FLOOR times the first"),
))
#: A point's monodromies (_Points.jacobians: (n, 3, D, D)).
_JACOBIANS = layout("Jacobians", (
    ("jacobian", "of the orbit taken"),
    ("first_jacobian", "of each attempt's first run"),
    ("newton_jacobian", "of the last run that took one, or the contact-free map's"),
))
#: A point's metric rows (_Points.metric_rows: (n, 2, len(METRIC))).
_METRIC_ROWS = layout("MetricRows", (
    ("metrics", "of the orbit"),
))
_Points = namedtuple("_Points", (
    "rows",  # packed parameter rows (n, len(PARAM))
    "reals", "counts", "flags", "states", "components", "jacobians", "metric_rows",
    "strobes",  # stroboscopic samples of the last run (n, SAMPLES, D)
    "work",  # RK4 steps taken (n, len(WORK)), by kind
    "calls",  # rounds run (1,)
))
#: A solve's groups of lines, each solved in a thread of its own (_solve): one row each.
_TEAM = layout("TeamRow", (
    ("threads", "threads of the group's engine calls"),
    ("done", "points of the group done"),
    ("stop", "nonzero: run no more rounds"),
))


@dataclass
class Orbits:
    """Every point's steady state.

    Attributes
    ----------
    metrics : numpy.ndarray
        float64 (n, len(layouts.METRIC)): the metrics of the orbit (``status``,
        ``orbit_period`` and ``periods_run`` as the point ended).
    strobes : numpy.ndarray
        float64 (n, samples, 3): the last stroboscopic samples y(nT) [m, m/s, V] (the orbit
        repeated, for a settled point).
    finals : numpy.ndarray
        float64 (n, 4): the state on the orbit at a period boundary (layouts.STATE).
    multipliers : numpy.ndarray
        complex128 (n, 3): Floquet multipliers [-], largest modulus first; NaN where the
        point did not settle.
    errors : numpy.ndarray
        float64 (n,): step-halving error estimates [-], NaN where not estimated.
    steps : numpy.ndarray
        int64 (n,): the steps per period of the orbit reported.
    rk4_steps : numpy.ndarray
        int64 (n,): RK4 steps taken for the point: trajectory, Newton with its perturbed
        copies, error estimate and re-solves.
    rounds : numpy.ndarray
        int64 (n,): the round of its group of lines (engine call, counted from 1) in which
        the point was done, 0 for a point not run: how long a solve took in calls (what
        run_estimate counts; the groups run side by side, see _solve).
    work_by_kind : numpy.ndarray
        int64 (n, len(WORK)): the RK4 steps of ``rk4_steps`` by what they were run for.
    """

    metrics: np.ndarray
    strobes: np.ndarray
    finals: np.ndarray
    multipliers: np.ndarray
    errors: np.ndarray
    steps: np.ndarray
    rk4_steps: np.ndarray
    rounds: np.ndarray
    work_by_kind: np.ndarray


def solve_orbits(rows, states, successors=None, estimated=None, accuracy=None,
                 max_steps=None, samples=0, on_points=None, settling=SETTLING) -> Orbits:
    """Every point's steady state as a periodic orbit of the RK4 period map.

    Parameters
    ----------
    rows : numpy.ndarray
        float64 (n, len(layouts.PARAM)): packed parameter rows (a budget of 0 periods: the
        point is refused, too stiff).
    states : numpy.ndarray
        float64 (n, 4): initial states (layouts.STATE); not modified.
    successors : numpy.ndarray, optional
        int (n,): the point that starts from each point's orbit, -1 for none (lines of a
        frequency continuation, as the engine's ``run_points``).
    estimated : numpy.ndarray, optional
        bool (n,): the points given a step-halving error estimate (default: none).
    accuracy : numpy.ndarray, optional
        float64 (n,): the error target [-] of points whose step was chosen automatically,
        NaN where the step was given; with ``max_steps`` (the most steps per period
        allowed), a point estimated above it is solved again at a finer step.
    samples : int
        Stroboscopic samples returned per point.
    on_points : callable, optional
        Called with the number of points newly finished, as they finish (about every
        0.2 s); what it raises (KeyboardInterrupt included) stops the solve after the
        rounds running then, and is raised again.
    settling : float
        An attempt's iterates end once within this of an orbit they cannot take, relative
        to the scales [-] (default SETTLING); below 0 they never do and every attempt
        converges, which the tests compare against. A value at run time, not a constant
        compiled in, so that changing it compiles nothing.

    The rounds run in compiled code, the lines in groups each solved in a thread of its
    own (_solve).
    """
    rows = np.ascontiguousarray(rows, dtype=float)
    states = np.ascontiguousarray(states, dtype=float)
    n = len(rows)
    pts = _points(rows, states,
                  np.full(n, -1) if successors is None else np.asarray(successors),
                  np.zeros(n, bool) if estimated is None else np.asarray(estimated, bool),
                  np.full(n, np.nan) if accuracy is None else np.asarray(accuracy, float),
                  np.full(n, np.inf) if max_steps is None else np.asarray(max_steps, float),
                  settling)
    linked = pts.counts[pts.counts[:, _COUNT.successors] >= 0, _COUNT.successors]
    heads = np.ones(n, bool)
    heads[linked] = False
    # (read here, which also starts numba's threads: compiled code calling the engine's
    # parallel loop does not start them, and would crash; a count read in compiled code
    # would keep that code out of numba's cache)
    threads = numba.get_num_threads()
    guessed = pts.components.shape[2] == N_RIGID  # (a moving stop's motion is not the tip's alone)
    extent = (period_map.contact_free_extent(rows, states, GUESS_STEPS) if guessed
              else np.zeros((n, 2)))
    _set_up(pts, _linear_amplitude(rows), guessed, extent, np.flatnonzero(heads))
    return _result(pts, samples, _solve(pts, threads, on_points))


def _solve(pts: _Points, threads: int, on_points) -> np.ndarray:
    """Run the rounds of ``pts`` until every point is done, on ``threads`` threads, and
    return the points' Floquet multipliers (_multipliers).

    The lines (a point, or a continuation's points) are dealt out to groups, one for each
    thread while lines last, and each group is solved in a thread of its own, its engine
    calls on one thread: a round of a solve waits for its slowest point, and a round of
    few points (a continuation's, a line's points coming one after the other) is mostly
    short calls and the algebra between them, on one core. The last group left runs on
    every thread. A group's multipliers are taken in its thread, as it ends (LAPACK's, a
    matrix at a time: the same bits in any group). A point's result does not depend on its
    group.
    """
    groups = _groups(pts.counts[:, _COUNT.successors], threads)
    team = np.zeros((len(groups), len(_TEAM)), dtype=np.int64)
    team[:, _TEAM.threads] = threads if len(groups) == 1 else 1
    if len(groups) == 1 and on_points is None:
        _ran(_rounds(pts, team, 0))
        return _multipliers(pts)
    parts = [pts] if len(groups) == 1 else [_part(pts, group) for group in groups]
    multipliers = [None] * len(groups)
    lock, running = threading.Lock(), [len(groups)]

    def solve(g):
        numba.set_num_threads(threads)  # (numba's thread count is per calling thread)
        _ran(_rounds(parts[g], team, g))
        multipliers[g] = _multipliers(parts[g])
        with lock:
            running[0] -= 1
            if running[0] == 1:
                # (no group runs a round now but the last: numba's workqueue threading
                # layer takes one parallel call at a time)
                team[:, _TEAM.threads] = threads

    def stop():
        team[:, _TEAM.stop] = 1

    run_watched([lambda g=g: solve(g) for g in range(len(groups))],
                lambda: int(team[:, _TEAM.done].sum()), stop, on_points)
    if len(groups) == 1:
        return multipliers[0]
    successors = pts.counts[:, _COUNT.successors].copy()
    whole_multipliers = np.empty((len(pts.rows), pts.components.shape[2]), dtype=complex)
    for group, part, piece in zip(groups, parts, multipliers):
        whole_multipliers[group] = piece
        for whole, column in zip(pts, part):
            if whole is not pts.calls and whole is not pts.rows:  # (rows: read only)
                whole[group] = column
    pts.counts[:, _COUNT.successors] = successors
    pts.calls[0] = max(part.calls[0] for part in parts)
    return whole_multipliers


def _ran(outcome: int) -> None:
    """Check what _rounds returned (it is stopped only by a failure, raised elsewhere)."""
    if outcome < 0:
        raise RuntimeError("the orbit solver has points waiting that no run releases")


def _groups(successors, threads: int) -> list:
    """The points (indices) of each group of lines that ``successors`` (see solve_orbits)
    make: the lines dealt out in turn to min(threads, lines) groups, so that each group
    gets its share of every part of a grid (neighbouring points cost alike)."""
    n = len(successors)
    linked = successors[successors >= 0]
    heads = np.setdiff1d(np.arange(n), linked)
    count = min(threads, len(heads))
    if count <= 1:
        return [np.arange(n)]
    group = np.empty(n, dtype=np.int64)
    group[heads] = np.arange(len(heads)) % count
    ahead = heads
    while ahead.size:  # one point further along every line a pass
        following = successors[ahead]
        ahead, following = ahead[following >= 0], following[following >= 0]
        group[following] = group[ahead]
        ahead = following
    return [np.flatnonzero(group == g) for g in range(count)]


def _part(pts: _Points, points) -> _Points:
    """The table of ``points`` (indices, whole lines) of ``pts``, its successors counted
    within it, none of its rounds run."""
    part = _Points(*(np.zeros(1, dtype=np.int64) if whole is pts.calls else whole[points]
                     for whole in pts))
    where = np.full(len(pts.rows), -1, dtype=np.int64)
    where[points] = np.arange(len(points))
    successors = part.counts[:, _COUNT.successors]
    successors[:] = np.where(successors >= 0, where[np.maximum(successors, 0)], -1)
    return part


def _points(rows, states, successors, estimated, accuracy, max_steps, settling) -> _Points:
    """The solve's points before any run: each waiting (_WAITING)."""
    n, size = len(rows), state_size(rows)
    reals = np.zeros((n, len(_REAL)))
    reals[:, _REAL.last] = np.inf
    reals[:, [_REAL.steps, _REAL.orbit_steps]] = rows[:, PARAM.steps, None]
    reals[:, [_REAL.errors, _REAL.coarser_steps, _REAL.coarser_error]] = np.nan
    reals[:, _REAL.accuracy], reals[:, _REAL.max_steps] = accuracy, max_steps
    reals[:, _REAL.settling] = settling
    counts = np.zeros((n, len(_COUNT)), dtype=np.int64)
    counts[:, _COUNT.phase] = _WAITING
    counts[:, [_COUNT.p, _COUNT.t1_periods]] = 1
    counts[:, _COUNT.status] = STATUS.not_settled
    counts[:, _COUNT.successors] = successors
    flags = np.zeros((n, len(_FLAG)), dtype=bool)
    flags[:, _FLAG.estimated] = estimated
    components = np.ones((n, len(_COMPONENTS), size))
    components[:, _COMPONENTS.t0] = components[:, _COMPONENTS.t1] = states[:, :size]
    return _Points(
        rows=rows, reals=reals, counts=counts, flags=flags,
        states=np.repeat(states[:, None, :], len(_STATES), axis=1), components=components,
        jacobians=np.full((n, len(_JACOBIANS), size, size), np.nan),
        metric_rows=np.full((n, len(_METRIC_ROWS), len(METRIC)), np.nan),
        strobes=np.full((n, SAMPLES, size), np.nan), work=np.zeros((n, len(WORK))),
        calls=np.zeros(1, dtype=np.int64))


def scale_floors(rows, size=N_RIGID):
    """The least each component's scale may be (orbits of packed rows ``rows`` (n,
    len(PARAM))): SCALE_FLOOR times the first scales solve_orbits gives them, from their
    motion without the stop; (n, size) [m, m/s, V, ...]."""
    rows = np.asarray(rows, dtype=float)
    return SCALE_FLOOR * period_map.orbit_scales(rows, _linear_amplitude(rows), 0.0, size)


def _linear_amplitude(rows):
    """Displacement amplitudes [m] of the points before any run: the response without the
    stop (the model's linear system's phasor), floored at the gap."""
    r = rows
    x = tip_mass.free_amplitude(r[:, PARAM.amplitude], 2 * np.pi / r[:, PARAM.period],
                                r[:, PARAM.wn2], r[:, PARAM.cm], r[:, PARAM.thm],
                                r[:, PARAM.irc], r[:, PARAM.thc])
    x = np.where(np.isfinite(x), x, 0.0)
    gap = np.where(r[:, PARAM.gap] < NO_STOP, np.abs(r[:, PARAM.gap]), 0.0)
    return np.maximum(x, gap * 1e-3) + 1e-30


def _multipliers(pts: _Points) -> np.ndarray:
    """The Floquet multipliers (n, D) of the solved points ``pts`` [-], largest modulus
    first; NaN, real and imaginary parts, where a point did not settle."""
    settled = pts.counts[:, _COUNT.status] == STATUS.settled
    multipliers = np.full((len(pts.rows), pts.components.shape[2]), complex(np.nan, np.nan))
    if settled.any():
        multipliers[settled] = sorted_multipliers(
            pts.jacobians[settled, _JACOBIANS.jacobian])
    return multipliers


def _result(pts: _Points, samples: int, multipliers) -> Orbits:
    """The solved points ``pts`` as Orbits, with their ``multipliers`` (_multipliers)."""
    n, size = len(pts.rows), pts.components.shape[2]
    metrics = pts.metric_rows[:, _METRIC_ROWS.metrics].copy()
    status, p = pts.counts[:, _COUNT.status], pts.counts[:, _COUNT.p]
    settled = status == STATUS.settled
    metrics[:, METRIC.status] = status
    metrics[:, METRIC.orbit_period] = np.where(settled, p, 0)
    metrics[:, METRIC.periods_run] = pts.reals[:, _REAL.run]
    strobes = np.full((n, samples, size), np.nan)
    age = np.arange(samples)[::-1]  # periods before the end
    # a settled orbit repeats: its p + 1 samples tiled; else the last run's samples
    p = np.where(settled, p, SAMPLES)
    back = np.where(settled[:, None], age[None, :] % p[:, None], age[None, :])
    valid = back < SAMPLES
    taken = np.take_along_axis(pts.strobes, (SAMPLES - 1 - back.clip(0, SAMPLES - 1))
                               [..., None].repeat(size, axis=2), axis=1)
    strobes[valid] = taken[valid]
    work = pts.work.astype(np.int64)
    return Orbits(metrics, strobes, pts.states[:, _STATES.finals].copy(), multipliers,
                  pts.reals[:, _REAL.errors].copy(),
                  pts.reals[:, _REAL.orbit_steps].astype(np.int64), work.sum(axis=1),
                  pts.counts[:, _COUNT.rounds].copy(), work)


# -- compiled: set-up and rounds ---------------------------------------------------------

@njit(**SOLVER_JIT)
def _set_up(T, amplitude, guessed, extent, heads):
    """Each point's first scales from its amplitude ``amplitude`` [m] (the response without
    the stop), whether its motion touches a stop in its first period (where ``guessed``:
    from ``extent``, the linear motion's), and the lines' first points ``heads`` start."""
    for i in range(T.rows.shape[0]):
        period_map.point_scales(T.rows[i], amplitude[i], 0.0,
                                T.components[i, _COMPONENTS.scale])
        T.components[i, _COMPONENTS.floor] = SCALE_FLOOR * T.components[i, _COMPONENTS.scale]
        if guessed:
            T.flags[i, _FLAG.touched] = reaches_a_stop(T.rows[i], extent[i, 0], extent[i, 1])
    for i in heads:
        _start(T, i)


@njit(**SOLVER_JIT)
def _counts(T):
    """Points not done yet, and of them those with a run to make."""
    left = running = 0
    for i in range(T.counts.shape[0]):
        if T.counts[i, _COUNT.phase] != _DONE:
            left += 1
            running += T.counts[i, _COUNT.phase] != _WAITING
    return left, running


@njit(nogil=True, **SOLVER_JIT)
def _rounds(T, team, g):
    """Run the rounds of group ``g`` of a solve (table ``T``; its row of ``team``, _TEAM)
    until every point is done or the row's ``stop`` is set, each on the row's ``threads``
    threads as it is then, counting the points done in its ``done``: 0 when every point
    is done, 1 when stopped first, -1 where points wait that no run will release.

    It runs without the GIL: the groups of a solve run at once (_solve), and a sweep sets
    up its next chunk in a Python thread meanwhile (sweep._run_here)."""
    while True:
        left, running = _counts(T)
        if left == 0:
            return 0
        if running == 0:
            return -1
        if team[g, _TEAM.stop] != 0:
            return 1
        team[g, _TEAM.done] += _round(T, team[g, _TEAM.threads])
        T.calls[0] += 1
        for i in range(T.counts.shape[0]):
            if T.counts[i, _COUNT.phase] == _DONE and T.counts[i, _COUNT.rounds] == 0:
                T.counts[i, _COUNT.rounds] = T.calls[0]


@njit(inline="always", **SOLVER_JIT)
def _carries(T, i):
    """Whether point i's runs can carry their monodromy along (the variational equations,
    see _engine.tangents) rather than take it by copies."""
    return T.components.shape[2] == N_RIGID and carries_tangents(T.rows[i])


@njit(inline="always", **SOLVER_JIT)
def _tangents(T, i):
    """Whether point i's next run carries its monodromy along: a Newton iterate's that is
    not a chord step, where the engine can."""
    return (T.counts[i, _COUNT.phase] == _NEWTON and not T.flags[i, _FLAG.chord]
            and _carries(T, i))


@njit(inline="always", **SOLVER_JIT)
def _lanes(T, i):
    """Lanes of point i's next run: 0 for none, 1 alone (with its tangents or not), or
    with its copies (forward ones, or central ones both ways)."""
    phase = T.counts[i, _COUNT.phase]
    if phase == _NEWTON:
        if T.flags[i, _FLAG.chord] or _tangents(T, i):
            return 1
        return 1 + T.components.shape[2] * (2 if T.flags[i, _FLAG.central] else 1)
    return 1 if phase == _TRANSIENT or phase == _ESTIMATE else 0


@njit(**SOLVER_JIT)
def _round(T, threads):
    """Run every point's next request in one engine call and act on the results; returns
    the number of points that finished."""
    n, _, size = T.components.shape
    first = np.zeros(n + 1, dtype=np.int64)
    tangent = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        first[i + 1] = first[i] + _lanes(T, i)
        tangent[i] = _tangents(T, i)
    total = first[n]
    params = np.empty((total, T.rows.shape[1]))
    states = np.empty((total, T.states.shape[2]))
    for i in range(n):
        width = first[i + 1] - first[i]
        if width == 0:
            continue
        k = first[i]
        steps, periods = T.reals[i, _REAL.steps], float(T.counts[i, _COUNT.p])
        start = T.states[i, _STATES.y]
        if T.counts[i, _COUNT.phase] == _TRANSIENT:
            # (no slice shorter than MAX_ORBIT_PERIOD unless the whole chunk is: _chunk)
            left = T.reals[i, _REAL.left]
            periods = left if left < SLICE + MAX_ORBIT_PERIOD else SLICE
            start = T.states[i, _STATES.traj]
        estimate = T.counts[i, _COUNT.phase] == _ESTIMATE
        for w in range(width):
            params[k + w] = T.rows[i]
            params[k + w, PARAM.steps] = steps
            if estimate:
                estimating_row(params[k + w], steps, 2 * steps)
            params[k + w, PARAM.max_periods] = periods
            states[k + w] = start
            if w > 0:  # (the copies book no extrema: their end states alone are read)
                params[k + w, PARAM.book] = 0.0
        params[k, PARAM.tangents] = 1.0 if tangent[i] else 0.0
        if width == 1 + size:  # copies, each moved along one component by its scale
            perturb(states[k:k + width], T.components[i, _COMPONENTS.scale], FORWARD)
        elif width > 1:
            perturb(states[k:k + width], T.components[i, _COMPONENTS.scale], BOTH_WAYS)
    metrics = np.empty((total, len(METRIC)))
    strobes = np.empty((total, SAMPLES, size))
    # (the engine's steady-state test ends a piece of the motion that settles; it never
    # ends a Newton or estimate run, whose p <= MAX_ORBIT_PERIOD periods are fewer than
    # the SAMPLES periods the test waits for)
    derivatives = np.empty((total, N_RIGID, N_RIGID))
    run_lanes(params, states, metrics, strobes, threads, derivatives)
    before = 0
    for i in range(n):
        before += T.counts[i, _COUNT.phase] == _DONE
    phases = T.counts[:, _COUNT.phase].copy()
    jac = np.empty((size, size))
    for i in range(n):
        k, width = first[i], first[i + 1] - first[i]
        if width == 0:
            continue
        # (not the literal True: numba would compile _newton and _estimate for that type
        # too, on their way to the bool the loop makes of it)
        ok = width > 0
        for w in range(width):
            ok = ok and sane_run(metrics[k + w])
            for c in range(size):
                ok = ok and np.isfinite(states[k + w, c])
                if tangent[i]:
                    for r in range(size):
                        ok = ok and np.isfinite(derivatives[k, r, c])
        _book_work(T, i, params, metrics, k, width)
        m, end, strobe = metrics[k], states[k], strobes[k]
        if T.counts[i, _COUNT.phase] == _NEWTON:
            if width > 1:
                central = width > 1 + size
                copies_monodromy(states[k:k + width], T.components[i, _COMPONENTS.scale],
                                 central, jac)
                _copies(T, i, metrics[k:k + width], central)
                # (in a re-solve at a finer step, a step by central differences is not
                # compared with the last one, by forward differences: near grazing that
                # one can be several times off. In a first solve a step that does not
                # contract ends the attempt, as it did: there it also turns away orbits
                # the motion does not reach)
                if central:
                    T.flags[i, _FLAG.central] = False
                    if T.counts[i, _COUNT.refine] > 0:
                        T.reals[i, _REAL.last] = np.inf
            elif tangent[i]:  # (judges an orbit as central differences would, more nearly)
                jac[:] = derivatives[k]
                T.flags[i, _FLAG.affine] = not _touched(T.rows[i], m)
                T.flags[i, _FLAG.exact] = True
                T.flags[i, _FLAG.central] = False
            else:
                jac[:] = T.jacobians[i, _JACOBIANS.newton_jacobian]
            phases[i] = _newton(T, i, m, end, strobe, jac, ok)
        elif T.counts[i, _COUNT.phase] == _TRANSIENT:
            phases[i] = _transient(T, i, m, end, strobe)
        else:
            phases[i] = _estimate(T, i, m, end, ok)
    for i in range(n):
        if first[i + 1] > first[i]:
            _enter(T, i, phases[i])
    after = 0
    for i in range(n):
        after += T.counts[i, _COUNT.phase] == _DONE
    return after - before


@njit(inline="always", **SOLVER_JIT)
def _book_work(T, i, params, metrics, k, width):
    """Add the RK4 steps of point i's lanes k ... k + width to its work, by kind (WORK)."""
    phase = T.counts[i, _COUNT.phase]
    for w in range(width):
        steps = metrics[k + w, METRIC.periods_run] * params[k + w, PARAM.steps]
        if phase == _ESTIMATE:
            kind = _ESTIMATE_WORK
        elif phase == _TRANSIENT:
            kind = _TRAJECTORY_WORK
        elif w == 0:
            kind = _NEWTON_WORK
        else:
            kind = _FORWARD_WORK if width == 1 + T.components.shape[2] else _CENTRAL_WORK
        T.work[i, kind] += steps


@njit(inline="always", **SOLVER_JIT)
def _enter(T, i, phase):
    """Point i goes on to ``phase``; a point done, or taken on its orbit, lets its
    successor start (once)."""
    T.counts[i, _COUNT.phase] = phase
    if phase == _DONE or T.counts[i, _COUNT.status] == STATUS.settled:
        _release(T, i)


@njit(inline="always", **SOLVER_JIT)
def _copies(T, i, m, central):
    """Whether point i's run with its copies (metric rows ``m``, its own first) took an
    affine map, and whether its monodromy is one to judge an orbit on."""
    row = T.rows[i]
    affine = not _touched(row, m[0])
    # (the copies book no extrema: their impacts alone say they stayed clear)
    for w in range(1, m.shape[0]):
        affine = affine and (row[PARAM.khm] == 0 or m[w, METRIC.impacts_per_period] == 0) \
            and (row[PARAM.lower_khm] == 0 or m[w, METRIC.impacts_per_period_lower] == 0)
    T.flags[i, _FLAG.affine] = affine
    T.flags[i, _FLAG.exact] = affine or central


@njit(**SOLVER_JIT)
def _touched(row, m):
    """Whether a run of packed row ``row`` (its metric row ``m``) touched a stop or came to
    its gap."""
    return reaches_a_stop(row, m[METRIC.x_max], m[METRIC.x_min]) \
        or (row[PARAM.khm] > 0 and m[METRIC.impacts_per_period] > 0) \
        or (row[PARAM.lower_khm] > 0 and m[METRIC.impacts_per_period_lower] > 0)


# -- set-up of a point -------------------------------------------------------------------

@njit(**SOLVER_JIT)
def _start(T, i):
    """Point i starts: a refused one is done at once (its state passes on, and its
    successor starts), the others make a Newton attempt from their initial state."""
    while i >= 0:
        if T.rows[i, PARAM.max_periods] > 0:
            T.states[i, _STATES.traj] = T.states[i, _STATES.begin]
            _attempt(T, i)
            T.counts[i, _COUNT.phase] = _NEWTON
            return
        T.metric_rows[i, _METRIC_ROWS.metrics, :METRIC.orbit_period] = np.nan
        T.counts[i, _COUNT.status] = STATUS.too_stiff
        T.states[i, _STATES.finals] = T.states[i, _STATES.begin]
        T.counts[i, _COUNT.phase] = _DONE
        i = _pass_on(T, i)


@njit(inline="always", **SOLVER_JIT)
def _release(T, i):
    """The successor of point i starts from its orbit (from its own initial state after a
    divergence), once."""
    following = _pass_on(T, i)
    if following >= 0:
        _start(T, following)


@njit(inline="always", **SOLVER_JIT)
def _pass_on(T, i):
    """Hand point i's orbit to its successor, once: returns the successor to start, or -1."""
    if T.flags[i, _FLAG.released]:
        return -1
    T.flags[i, _FLAG.released] = True
    following = T.counts[i, _COUNT.successors]
    if following < 0:
        return -1
    if T.counts[i, _COUNT.status] != STATUS.diverged:
        T.states[following, _STATES.begin] = T.states[i, _STATES.finals]
        T.flags[following, _FLAG.touched] = _touched(T.rows[i],
                                                     T.metric_rows[i, _METRIC_ROWS.metrics])
    settled = T.counts[i, _COUNT.status] == STATUS.settled
    T.counts[following, _COUNT.p] = T.counts[i, _COUNT.p] if settled else 1
    return following


@njit(inline="always", **SOLVER_JIT)
def _attempt(T, i):
    """Set up a Newton attempt from the trajectory's state (phase _NEWTON)."""
    size = T.components.shape[2]
    T.states[i, _STATES.y] = T.states[i, _STATES.traj]
    T.components[i, _COMPONENTS.t0] = T.states[i, _STATES.traj, :size]
    T.counts[i, _COUNT.iteration] = 0
    T.reals[i, _REAL.last] = np.inf
    _first_run(T, i)


@njit(inline="always", **SOLVER_JIT)
def _first_run(T, i):
    """Newton's first run from point i's iterate: where the motion was clear of the stops,
    it is likely to be too, so its centre lane alone, with the contact-free map's
    monodromy (run again if it touched after all); else with its monodromy, carried or
    by copies."""
    T.flags[i, _FLAG.chord] = T.flags[i, _FLAG.central] = T.flags[i, _FLAG.exact] = False
    # (a moving stop's map is not the tip's alone)
    if T.components.shape[2] == N_RIGID and not T.flags[i, _FLAG.touched]:
        T.flags[i, _FLAG.chord] = T.flags[i, _FLAG.affine] = T.flags[i, _FLAG.exact] = True
        free_monodromy_into(T.rows[i:i + 1], T.reals[i:i + 1, _REAL.steps],
                            T.counts[i:i + 1, _COUNT.p],
                            T.jacobians[i:i + 1, _JACOBIANS.newton_jacobian])


# -- Newton --------------------------------------------------------------------------------

@njit(**SOLVER_JIT)
def _newton(T, i, m, centre, strobes, jac, lanes_ok):
    """The phase _NEWTON: point i's Newton iterate ran, metrics ``m``, end state ``centre``
    and strobes of its centre lane, the monodromy ``jac`` (carried along the run, of its
    copies, or reused by a chord step) and whether every lane ran sane and finite. Returns
    its next phase: _NEWTON for a next iterate (or the same one again, with its
    monodromy), and those of a fixed point (_converged) or of an attempt given up
    (_give_up)."""
    size = T.components.shape[2]
    phase = _NEWTON
    trajectory = T.counts[i, _COUNT.iteration] == 0 and T.counts[i, _COUNT.refine] == 0
    if trajectory:
        _trajectory_ran(T, i, m, centre, strobes)
    diverged = trajectory and not sane_run(m)
    if diverged:
        _diverge(T, i)
        phase = _DONE
    ok = not diverged and lanes_ok
    y = T.states[i, _STATES.y, :size].copy()
    scale, step, size_, good, floor = _newton_step(T, i, m, centre, jac, ok)
    converged = good and size_ <= floor
    # an orbit with contact is not taken from beyond NEAR of it: not when the first step
    # is beyond NEAR (the step is about the distance from the orbit), nor when the motion
    # moved more than 2 NEAR in these p periods (d0, d1 <= NEAR would bound that move by
    # 2 NEAR). Integrate on, for about the periods the motion needs to come NEAR (from the
    # monodromy at t), rather than pay the iterations. Nor when the monodromy at t expands
    # (EXPANDING): t is not in a stable orbit's linear regime
    touched = _touched(T.rows[i], m)
    distance = np.maximum(size_, 0.5 * norm(centre[:size] - y, scale))
    # (a first run that touched a stop with the contact-free map's monodromy is run again
    # with its own, and judged then)
    recheck = trajectory and T.flags[i, _FLAG.chord] and T.flags[i, _FLAG.affine] and touched \
        and not diverged
    opening = (trajectory and not recheck) or T.flags[i, _FLAG.recheck]
    T.flags[i, _FLAG.recheck] = recheck
    # (a converged first run is judged by _converged, stable or not)
    looked = opening and good and touched and (distance > NEAR or not converged)
    radius = dense.spectral_radius(jac) if looked else 0.0
    # (not in an attempt at the period of the stable orbit with contact the last one
    # turned away: the motion nears that orbit, and the monodromy taken off it, by a
    # multiplier near -1, may expand)
    far = looked and (distance > NEAR or (radius > EXPANDING and not T.flags[i, _FLAG.retry]))
    # a later iterate of an attempt from the motion, whose run touched a stop, is given
    # up when Newton has come within SETTLING of an orbit beyond NEAR of the motion's
    # state at the attempt's start (on_its_way takes an orbit with contact from within
    # NEAR of it; the steps left add up to about this one)
    later = not opening and not trajectory and good and touched and not converged \
        and T.counts[i, _COUNT.refine] == 0 and size_ <= T.reals[i, _REAL.settling] \
        and size_ <= 0.5 * T.reals[i, _REAL.last]
    if later:
        d0 = norm(T.components[i, _COMPONENTS.t0] - (y + step), scale)
        if d0 - size_ > NEAR:
            radius = dense.spectral_radius(jac)
            distance = d0
            far = True
    if far:
        need = periods_to_near(T.counts[i, _COUNT.p], NEAR, distance, radius)
        T.reals[i, _REAL.hint] = need if radius < 1 else 0.0
    stalled = not converged and not diverged and (
        not good or T.counts[i, _COUNT.iteration] + 1 >= MAX_NEWTON
        or (T.counts[i, _COUNT.iteration] > 0 and size_ > 0.5 * T.reals[i, _REAL.last]))
    # in a re-solve at a finer step, an iterate that stalls within half the accuracy target
    # of its orbit is taken (its metrics then within about the target, power being a
    # square): where the map jumps near Newton's floor (by about its own error where a
    # switch crosses a step's end) the iterates stall short of it, and the re-solve kept
    # the coarser orbit, above the target; the error estimate that follows measures the
    # orbit as taken
    enough = stalled and good and T.counts[i, _COUNT.refine] > 0 \
        and size_ <= 0.5 * T.reals[i, _REAL.accuracy]
    converged = converged or enough
    stalled = stalled and not enough
    # a chord step that stalls, or that touched a stop with the monodromy of an affine run
    # (converged or not: that monodromy is not the orbit's), is taken again from the same
    # iterate, with its monodromy
    again = recheck or ((stalled or (T.flags[i, _FLAG.affine] and touched))
                        and T.flags[i, _FLAG.chord] and not far and not diverged
                        and T.counts[i, _COUNT.iteration] + 1 < MAX_NEWTON)
    # a converged orbit is judged, and its multipliers given, on a monodromy carried along
    # its run or by central differences (CENTRAL) where its map is not affine: forward
    # ones err by PERTURBATION times the map's curvature; so its copies run again from the
    # same iterate, both ways (a carried monodromy is exact: _round)
    sharpen = converged and not again and not T.flags[i, _FLAG.exact] and not diverged
    # (and in a re-solve at a finer step, which has no other way to its orbit, a chord step
    # that stalled had a monodromy too far off to contract: near grazing forward
    # differences can be, so it is taken again by central ones)
    if sharpen or (again and stalled and T.counts[i, _COUNT.refine] > 0):
        T.flags[i, _FLAG.central] = True
    again = again or sharpen
    converged = converged and not again
    failed = far or (stalled and not again)
    going = not converged and not failed and not diverged and not again
    if ok:
        T.components[i, _COMPONENTS.scale] = scale
    if opening:
        T.jacobians[i, _JACOBIANS.first_jacobian] = jac
    T.jacobians[i, _JACOBIANS.newton_jacobian] = jac
    if again:
        T.counts[i, _COUNT.iteration] += 1
        T.flags[i, _FLAG.chord] = False
    # on: a new iterate, by a chord step where the monodromy is known there (the map is
    # affine where no lane touched a stop; elsewhere the iterate moved less than CHORD)
    if going:
        T.states[i, _STATES.y, :size] = y + step
        T.states[i, _STATES.y, size:] = centre[size:]
        T.counts[i, _COUNT.iteration] += 1
        T.reals[i, _REAL.last] = size_
        # (where the monodromy is carried along, an iterate near the last has it for one
        # or two more periods' cost, and a fixed point the monodromy of its own run, not
        # one taken CHORD away: near grazing that one can be 2e-4 off)
        T.flags[i, _FLAG.chord] = T.flags[i, _FLAG.affine] or (size_ <= CHORD
                                                               and not _carries(T, i))
        # (an iterate this near is likely the orbit: its copies run both ways at once)
        T.flags[i, _FLAG.central] = not T.flags[i, _FLAG.chord] and size_ <= LAST_STEP
    if converged:  # a fixed point; taken or not
        phase = _converged(T, i, m, centre, strobes, jac, scale, floor)
    if failed:  # integrate on (a re-solve keeps the orbit it had)
        if not far:
            T.reals[i, _REAL.hint] = 0.0
        phase = _give_up(T, i)
    return phase


@njit(inline="always", **SOLVER_JIT)
def _trajectory_ran(T, i, m, centre, strobes):
    """The first run of point i's attempt is its trajectory's next p periods (metrics
    ``m``, end state ``centre``, ``strobes``): the trajectory moves on (an orbit the
    engine's steady-state test found is kept)."""
    size = T.components.shape[2]
    T.flags[i, _FLAG.touched] = _touched(T.rows[i], m)
    T.components[i, _COMPONENTS.t1] = centre[:size]
    T.counts[i, _COUNT.t1_periods] = T.counts[i, _COUNT.p]
    T.states[i, _STATES.traj] = centre
    T.reals[i, _REAL.run] += T.counts[i, _COUNT.p]
    if T.flags[i, _FLAG.tested]:
        T.states[i, _STATES.traj] = T.states[i, _STATES.y]
    else:
        T.metric_rows[i, _METRIC_ROWS.metrics] = m
        T.strobes[i] = strobes


@njit(inline="always", **SOLVER_JIT)
def _newton_step(T, i, m, centre, jac, ok):
    """Newton's step from point i's iterate to the fixed point of the map that ran it to
    ``centre`` with monodromy ``jac`` (where ``ok``): the component scales of the run (its
    own where ok, else the last), the step, its size relative to the scales (inf where
    I - M is singular), whether it was taken (``good``), and Newton's floor (the settle
    tolerance, or rounding times the conditioning of I - M)."""
    size = T.components.shape[2]
    xs = np.maximum(abs(m[METRIC.x_max]), abs(m[METRIC.x_min]))
    scale = np.empty(size)
    period_map.point_scales(T.rows[i], xs if ok else 1.0, m[METRIC.v_peak] if ok else 1.0,
                            scale)
    for c in range(size):
        if not (ok and scale[c] > 0):
            scale[c] = T.components[i, _COMPONENTS.scale, c]
        scale[c] = max(scale[c], T.components[i, _COMPONENTS.floor, c])
    residual = centre[:size] - T.states[i, _STATES.y, :size]
    step = np.zeros(size)
    cond = np.inf
    good = False
    if ok:
        scaled = np.empty((size, size))  # (I - M) in scaled components
        for r in range(size):
            for c in range(size):
                scaled[r, c] = ((1.0 if r == c else 0.0) - jac[r, c]) / scale[r] * scale[c]
        d, inverse = dense.det_and_inverse(scaled)
        good = abs(d) > 1e-12
        if good:
            step = scale * dense.matvec(inverse, residual / scale)
            cond = dense.row_sum_norm(inverse)
    size_ = norm(step, scale) if good else np.inf
    floor = np.maximum(T.rows[i, PARAM.tolerance], ROUNDING * cond)
    return scale, step, size_, good, floor


@njit(inline="always", **SOLVER_JIT)
def _converged(T, i, m, centre, strobes, jac, scale, floor):
    """Point i's Newton iterates converged to a fixed point: solved again at a shorter
    period that closes the orbit too (_NEWTON), taken (_ESTIMATE, or _DONE without an
    error estimate), or not taken (_give_up). Returns its next phase."""
    size = T.components.shape[2]
    p = T.counts[i, _COUNT.p]
    y = T.states[i, _STATES.y, :size].copy()
    # a shorter period that also closes the orbit: solve again at it
    shorter = closing_period(strobes, y, p, scale, 10 * floor)
    if shorter < p:
        T.counts[i, _COUNT.p] = shorter
        T.counts[i, _COUNT.iteration] = 1  # (the trajectory already ran this attempt)
        T.reals[i, _REAL.last] = np.inf
        T.flags[i, _FLAG.chord] = False
        return _NEWTON
    radius = dense.spectral_radius(jac)
    stable = radius < 1.0
    refining = T.counts[i, _COUNT.refine] > 0
    row = T.rows[i]
    # (a moving stop comes at most stop_displacement_max towards the tip: 0 if rigid)
    xmax = np.maximum(m[METRIC.x_max], centre[STATE.x]) + m[METRIC.stop_displacement_max]
    xmin = np.minimum(m[METRIC.x_min], centre[STATE.x])
    free = m[METRIC.impacts_per_period] == 0 and xmax < row[PARAM.gap] \
        and m[METRIC.impacts_per_period_lower] == 0 and xmin > -row[PARAM.lower_gap]
    e = T.components[i, _COMPONENTS.t0] - y
    proved = never_reaches(row, xmax, xmin, e)
    linear = row[PARAM.khm] == 0 and row[PARAM.lower_khm] == 0  # (no stop at all)
    free = free or linear
    proved = proved or linear
    near = NEAR
    on_way = False  # (asked where the orbit has contact)
    if not free:
        q = max(T.counts[i, _COUNT.t1_periods] // p, 1)  # (maps of p periods from t0 to t1)
        near = reach(m, scale)
        on_way = on_its_way(T.components[i, _COMPONENTS.t0], T.components[i, _COMPONENTS.t1],
                            q, y, jac, scale, floor, near)
    if refining or (stable and (proved if free else on_way)):
        T.metric_rows[i, _METRIC_ROWS.metrics] = m
        T.strobes[i] = strobes
        T.states[i, _STATES.finals, :size] = y
        T.states[i, _STATES.finals, size:] = centre[size:]
        T.states[i, _STATES.y] = T.states[i, _STATES.finals]
        T.jacobians[i, _JACOBIANS.jacobian] = jac
        T.reals[i, _REAL.orbit_steps] = T.reals[i, _REAL.steps]
        T.reals[i, _REAL.floor] = floor
        # (its successor starts: need not wait for estimates)
        T.counts[i, _COUNT.status] = STATUS.settled
        if T.flags[i, _FLAG.estimated]:
            T.counts[i, _COUNT.iteration] = 0
            return _ESTIMATE
        return _DONE
    # not taken: integrate on for about the periods the motion needs to come near
    d0 = norm(e, scale)
    T.reals[i, _REAL.hint] = periods_to_near(p, near, d0, radius) if stable and d0 > near else 0.0
    T.counts[i, _COUNT.refused] = p if stable and not free else 0
    return _give_up(T, i)


@njit(inline="always", **SOLVER_JIT)
def _give_up(T, i):
    """Point i's attempt did not give an orbit to take: integrate the trajectory on
    (_TRANSIENT), or _DONE: a re-solve at a finer step keeps the orbit and estimate it
    had; an orbit found by the engine's steady-state test stands, with the monodromy of
    the attempt's first run, at its state (not estimated: the orbit is not a fixed point
    to Newton); a budget spent ends the point not settled. Returns the next phase."""
    if T.counts[i, _COUNT.refine] > 0:
        return _DONE
    if T.flags[i, _FLAG.tested]:
        T.counts[i, _COUNT.status] = STATUS.settled
        T.states[i, _STATES.finals] = T.states[i, _STATES.traj]
        T.jacobians[i, _JACOBIANS.jacobian] = T.jacobians[i, _JACOBIANS.first_jacobian]
        return _DONE
    if T.reals[i, _REAL.run] < T.rows[i, PARAM.max_periods]:
        _chunk(T, i)
        return _TRANSIENT
    T.counts[i, _COUNT.status] = STATUS.not_settled
    T.states[i, _STATES.finals] = T.states[i, _STATES.traj]
    return _DONE


@njit(inline="always", **SOLVER_JIT)
def _diverge(T, i):
    """Point i diverged: done, its successor starts from its own state."""
    T.counts[i, _COUNT.status] = STATUS.diverged
    T.metric_rows[i, _METRIC_ROWS.metrics, :METRIC.orbit_period] = np.nan
    T.strobes[i] = np.nan
    T.states[i, _STATES.finals] = T.states[i, _STATES.traj]


# -- the trajectory ------------------------------------------------------------------------

@njit(inline="always", **SOLVER_JIT)
def _chunk(T, i):
    """Point i integrates its trajectory on: as long as all it has run so far (at least
    FIRST_CHUNK periods), or the periods the last attempt's monodromy says the motion
    needs to come NEAR its orbit, within the budget: to its end, or short of it by
    2 MAX_ORBIT_PERIOD periods at least (phase _TRANSIENT)."""
    chunk = max(T.reals[i, _REAL.run], float(FIRST_CHUNK))
    hint = T.reals[i, _REAL.hint]
    if hint > 0:
        chunk = min(max(hint, float(T.counts[i, _COUNT.p])), 4 * chunk)
    # (a motion that does not settle reports its last MAX_ORBIT_PERIOD periods: a chunk
    # that ends short of the budget leaves twice that, room for an attempt of up to
    # MAX_ORBIT_PERIOD periods and a last piece of trajectory as long as the report)
    rest = T.rows[i, PARAM.max_periods] - T.reals[i, _REAL.run]
    if chunk >= rest or rest <= 2 * MAX_ORBIT_PERIOD:
        T.reals[i, _REAL.left] = rest
    else:
        T.reals[i, _REAL.left] = min(chunk, rest - 2 * MAX_ORBIT_PERIOD)


@njit(**SOLVER_JIT)
def _transient(T, i, m, f, strobes):
    """The phase _TRANSIENT: a piece of point i's trajectory chunk was run (metrics ``m``,
    end state ``f``, ``strobes``). Returns its next phase: _TRANSIENT while the chunk goes
    on, _NEWTON for an attempt from where it got to, _DONE when it diverged or spent its
    budget."""
    T.flags[i, _FLAG.touched] = _touched(T.rows[i], m)
    T.reals[i, _REAL.run] += m[METRIC.periods_run]
    T.reals[i, _REAL.left] -= m[METRIC.periods_run]
    T.states[i, _STATES.traj] = f
    T.metric_rows[i, _METRIC_ROWS.metrics] = m
    T.strobes[i] = strobes
    if not sane_run(m):
        _diverge(T, i)
        return _DONE
    if T.reals[i, _REAL.run] >= T.rows[i, PARAM.max_periods]:
        T.counts[i, _COUNT.status] = STATUS.not_settled
        T.states[i, _STATES.finals] = T.states[i, _STATES.traj]
        return _DONE
    # the engine's steady-state test passed: Newton polishes the orbit and gives its
    # multipliers; where it cannot (a period map too rough for it), the orbit the test
    # found stands (_give_up)
    settled = m[METRIC.status] == STATUS.settled
    if not settled and T.reals[i, _REAL.left] > 0:
        return _TRANSIENT  # (the chunk goes on in the next round)
    if settled:
        T.flags[i, _FLAG.tested] = True
    # (a motion nearing a stable orbit along a multiplier near -1 repeats after twice its
    # period better than after it, and Newton on that map, whose multiplier is then near
    # +1, stalls: where the samples suggest twice the period of the orbit with contact it
    # was last turned away from, the period is that orbit's)
    suggested = suggested_period(strobes, T.components[i, _COMPONENTS.scale])
    refused = T.counts[i, _COUNT.refused]
    if refused > 0 and suggested == 2 * refused:
        suggested = refused
    T.flags[i, _FLAG.retry] = not settled and suggested == refused
    T.counts[i, _COUNT.refused] = 0
    T.counts[i, _COUNT.p] = int(m[METRIC.orbit_period]) if settled else suggested
    _attempt(T, i)
    return _NEWTON


# -- error estimate and accuracy -------------------------------------------------------------

@njit(**SOLVER_JIT)
def _estimate(T, i, m, f, ok):
    """The phase _ESTIMATE: quasi-Newton at twice the steps from point i's orbit, with its
    monodromy. Returns its next phase: _ESTIMATE until the orbit at twice the steps is
    located, then _DONE, or _NEWTON for a re-solve at a finer step where the estimate is
    above the accuracy target (_refine)."""
    size = T.components.shape[2]
    step = np.zeros(size)
    size_ = np.inf
    change = np.nan
    if ok:
        a = np.eye(size) - T.jacobians[i, _JACOBIANS.jacobian]
        step = dense.solve_system(a, f[:size] - T.states[i, _STATES.y, :size])
        size_ = norm(step, T.components[i, _COMPONENTS.scale])
        change = halving_error(T.metric_rows[i, _METRIC_ROWS.metrics], m)
    # (or the run is near enough the orbit at twice the steps for the change it measures:
    # where the map is not smooth at Newton's floor the iterates contract slowly, and four
    # runs may not reach it)
    converged = ok and (size_ <= T.reals[i, _REAL.floor] or size_ <= LOCATED * change)
    T.counts[i, _COUNT.iteration] += 1
    last = not converged and T.counts[i, _COUNT.iteration] >= ESTIMATE_RUNS
    # at the last run, an estimate still not located but farther from the target than the
    # run is from the finer orbit says whether the target is met (the metrics of a run
    # move by about twice its start's distance, power being a square): where the map jumps
    # near Newton's floor the iterates may stall short of LOCATED
    decided = last and ok and abs(change - T.reals[i, _REAL.accuracy]) >= 2 * size_
    converged = converged or decided
    if last and not decided:
        return _DONE
    if not converged:
        T.states[i, _STATES.y, :size] += step
        return _ESTIMATE
    T.reals[i, _REAL.errors] = change
    # the accuracy target: solve again at the step the fourth order asks for, or at twice
    # the steps after a re-solve whose estimate fell slower than SLOW_ORDER
    target = T.reals[i, _REAL.accuracy]
    want = refined_steps(T.reals[i, _REAL.steps], change, target,
                         T.reals[i, _REAL.coarser_steps], T.reals[i, _REAL.coarser_error],
                         T.counts[i, _COUNT.refine])
    if np.isfinite(target) and change > target and T.counts[i, _COUNT.refine] < REFINEMENTS \
            and want <= T.reals[i, _REAL.max_steps]:
        _refine(T, i, want, step)
        return _NEWTON
    return _DONE


@njit(inline="always", **SOLVER_JIT)
def _refine(T, i, steps, step):
    """Set up the re-solve of point i at ``steps`` steps per period (at least
    STEPS_QUANTUM more), from its orbit moved by ``step``, Newton's step towards the
    orbit at twice the steps (phase _NEWTON)."""
    size = T.components.shape[2]
    T.reals[i, _REAL.coarser_steps] = T.reals[i, _REAL.steps]
    T.reals[i, _REAL.coarser_error] = T.reals[i, _REAL.errors]
    T.reals[i, _REAL.steps] = np.maximum(steps, T.reals[i, _REAL.steps] + STEPS_QUANTUM)
    T.counts[i, _COUNT.refine] += 1
    T.states[i, _STATES.y, :size] += step  # the orbit at twice the steps: closer
    T.counts[i, _COUNT.iteration] = 0
    T.reals[i, _REAL.last] = np.inf
    T.flags[i, _FLAG.touched] = _touched(T.rows[i], T.metric_rows[i, _METRIC_ROWS.metrics])
    _first_run(T, i)
    # (its orbit lies between the coarser one and the one at twice the steps, where it
    # starts: where those two are within LAST_STEP, its copies run both ways at once, as
    # those of an iterate that near its orbit do)
    moved = T.states[i, _STATES.y, :size] - T.states[i, _STATES.finals, :size]
    T.flags[i, _FLAG.central] = not T.flags[i, _FLAG.chord] \
        and norm(moved, T.components[i, _COMPONENTS.scale]) <= LAST_STEP


# -- the compiled code's cache ---------------------------------------------------------------

#: The modules whose compiled functions the solver's rounds are made from (the engine
#: aside): numba checks a cached function against its own file alone, so the solver's are
#: dropped together when any of these, or the engine, changes (_engine.cache).
_COMPILED = (sys.modules[__name__], acceptance, accuracy, dense, period_map)
#: SHA-256 of the source the solver's numbers come from: the engine's and these modules'.
SOURCE_DIGEST = cache.source_digest(cache.ENGINE_SOURCES + tuple(
    cache.PACKAGE / (m.__name__.split(".")[-1] + ".py") for m in _COMPILED))
cache.flush_if_changed(_round, _COMPILED, SOURCE_DIGEST)


#: The longest a first compile waits for the process that compiles the solver's decisions
#: beside it (_decisions_beside) once its own engine is compiled [s]: they take about a
#: minute on one core.
HELPER_WAIT = 600.0


def _no_points() -> _Points:
    """A table of no points, of the types every solve's table has."""
    return _points(np.zeros((0, len(PARAM))), np.zeros((0, len(STATE))),
                   np.zeros(0, np.int64), np.zeros(0, bool), np.zeros(0), np.zeros(0),
                   SETTLING)


def compile_solver() -> None:
    """Compile the solver and the engine, or load them from numba's on-disk cache, without
    running a point (the table's types are the same for any size of the state). A first
    compile of both, with two cores or more, has a second process compile the solver's
    decisions meanwhile (compile_decisions), which this one then loads."""
    helper = _decisions_beside() if _first_compile() else None
    try:
        period_map.compile_engine()
        if helper is not None:
            helper.wait(timeout=HELPER_WAIT)
    except subprocess.TimeoutExpired:
        pass  # (compile_decisions compiles what the helper did not save)
    finally:
        if helper is not None and helper.poll() is None:
            helper.kill()
    compile_decisions()
    team = np.zeros((1, len(_TEAM)), dtype=np.int64)
    team[0, _TEAM.threads] = 1
    _rounds(_no_points(), team, 0)  # (and the _round it calls)


def _first_compile() -> bool:
    """Whether neither this process nor numba's on-disk cache holds the engine or the
    solver's decisions (cache.holds: not is_warm, which says 'cold' for the rest of a
    process that flushed the cache)."""
    return not (period_map.engine_at_hand() or _newton.overloads or cache.holds(_newton))


def _decisions_beside():
    """A process that compiles the solver's decisions (compile_decisions) into numba's
    on-disk cache, where this process may use two cores or more; None where it may not,
    or where no process can be started. Its failure costs only what this process then
    compiles itself."""
    try:
        if len(os.sched_getaffinity(0)) < 2:
            return None
    except AttributeError:  # (no affinity on this platform)
        if (os.cpu_count() or 1) < 2:
            return None
    path = os.pathsep.join([str(Path(__file__).resolve().parents[1]),
                            os.environ.get("PYTHONPATH", "")])
    try:
        return subprocess.Popen(
            [sys.executable, "-c",
             "from harvester_sweep.orbits import compile_decisions; compile_decisions()"],
            env={**os.environ, "PYTHONPATH": path}, stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        return None


def compile_decisions() -> None:
    """Compile the solver's set-up and its phases' decisions (``_set_up``, ``_newton``,
    ``_transient``, ``_estimate``), or load them from numba's on-disk cache, without the
    engine: for the types ``_round`` calls them with, so that a compile of the solver that
    finds them cached has only ``_rounds`` and ``_round``, with the engine's calls, left to
    compile. A second process can compile them while the first compiles the engine (the
    test suite's workers do: conftest.py)."""
    pts = _no_points()
    _set_up(pts, np.zeros(0), True, np.zeros((0, 2)), np.zeros(0, np.int64))
    # (as _round passes them: a row of its metrics, states and strobes, its jac, ok a bool)
    metrics, states = np.empty((1, len(METRIC))), np.empty((1, len(STATE)))
    strobes, jac = np.empty((1, SAMPLES, N_RIGID)), np.empty((N_RIGID, N_RIGID))
    run = tuple(numba.typeof(a) for a in (pts, np.int64(0), metrics[0], states[0], strobes[0]))
    _newton.compile(run + (numba.typeof(jac), numba.types.boolean))
    _transient.compile(run)
    _estimate.compile(run[:4] + (numba.types.boolean,))


def solver_ready() -> bool:
    """Whether the solver and the engine are in numba's on-disk cache (else the first solve
    compiles them)."""
    return period_map.engine_ready() and cache.is_warm(_round)


__all__ = ["SOURCE_DIGEST", "Orbits", "WORK", "compile_decisions", "compile_solver", "solve_orbits",
           "solver_ready"]
