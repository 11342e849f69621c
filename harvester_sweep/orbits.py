"""Periodic orbits of the RK4 period map: how every point reaches its steady state.

A point's steady state is a fixed point ``y* = P^p(y*)`` of the p-period stroboscopic map
``P^p: y(0) -> y(pT)`` of the engine's own fixed-step RK4 with located contact switches,
so it is the RK4 solution's own periodic orbit. :func:`solve_orbits` finds it by Newton's
method from the state the motion has reached, and gives every point its Floquet
multipliers (the eigenvalues of the monodromy matrix ``dP^p/dy``).

How, and why (docs/numerics.md, "Periodic orbits"):

- **The monodromy matrix by perturbed copies.** Each Newton iterate is run for p periods
  in one lane and, in three more, from it moved by ``PERTURBATION`` of each component's
  scale: the columns of the monodromy are the forward differences. The copies are
  ordinary points of the lane engine (the same RK4, switches located as in the run), so
  the matrix includes the contact switches without any saltation algebra. A converged
  orbit is judged, and its multipliers given, on central differences (``CENTRAL``, six
  copies), where its map is not affine: near grazing the map bends too sharply for the
  forward ones. An iterate a small Newton step (``LAST_STEP``) from the last runs its
  copies both ways at once, as it is likely the orbit.
- **Chord steps.** An iterate reuses the last monodromy and runs its centre lane alone
  where that monodromy is still the map's: no lane of its run touched a stop (the map is
  affine off the stop), or the iterate moved less than ``CHORD`` from where it was taken.
  Where the run Newton starts from is expected to stay clear of the stops (the last run
  did; from rest, the motion without the stops says so: period_map.contact_free_extent), its first
  iterate is a chord step too, with the contact-free map's monodromy in closed form
  (:func:`contact_free_monodromy`); if it touched after all, it is run again with copies.
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

from dataclasses import dataclass

import numpy as np

from . import dense, period_map
from ._engine import MAX_ORBIT_PERIOD, METRIC, NO_STOP, PARAM, STATE, STATUS
from .acceptance import (
    NEAR,
    never_reaches,
    norm,
    on_its_way,
    reach,
    reaches_a_stop,
)
from .accuracy import REFINEMENTS, STEPS_QUANTUM, halving_error, refined_steps
from .models import tip_mass
from .period_map import (
    PERTURBATION,
    ROUNDING,
    D,
    contact_free_monodromy,
    orbit_scales,
    sane,
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
SAMPLES = MAX_ORBIT_PERIOD + 1  # stroboscopic samples read back from each run

# A point's phase: what its next run is (:class:`_Points`). A phase that runs has one
# function that takes its points' runs and returns each point's next phase (_newton,
# _transient, _estimate; _converged and _give_up return theirs for the points they are
# handed); a point is set up for a phase's run where that next phase is chosen (_attempt,
# _chunk, _start_estimate, _refine), and _enter moves the points on.
_WAITING, _NEWTON, _TRANSIENT, _ESTIMATE, _DONE = range(5)


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
        int64 (n,): the round (engine call, counted from 1) in which the point was done,
        0 for a point not run: how long a solve took in calls, each of which costs the
        solver's Python besides its steps (what run_estimate counts).
    """

    metrics: np.ndarray
    strobes: np.ndarray
    finals: np.ndarray
    multipliers: np.ndarray
    errors: np.ndarray
    steps: np.ndarray
    rk4_steps: np.ndarray
    rounds: np.ndarray


def solve_orbits(rows, states, successors=None, estimated=None, accuracy=None,
                 max_steps=None, samples=0, on_points=None) -> Orbits:
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
        Called with the number of points newly finished after each round of runs; what it
        raises (KeyboardInterrupt included) stops the solve and is raised again.
    """
    n = len(rows)
    pts = _Points(np.asarray(rows, dtype=float), np.asarray(states, dtype=float),
                  np.full(n, -1) if successors is None else np.asarray(successors),
                  np.zeros(n, bool) if estimated is None else np.asarray(estimated, bool),
                  np.full(n, np.nan) if accuracy is None else np.asarray(accuracy, float),
                  np.full(n, np.inf) if max_steps is None else np.asarray(max_steps, float))
    pts.start(np.flatnonzero(pts.heads()))
    while not (pts.phase == _DONE).all():
        assert ((pts.phase != _WAITING) & (pts.phase != _DONE)).any(), "no point to run"
        done = pts.round()
        pts.calls += 1
        pts.rounds[(pts.phase == _DONE) & (pts.rounds == 0)] = pts.calls
        if on_points is not None and done:
            on_points(done)
    return pts.result(samples)


class _Points:
    """The points of one solve, each a small state machine (its phase) advanced one round
    of engine runs at a time; all arrays are indexed by point. A point's result depends on
    its own numbers only: every transition acts on each point apart."""

    def __init__(self, rows, states, successors, estimated, accuracy, max_steps):
        n = len(rows)
        self.D = state_size(rows)
        self.rows, self.successors, self.estimated = rows, successors, estimated
        self.accuracy, self.max_steps = accuracy, max_steps
        self.phase = np.full(n, _WAITING)
        self.begin = states.copy()  # start state (rest, or the predecessor's orbit)
        self.traj = states.copy()  # the trajectory's state
        self.run = np.zeros(n)  # trajectory periods run
        self.work = np.zeros(n)  # RK4 steps taken
        self.calls = 0  # rounds run
        self.rounds = np.zeros(n, dtype=np.int64)  # the round each point was done in
        self.steps = rows[:, PARAM.steps].copy()
        self.p = np.ones(n, dtype=np.int64)  # orbit period tried
        self.y = states.copy()  # Newton iterate (or the orbit under estimate)
        self.iteration = np.zeros(n, dtype=np.int64)
        self.last = np.full(n, np.inf)  # size of the last Newton correction
        self.refine = np.zeros(n, dtype=np.int64)  # re-solves at a finer step so far
        self.t0 = states[:, :self.D].copy()  # trajectory state at the attempt's start
        self.t1 = states[:, :self.D].copy()  # ... and t1_periods periods later
        self.t1_periods = np.ones(n, dtype=np.int64)
        self.orbit_steps = self.steps.copy()  # steps per period of the orbit taken
        self.floor = np.zeros(n)  # Newton's floor at the orbit taken
        self.released = np.zeros(n, bool)  # successors started
        self.hint = np.zeros(n)  # periods the trajectory should run next (0: no idea)
        self.left = np.zeros(n)  # periods of the trajectory's chunk still to run
        self.tested = np.zeros(n, bool)  # the engine's steady-state test passed
        # period of the stable orbit with contact last turned away (0: none)
        self.refused = np.zeros(n, dtype=np.int64)
        self.retry = np.zeros(n, bool)  # the attempt is at that period
        self.scale = np.ones((n, self.D))
        self.scale[:] = self._linear_scale()
        self.jacobian = np.full((n, self.D, self.D), np.nan)
        self.first_jacobian = np.full((n, self.D, self.D), np.nan)  # at each attempt's start
        self.newton_jacobian = np.full((n, self.D, self.D), np.nan)  # at the last copies
        self.chord = np.zeros(n, bool)  # the next iterate reuses newton_jacobian
        self.affine = np.zeros(n, bool)  # ... taken where no lane touched a stop
        self.central = np.zeros(n, bool)  # the next copies run both ways
        # newton_jacobian is one to judge an orbit on: by central differences, or of a map
        # affine where it was taken (where forward differences are exact)
        self.exact = np.zeros(n, bool)
        # the run Newton starts from touched a stop (before any run: the linear motion's
        # first period says whether it will)
        self.touched = np.zeros(n, bool)
        if self.D == D:
            extent = period_map.contact_free_extent(rows, states, GUESS_STEPS)
            self.touched = reaches_a_stop(rows, extent[:, 0], extent[:, 1])
        self.recheck = np.zeros(n, bool)  # the attempt's first run, again with copies
        self.metrics = np.full((n, len(METRIC)), np.nan)
        self.fine = np.full((n, len(METRIC)), np.nan)  # metrics at twice the steps
        self.strobes = np.full((n, SAMPLES, self.D), np.nan)
        self.finals = states.copy()
        self.errors = np.full(n, np.nan)
        self.coarser = np.full((n, 2), np.nan)  # steps and error estimate of the last solve
        self.status = np.full(n, STATUS.not_settled)

    # -- set-up ------------------------------------------------------------------------

    def heads(self):
        linked = self.successors[self.successors >= 0]
        head = np.ones(len(self.rows), bool)
        head[linked] = False
        return head

    def _linear_scale(self):
        """Component scales [m, m/s, V] before any run: the response without the stop (the
        model's linear system's phasor), floored at the gap."""
        r = self.rows
        x = tip_mass.free_amplitude(r[:, PARAM.amplitude], 2 * np.pi / r[:, PARAM.period],
                                    r[:, PARAM.wn2], r[:, PARAM.cm], r[:, PARAM.thm],
                                    r[:, PARAM.irc], r[:, PARAM.thc])
        x = np.where(np.isfinite(x), x, 0.0)
        gap = np.where(r[:, PARAM.gap] < NO_STOP, np.abs(r[:, PARAM.gap]), 0.0)
        x = np.maximum(x, gap * 1e-3) + 1e-30
        return self._scales(x, 0.0)

    def _scales(self, x, v_peak, index=slice(None)):
        return orbit_scales(self.rows[index], x, v_peak, self.D)

    def start(self, idx):
        """Points ``idx`` start: refused ones are done at once (their state passes on), the
        others make a Newton attempt from their initial state."""
        runs = self.rows[idx, PARAM.max_periods] > 0
        refused, going = idx[~runs], idx[runs]
        self.metrics[refused, :METRIC.orbit_period] = np.nan
        self.status[refused] = STATUS.too_stiff
        self.finals[refused] = self.begin[refused]
        self.traj[going] = self.begin[going]
        self._attempt(going)
        self._enter(idx, np.where(runs, _NEWTON, _DONE))

    def _attempt(self, idx):
        """Set up a Newton attempt from the trajectory's state (phase _NEWTON)."""
        self.y[idx] = self.traj[idx]
        self.t0[idx] = self.traj[idx, :self.D]
        self.iteration[idx] = 0
        self.last[idx] = np.inf
        self._first_run(idx)

    def _first_run(self, idx):
        """Newton's first run from points ``idx``' iterates: where the motion was clear of
        the stops, it is likely to be too, so its centre lane alone, with the contact-free
        map's monodromy (run again with copies if it touched after all); else with copies."""
        self.chord[idx] = self.central[idx] = self.exact[idx] = False
        free = idx[~self.touched[idx]]
        if self.D == D and free.size:  # (a moving stop's map is not the tip's alone)
            self.chord[free] = self.affine[free] = self.exact[free] = True
            self.newton_jacobian[free] = contact_free_monodromy(self.rows[free], self.steps[free],
                                                        self.p[free])

    # -- one round ---------------------------------------------------------------------

    def round(self):
        """Run every point's next request in one engine call and act on the results;
        returns the number of points that finished."""
        iterate = self.phase == _NEWTON
        copied = iterate & ~self.chord  # with the copies of the monodromy
        forward = np.flatnonzero(copied & ~self.central)
        central = np.flatnonzero(copied & self.central)
        chord = np.flatnonzero(iterate & self.chord)
        transient = np.flatnonzero(self.phase == _TRANSIENT)
        estimate = np.flatnonzero(self.phase == _ESTIMATE)
        batch = period_map.Batch(self.D, SAMPLES)
        blocks = [(b, kind) for b, kind in [(forward, "forward"), (central, "central")]
                  if b.size]
        for b, kind in blocks:
            batch.add(self.rows[b], self.y[b], self.p[b], self.steps[b], kind, self.scale[b])
        batch.add(self.rows[chord], self.y[chord], self.p[chord], self.steps[chord])
        # (no slice shorter than MAX_ORBIT_PERIOD unless the whole chunk is: see _chunk)
        left = self.left[transient]
        batch.add(self.rows[transient], self.traj[transient],
                  np.where(left < SLICE + MAX_ORBIT_PERIOD, left, SLICE), self.steps[transient])
        batch.add(self.rows[estimate], self.y[estimate], self.p[estimate],
                  2 * self.steps[estimate])
        # (the engine's steady-state test ends a piece of the motion that settles; it never
        # ends a Newton or estimate run, whose p <= MAX_ORBIT_PERIOD periods are fewer
        # than the SAMPLES periods the test waits for)
        *copies, chords, transients, estimates = batch.run(settle=True)
        for b, ev in zip([b for b, _ in blocks] + [chord, transient, estimate],
                         copies + [chords, transients, estimates]):
            self.work[b] += ev.work
        before = int((self.phase == _DONE).sum())
        for (b, kind), ev in zip(blocks, copies):
            self._copies(b, ev, kind)
        # (in a re-solve at a finer step, a step by central differences is not compared
        # with the last one, by forward differences: near grazing that one can be several
        # times off. In a first solve a step that does not contract ends the attempt, as it
        # did: there it also turns away orbits the motion does not reach)
        self.central[central] = False
        resolved = central[self.refine[central] > 0]
        self.last[resolved] = np.inf
        runs = [(ev.metrics, ev.ends, ev.strobes, ev.jacobian, ev.ok) for ev in copies]
        runs.append((chords.metrics, chords.ends, chords.strobes,
                     self.newton_jacobian[chord], chords.ok))
        newton = np.concatenate([b for b, _ in blocks] + [chord])
        after = [self._newton(newton, *(np.concatenate(parts) for parts in zip(*runs))),
                 self._transient(transient, transients.metrics, transients.ends,
                                 transients.strobes),
                 self._estimate(estimate, estimates.metrics, estimates.ends, estimates.ok)]
        self._enter(np.concatenate([newton, transient, estimate]), np.concatenate(after))
        return int((self.phase == _DONE).sum()) - before

    def _enter(self, idx, phases):
        """Points ``idx`` go on to ``phases``; a point done, or taken on its orbit, lets its
        successor start (once)."""
        self.phase[idx] = phases
        self._release(idx[(phases == _DONE) | (self.status[idx] == STATUS.settled)])

    def _copies(self, idx, ev, kind):
        """Whether the runs of points ``idx`` with their copies of ``kind`` (an
        Evaluation) took an affine map, and whether their monodromy is one to judge an
        orbit on."""
        # (the copies book no extrema: their impacts alone say they stayed clear)
        r = self.rows[idx, None]
        self.affine[idx] = ~self._touched(idx, ev.metrics) & np.all(
            ((r[..., PARAM.khm] == 0) | (ev.copy_metrics[..., METRIC.impacts_per_period] == 0))
            & ((r[..., PARAM.lower_khm] == 0)
               | (ev.copy_metrics[..., METRIC.impacts_per_period_lower] == 0)), axis=1)
        self.exact[idx] = self.affine[idx] | (kind != "forward")

    # -- Newton ------------------------------------------------------------------------

    def _touched(self, idx, m):
        """Whether runs of points ``idx`` (their metric rows ``m``) touched a stop or came
        to its gap."""
        r = self.rows[idx]
        return reaches_a_stop(r, m[:, METRIC.x_max], m[:, METRIC.x_min]) \
            | (r[:, PARAM.khm] > 0) & (m[:, METRIC.impacts_per_period] > 0) \
            | (r[:, PARAM.lower_khm] > 0) & (m[:, METRIC.impacts_per_period_lower] > 0)

    def _newton(self, idx, m, centre, strobes, jac, lanes_ok):
        """The phase _NEWTON: a Newton iterate's run, metrics ``m``, end state ``centre``
        and strobes of its centre lane, the monodromy ``jac`` (of its copies, or reused by
        a chord step) and whether every lane ran sane and finite. Returns each point's next
        phase: _NEWTON for a next iterate (or the same one again, with copies), and those
        of a fixed point (_converged) or of an attempt given up (_give_up)."""
        phases = np.full(len(idx), _NEWTON)
        if not idx.size:
            return phases
        trajectory = (self.iteration[idx] == 0) & (self.refine[idx] == 0)
        self._trajectory_ran(idx[trajectory], m[trajectory], centre[trajectory],
                             strobes[trajectory])
        diverged = trajectory & ~sane(m)
        self._diverge(idx[diverged])
        phases[diverged] = _DONE
        ok = ~diverged & lanes_ok
        y = self.y[idx, :self.D]
        scale, step, size, good, floor = self._newton_step(idx, m, centre, jac, ok)
        converged = good & (size <= floor)
        # an orbit with contact is not taken from beyond NEAR of it: not when the first
        # step is beyond NEAR (the step is about the distance from the orbit), nor when the
        # motion moved more than 2 NEAR in these p periods (d0, d1 <= NEAR would bound
        # that move by 2 NEAR). Integrate on, for about the periods the motion needs to
        # come NEAR (from the monodromy at t), rather than pay the iterations. Nor when the
        # monodromy at t expands (EXPANDING): t is not in a stable orbit's linear regime
        touched = self._touched(idx, m)
        distance = np.maximum(size, 0.5 * norm(centre[:, :self.D] - y, scale))
        # (a first run that touched a stop with the contact-free map's monodromy is run
        # again with copies, and judged then)
        recheck = trajectory & self.chord[idx] & self.affine[idx] & touched & ~diverged
        opening = trajectory & ~recheck | self.recheck[idx]
        self.recheck[idx] = recheck
        # (a converged first run is judged by _converged, stable or not)
        looked = opening & good & touched & ((distance > NEAR) | ~converged)
        radius = np.zeros(len(idx))
        if looked.any():
            radius[looked] = dense.spectral_radius_each(jac[looked])
        # (not in an attempt at the period of the stable orbit with contact the last one
        # turned away: the motion nears that orbit, and the monodromy taken off it, by a
        # multiplier near -1, may expand)
        far = looked & ((distance > NEAR) | (radius > EXPANDING) & ~self.retry[idx])
        # a later iterate of an attempt from the motion, whose run touched a stop, is given
        # up when Newton has come within SETTLING of an orbit beyond NEAR of the motion's
        # state at the attempt's start (on_its_way takes an orbit with contact from within
        # NEAR of it; the steps left add up to about this one)
        later = ~opening & ~trajectory & good & touched & ~converged \
            & (self.refine[idx] == 0) & (size <= SETTLING) & (size <= 0.5 * self.last[idx])
        if later.any():
            d0 = norm(self.t0[idx] - (y + step), scale)
            away = later & (d0 - size > NEAR)
            if away.any():
                radius[away] = dense.spectral_radius_each(jac[away])
                distance = np.where(away, d0, distance)
                far |= away
        if far.any():
            radius = radius[far]
            need = np.ceil(self.p[idx[far]] * np.log(NEAR / (2 * distance[far]))
                           / np.log(np.clip(radius, 1e-3, 1 - 1e-9)))
            self.hint[idx[far]] = np.where(radius < 1, need, 0)
        stalled = ~converged & ~diverged & (
            ~good | (self.iteration[idx] + 1 >= MAX_NEWTON)
            | (self.iteration[idx] > 0) & (size > 0.5 * self.last[idx]))
        # in a re-solve at a finer step, an iterate that stalls within half the accuracy
        # target of its orbit is taken (its metrics then within about the target, power
        # being a square): where the map jumps near Newton's floor (by about its own error
        # where a switch crosses a step's end) the iterates stall short of it, and the
        # re-solve kept the coarser orbit, above the target; the error estimate that
        # follows measures the orbit as taken
        enough = stalled & good & (self.refine[idx] > 0) & (size <= 0.5 * self.accuracy[idx])
        converged |= enough
        stalled &= ~enough
        # a chord step that stalls, or that touched a stop with the monodromy of an affine
        # run (converged or not: that monodromy is not the orbit's), is taken again from
        # the same iterate, with copies
        again = recheck | (stalled | self.affine[idx] & touched) & self.chord[idx] & ~far \
            & ~diverged & (self.iteration[idx] + 1 < MAX_NEWTON)
        # a converged orbit is judged, and its multipliers given, on a monodromy by central
        # differences (CENTRAL) where its map is not affine: the forward ones err by
        # PERTURBATION times the map's curvature; so its copies run again from the same
        # iterate, both ways
        sharpen = converged & ~again & ~self.exact[idx] & ~diverged
        # (and in a re-solve at a finer step, which has no other way to its orbit, a chord
        # step that stalled had a monodromy too far off to contract: near grazing forward
        # differences can be, so it is taken again by central ones)
        self.central[idx[sharpen | again & stalled & (self.refine[idx] > 0)]] = True
        again |= sharpen
        converged &= ~again
        failed = far | stalled & ~again
        going = ~converged & ~failed & ~diverged & ~again
        self.scale[idx[ok]] = scale[ok]
        self.first_jacobian[idx[opening]] = jac[opening]
        self.newton_jacobian[idx] = jac
        self.iteration[idx[again]] += 1
        self.chord[idx[again]] = False
        # on: a new iterate, by a chord step where the monodromy is known there (the map is
        # affine where no lane touched a stop; elsewhere the iterate moved less than CHORD)
        g = idx[going]
        self.y[g, :self.D] = y[going] + step[going]
        self.y[g, self.D:] = centre[going, self.D:]
        self.iteration[g] += 1
        self.last[g] = size[going]
        self.chord[g] = self.affine[g] | (size[going] <= CHORD)
        # (an iterate this near is likely the orbit: its copies run both ways at once)
        self.central[g] = ~self.chord[g] & (size[going] <= LAST_STEP)
        # converged: a fixed point; taken or not
        if converged.any():
            phases[converged] = self._converged(
                idx[converged], m[converged], centre[converged], strobes[converged],
                jac[converged], scale[converged], floor[converged])
        # failed: integrate on (a re-solve keeps the orbit it had)
        self.hint[idx[failed & ~far]] = 0
        phases[failed] = self._give_up(idx[failed])
        return phases

    def _trajectory_ran(self, idx, m, centre, strobes):
        """The first run of an attempt of points ``idx`` is their trajectory's next p
        periods (metrics ``m``, end states ``centre``, ``strobes``): the trajectory moves on
        (an orbit the engine's steady-state test found is kept)."""
        self.touched[idx] = self._touched(idx, m)
        self.t1[idx] = centre[:, :self.D]
        self.t1_periods[idx] = self.p[idx]
        self.traj[idx] = centre
        self.run[idx] += self.p[idx]
        tested = idx[self.tested[idx]]
        self.metrics[idx] = np.where(self.tested[idx, None], self.metrics[idx], m)
        self.strobes[idx] = np.where(self.tested[idx, None, None], self.strobes[idx], strobes)
        self.traj[tested] = self.y[tested]

    def _newton_step(self, idx, m, centre, jac, ok):
        """Newton's step from the iterates of points ``idx`` to the fixed point of the map
        that ran them to ``centre`` with monodromy ``jac`` (where ``ok``): the component
        scales of the run (its own where ok, else the last), the step, its size relative
        to the scales (inf where I - M is singular), whether it was taken (``good``), and
        Newton's floor (the settle tolerance, or rounding times the conditioning of
        I - M)."""
        xs = np.maximum(np.abs(m[:, METRIC.x_max]), np.abs(m[:, METRIC.x_min]))
        scale = self._scales(np.where(ok, xs, 1.0), np.where(ok, m[:, METRIC.v_peak], 1.0),
                             idx)
        scale = np.where(ok[:, None] & (scale > 0), scale, self.scale[idx])
        residual = centre[:, :self.D] - self.y[idx, :self.D]
        step = np.zeros_like(residual)
        cond = np.full(len(idx), np.inf)
        a = np.eye(self.D) - np.where(ok[:, None, None], jac, 0.0)
        scaled = a / scale[:, :, None] * scale[:, None, :]  # (I - M) in scaled components
        good = ok & (np.abs(dense.det_each(scaled)) > 1e-12)
        if good.any():
            inverse = dense.inverse_each(scaled[good])
            step[good] = scale[good] * dense.matvec_each(inverse, residual[good] / scale[good])
            cond[good] = dense.row_sum_norm_each(inverse)
        size = np.where(good, norm(step, scale), np.inf)
        floor = np.maximum(self.rows[idx, PARAM.tolerance], ROUNDING * cond)
        return scale, step, size, good, floor

    def _converged(self, idx, m, centre, strobes, jac, scale, floor):
        """Points ``idx`` whose Newton iterates converged to a fixed point: solved again at a
        shorter period that closes the orbit too (_NEWTON), taken (_ESTIMATE, or _DONE
        without an error estimate), or not taken (_give_up). Returns their next phases."""
        phases = np.full(len(idx), _NEWTON)
        p = self.p[idx]
        y = self.y[idx, :self.D]
        # a shorter period that also closes the orbit: solve again at it
        shorter = np.zeros(len(idx), dtype=np.int64)
        for d in range(int(p.max()) - 1, 0, -1):
            sample = strobes[np.arange(len(idx)), SAMPLES - 1 - (p - d).clip(0)]
            closes = (d < p) & (p % d == 0) & (norm(sample - y, scale) <= 10 * floor)
            shorter = np.where(closes, d, shorter)
        again = shorter > 0
        if again.any():
            self.p[idx[again]] = shorter[again]
            self.iteration[idx[again]] = 1  # (the trajectory already ran this attempt)
            self.last[idx[again]] = np.inf
            self.chord[idx[again]] = False
        keep = ~again
        idx, m, centre, strobes, jac, scale, floor, y = (
            a[keep] for a in (idx, m, centre, strobes, jac, scale, floor, y))
        if not idx.size:
            return phases
        kept = np.zeros(len(idx), phases.dtype)
        p = self.p[idx]
        radius = dense.spectral_radius_each(jac)
        stable = radius < 1.0
        refining = self.refine[idx] > 0
        r = self.rows[idx]
        # (a moving stop comes at most stop_displacement_max towards the tip: 0 if rigid)
        xmax = np.maximum(m[:, METRIC.x_max], centre[:, STATE.x]) \
            + m[:, METRIC.stop_displacement_max]
        xmin = np.minimum(m[:, METRIC.x_min], centre[:, STATE.x])
        free = (m[:, METRIC.impacts_per_period] == 0) & (xmax < r[:, PARAM.gap]) \
            & (m[:, METRIC.impacts_per_period_lower] == 0) & (xmin > -r[:, PARAM.lower_gap])
        e = self.t0[idx] - y
        proved = never_reaches(r, xmax, xmin, e)
        linear = (r[:, PARAM.khm] == 0) & (r[:, PARAM.lower_khm] == 0)  # (no stop at all)
        free |= linear
        proved |= linear
        q = np.maximum(self.t1_periods[idx] // p, 1)  # (maps of p periods from t0 to t1)
        on_way = np.zeros(len(idx), bool)  # (asked where the orbit has contact)
        w = ~free
        near = np.full(len(idx), NEAR)
        if w.any():
            near[w] = reach(m[w], scale[w])
            on_way[w] = on_its_way(self.t0[idx[w]], self.t1[idx[w]], q[w], y[w], jac[w],
                                   scale[w], floor[w], near[w])
        taken = refining | stable & np.where(free, proved, on_way)
        t = idx[taken]
        self.metrics[t] = m[taken]
        self.strobes[t] = strobes[taken]
        self.finals[t, :self.D] = y[taken]
        self.finals[t, self.D:] = centre[taken, self.D:]
        self.y[t] = self.finals[t]
        self.jacobian[t] = jac[taken]
        self.orbit_steps[t] = self.steps[t]
        self.floor[t] = floor[taken]
        self.status[t] = STATUS.settled  # (its successor starts: need not wait for estimates)
        self._start_estimate(t[self.estimated[t]])
        kept[taken] = np.where(self.estimated[t], _ESTIMATE, _DONE)
        # not taken: integrate on for about the periods the motion needs to come near
        d0 = norm(e, scale)
        with np.errstate(divide="ignore"):  # (d0 = 0: no hint, below)
            hint = np.ceil(p[~taken] * np.log(near[~taken] / (2 * d0[~taken]))
                           / np.log(np.clip(radius[~taken], 1e-3, 1 - 1e-9)))
        self.hint[idx[~taken]] = np.where(stable[~taken] & (d0[~taken] > near[~taken]), hint, 0)
        self.refused[idx[~taken]] = np.where(stable[~taken] & w[~taken], p[~taken], 0)
        kept[~taken] = self._give_up(idx[~taken])
        phases[keep] = kept
        return phases

    def _give_up(self, idx):
        """An attempt that did not give an orbit to take: integrate the trajectory on
        (_TRANSIENT), or _DONE: a re-solve at a finer step keeps the orbit and estimate it
        had; an orbit found by the engine's steady-state test stands, with the monodromy of
        the attempt's first run, at its state (not estimated: the orbit is not a fixed point
        to Newton); a budget spent ends the point not settled. Returns the next phases."""
        refining = self.refine[idx] > 0
        tested = ~refining & self.tested[idx]
        left = ~refining & ~tested & (self.run[idx] < self.rows[idx, PARAM.max_periods])
        out = ~refining & ~tested & ~left
        t, o = idx[tested], idx[out]
        self.status[t] = STATUS.settled
        self.finals[t] = self.traj[t]
        self.jacobian[t] = self.first_jacobian[t]
        self._chunk(idx[left])
        self.status[o] = STATUS.not_settled
        self.finals[o] = self.traj[o]
        return np.where(left, _TRANSIENT, _DONE)

    def _diverge(self, idx):
        """Points ``idx`` diverged: done, their successors start from their own state."""
        self.status[idx] = STATUS.diverged
        self.metrics[idx, :METRIC.orbit_period] = np.nan
        self.strobes[idx] = np.nan
        self.finals[idx] = self.traj[idx]

    # -- the trajectory ----------------------------------------------------------------

    def _chunk(self, idx):
        """Points ``idx`` integrate their trajectory on: as long as all it has run so far
        (at least FIRST_CHUNK periods), or the periods the last attempt's monodromy says
        the motion needs to come NEAR its orbit, within the budget: to its end, or short of
        it by 2 MAX_ORBIT_PERIOD periods at least (phase _TRANSIENT)."""
        chunk = np.maximum(self.run[idx], FIRST_CHUNK)
        hint = self.hint[idx]
        chunk = np.where(hint > 0, np.clip(hint, self.p[idx], 4 * chunk), chunk)
        # (a motion that does not settle reports its last MAX_ORBIT_PERIOD periods: a chunk
        # that ends short of the budget leaves twice that, room for an attempt of up to
        # MAX_ORBIT_PERIOD periods and a last piece of trajectory as long as the report)
        rest = self.rows[idx, PARAM.max_periods] - self.run[idx]
        self.left[idx] = np.where((chunk >= rest) | (rest <= 2 * MAX_ORBIT_PERIOD), rest,
                                  np.minimum(chunk, rest - 2 * MAX_ORBIT_PERIOD))

    def _transient(self, idx, m, f, strobes):
        """The phase _TRANSIENT: a piece of the trajectory's chunk was run (metrics ``m``,
        end states ``f``, ``strobes``). Returns each point's next phase: _TRANSIENT while the
        chunk goes on, _NEWTON for an attempt from where it got to, _DONE when it diverged
        or spent its budget."""
        phases = np.full(len(idx), _DONE)
        if not idx.size:
            return phases
        self.touched[idx] = self._touched(idx, m)
        self.run[idx] += m[:, METRIC.periods_run]
        self.left[idx] -= m[:, METRIC.periods_run]
        self.traj[idx] = f
        self.metrics[idx] = m
        self.strobes[idx] = strobes
        bad = ~sane(m)
        self._diverge(idx[bad])
        out = ~bad & (self.run[idx] >= self.rows[idx, PARAM.max_periods])
        self.status[idx[out]] = STATUS.not_settled
        self.finals[idx[out]] = self.traj[idx[out]]
        rest = ~bad & ~out
        position = np.flatnonzero(rest)
        idx, strobes, m = idx[rest], strobes[rest], m[rest]
        # the engine's steady-state test passed: Newton polishes the orbit and gives its
        # multipliers; where it cannot (a period map too rough for it), the orbit the test
        # found stands (_give_up)
        settled = m[:, METRIC.status] == STATUS.settled
        on = ~settled & (self.left[idx] > 0)  # the chunk goes on in the next round
        phases[position] = np.where(on, _TRANSIENT, _NEWTON)
        idx, strobes, m, settled = idx[~on], strobes[~on], m[~on], settled[~on]
        self.tested[idx[settled]] = True
        # (a motion nearing a stable orbit along a multiplier near -1 repeats after twice
        # its period better than after it, and Newton on that map, whose multiplier is
        # then near +1, stalls: where the samples suggest twice the period of the orbit
        # with contact it was last turned away from, the period is that orbit's)
        suggested = _orbit_period(strobes, self.scale[idx])
        refused = self.refused[idx]
        suggested = np.where((refused > 0) & (suggested == 2 * refused), refused, suggested)
        self.retry[idx] = ~settled & (suggested == refused)
        self.refused[idx] = 0
        self.p[idx] = np.where(settled, m[:, METRIC.orbit_period].astype(np.int64), suggested)
        self._attempt(idx)
        return phases

    # -- error estimate and accuracy -----------------------------------------------------

    def _start_estimate(self, idx):
        """Set up the error estimate of the orbits taken (phase _ESTIMATE)."""
        self.iteration[idx] = 0

    def _estimate(self, idx, m, f, ok):
        """The phase _ESTIMATE: quasi-Newton at twice the steps from the orbit, with its
        monodromy. Returns each point's next phase: _ESTIMATE until the orbit at twice the
        steps is located, then _DONE, or _NEWTON for a re-solve at a finer step where the
        estimate is above the accuracy target (_refine)."""
        phases = np.full(len(idx), _ESTIMATE)
        if not idx.size:
            return phases
        a = np.eye(self.D) - np.where(ok[:, None, None], self.jacobian[idx], 0.0)
        step = np.zeros((len(idx), self.D))
        if ok.any():
            residual = f[ok, :self.D] - self.y[idx[ok], :self.D]
            step[ok] = dense.solve_each(a[ok], residual)
        size = np.where(ok, norm(step, self.scale[idx]), np.inf)
        with np.errstate(invalid="ignore"):
            change = np.where(ok, halving_error(self.metrics[idx], m), np.nan)
        # (or the run is near enough the orbit at twice the steps for the change it
        # measures: where the map is not smooth at Newton's floor the iterates contract
        # slowly, and four runs may not reach it)
        converged = ok & ((size <= self.floor[idx]) | (size <= LOCATED * change))
        self.iteration[idx] += 1
        last = ~converged & (self.iteration[idx] >= ESTIMATE_RUNS)
        # at the last run, an estimate still not located but farther from the target than
        # the run is from the finer orbit says whether the target is met (the metrics of
        # a run move by about twice its start's distance, power being a square): where the
        # map jumps near Newton's floor the iterates may stall short of LOCATED
        decided = last & ok & (np.abs(change - self.accuracy[idx]) >= 2 * size)
        converged |= decided
        failed = last & ~decided
        going = ~converged & ~failed
        self.y[idx[going], :self.D] += step[going]
        phases[failed] = _DONE
        c = idx[converged]
        self.fine[c] = m[converged]
        self.errors[c] = change[converged]
        # the accuracy target: solve again at the step the fourth order asks for, or at
        # twice the steps after a re-solve whose estimate fell slower than SLOW_ORDER
        target = self.accuracy[c]
        want = refined_steps(self.steps[c], self.errors[c], target, self.coarser[c],
                             self.refine[c])
        again = (np.isfinite(target) & (self.errors[c] > target) & (self.refine[c] < REFINEMENTS)
                 & (want <= self.max_steps[c]))
        self._refine(c[again], want[again], step[converged][again])
        phases[converged] = np.where(again, _NEWTON, _DONE)
        return phases

    def _refine(self, idx, steps, step):
        """Set up the re-solve of points ``idx`` at ``steps`` steps per period (at least
        STEPS_QUANTUM more), from their orbit moved by ``step``, Newton's step towards the
        orbit at twice the steps (phase _NEWTON)."""
        self.coarser[idx] = np.stack([self.steps[idx], self.errors[idx]], axis=1)
        self.steps[idx] = np.maximum(steps, self.steps[idx] + STEPS_QUANTUM)
        self.refine[idx] += 1
        self.y[idx, :self.D] += step  # the orbit at twice the steps: closer
        self.iteration[idx] = 0
        self.last[idx] = np.inf
        self.touched[idx] = self._touched(idx, self.metrics[idx])
        self._first_run(idx)

    # -- the end of a point --------------------------------------------------------------

    def _release(self, idx):
        """The successors of points ``idx`` start from their orbit (from their own initial
        state after a divergence), once."""
        idx = idx[~self.released[idx]]
        self.released[idx] = True
        nxt = self.successors[idx]
        has = nxt >= 0
        follow, nxt = idx[has], nxt[has]
        if not nxt.size:
            return
        kept = self.status[follow] != STATUS.diverged
        self.begin[nxt[kept]] = self.finals[follow[kept]]
        self.touched[nxt[kept]] = self._touched(follow[kept], self.metrics[follow[kept]])
        self.p[nxt] = np.where(self.status[follow] == STATUS.settled, self.p[follow], 1)
        self.start(nxt)

    def result(self, samples):
        n = len(self.rows)
        metrics = self.metrics.copy()
        settled = self.status == STATUS.settled
        metrics[:, METRIC.status] = self.status
        metrics[:, METRIC.orbit_period] = np.where(settled, self.p, 0)
        metrics[:, METRIC.periods_run] = self.run
        multipliers = np.full((n, self.D), np.nan + 0j)
        if settled.any():
            multipliers[settled] = sorted_multipliers(self.jacobian[settled])
        strobes = np.full((n, samples, self.D), np.nan)
        age = np.arange(samples)[::-1]  # periods before the end
        # a settled orbit repeats: its p + 1 samples tiled; else the last run's samples
        p = np.where(settled, self.p, SAMPLES)
        back = np.where(settled[:, None], age[None, :] % p[:, None], age[None, :])
        valid = back < SAMPLES
        taken = np.take_along_axis(self.strobes, (SAMPLES - 1 - back.clip(0, SAMPLES - 1))
                                   [..., None].repeat(self.D, axis=2), axis=1)
        strobes[valid] = taken[valid]
        return Orbits(metrics, strobes, self.finals, multipliers, self.errors,
                      self.orbit_steps.astype(np.int64), self.work.astype(np.int64),
                      self.rounds.copy())


def _orbit_period(strobes, scale):
    """The orbit period suggested by a run's stroboscopic samples (..., SAMPLES, 3): the
    smallest p whose repeat |y(nT) - y((n-p)T)| is within 10 times the best of any p."""
    last = strobes[:, -1:, :]
    gaps = norm(last - strobes[:, -2::-1][:, :MAX_ORBIT_PERIOD], scale[:, None, :])
    gaps = np.where(np.isfinite(gaps), gaps, np.inf)
    best = gaps.min(axis=1, keepdims=True)
    within = gaps <= 10 * best
    p = np.argmax(within, axis=1) + 1
    return np.where(np.isfinite(best[:, 0]), p, 1)


__all__ = ["Orbits", "on_its_way", "reach", "solve_orbits"]
