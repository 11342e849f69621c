"""Branches of periodic orbits followed in one parameter, through folds.

A branch is the curve of solutions ``z = (y, lam)`` of ``F(z) = P^p(y; lam) - y = 0``: a
state ``y = (x, v, V)`` on a period-p orbit at forcing phase 0, and the value ``lam`` of the
continued parameter. ``P^p`` is the engine's own RK4 period map (contact switches
located), as in :mod:`harvester_sweep.orbits`, at a step per period fixed for the whole
branch so that the map is one smooth family. Pseudo-arclength continuation (Keller) steps
along the branch's unit tangent ``t`` and corrects by Newton on the square system
``[F(z); t . (z - z_predicted)] = 0``, whose Jacobian stays regular at a fold, where the
branch turns back in the parameter: the S-shaped response comes out whole, unstable parts
included. Components are scaled (x by the start orbit's amplitude, v by w x, V by its
peak voltage, lam by the range), and the arclength is measured in them.

- **Jacobian.** The monodromy matrix ``M = dP^p/dy`` carried along the iterate's run
  (the variational equations of the engine's own steps: period_map.Batch's "carried"
  requests) where the point can carry it (switches located, rigid stops, a fixed approach
  velocity); elsewhere from twelve perturbed copies, at +-1 and +-2 ``CENTRAL`` of each
  component's scale: the median of the four slopes between the five states along a
  component (the RK4 map jumps by about its own error where a switch crosses a step's
  end, and a slope across the jump is far off). ``dP^p/dlam`` by one more lane at
  ``lam + PERTURBATION * range``: every Newton iterate is one engine call of two lanes
  (fourteen with copies). Forward differences put the paper S-curve's lower fold where
  the SciPy reference's multiplier is 1.0036, central ones across a jump read 0.89 for its
  upper fold's 1.0000 (docs/numerics.md).
- **Steps.** The arclength step grows after an easy correction and shrinks after a hard
  one, a failed one or a turn of the tangent beyond ``MAX_TURN``: the branch's sharp bend
  where an orbit starts to touch the stop (a grazing) is passed in small steps, not
  jumped over.
- **Bifurcations** between two accepted points are where a test function changes sign:
  a fold where ``t_lam`` does, period doubling ``det(I + M)``, Neimark-Sacker
  ``|mu|^2 - 1`` of a complex pair of multipliers, grazing ``x_max - gap`` (a rigid upper
  stop; a moving stop's grazing is not watched) and ``-lower_gap - x_min``. Each is located
  by the Illinois method on the arclength between the two points, every trial point
  corrected onto the branch, until the bracket bounds the parameter to ``LOCATE``
  relative; the located point joins the branch with its flag. Where a correction inside
  the bracket fails, the end of the step is flagged, the step its bracket. A period
  doubling and a Neimark-Sacker point are located (and report their multipliers) on a
  monodromy of their own, by five-point differences over the first of
  ``MULTIPLIER_STEPS`` at which the map is smooth (``MULTIPLIER_AGREEMENT``) at both ends
  of the bracket: over the Jacobian's ``CENTRAL`` the map's jumps where a switch crosses a
  step's end enter the multipliers, and the location wandered with the step. Where no
  step is smooth (orbits of several periods bend at a smaller scale), or that monodromy
  does not bracket the sign change, it is located on the Jacobian's, as detected.
- **Period doubling.** With ``period_doubling="switch"`` the doubled branch is continued
  from each located period doubling: its orbits are fixed points of ``P^2p`` that leave
  the period-p orbit along the eigenvector of the multiplier -1. A doubled branch ends
  where it meets the orbit it doubles: where its offset after half its periods along that
  eigenvector changes sign (:func:`_half_offset`), or where its orbit has half its period
  (``COLLAPSED``); followed on, it would repeat orbits already found. The doubling it
  ends at starts no branch of its own, so that a branch between two doublings is
  followed once.
- **Error.** Every point is corrected again at twice its steps per period (its Jacobian
  reused): at its own parameter value, the change of its metrics is its
  ``error_estimate`` (near a fold, where that orbit may not exist, it is taken normal to
  the branch); normal to the branch, the change of the parameter is the point's shift.
  A located bifurcation is located again at twice its steps and at 3/2 of them, and the
  larger change of its location is its shift (fold, period doubling, Neimark-Sacker and
  grazing alike: one ratio alone can happen to be small, as the map's error wanders with
  the step).
- **Accuracy.** The branch is followed at one step; where that step was chosen
  automatically, a point whose estimate is above ``accuracy`` is solved again alone at
  the step the fourth order asks for, as a sweep point (accuracy.refined_steps), and a
  located bifurcation is located again at the step where its shift (relative to its
  value) and its estimate meet ``accuracy``: each point reports its own steps per period.
"""

from __future__ import annotations

import copy
import math
import time
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from . import period_map
from ._engine import MAX_ORBIT_PERIOD, METRIC, NO_STOP, PARAM, STATUS
from .accuracy import REFINEMENTS, STEPS_QUANTUM, halving_error, refined_steps
from .linear import linear_response
from .outputs import BIFURCATIONS
from .packing import check_runnable, pack_parameters, pack_points
from .parameters import (
    DEFAULT_PRESET,
    PARAMETERS,
    ParameterError,
    check_names,
    is_number,
    resolve_parameters,
    whole_number,
)
from .period_map import (
    CENTRAL,
    PERTURBATION,
    ROUNDING,
    multiplier_shift,
    orbit_scales,
    state_size,
)
from .results import solve
from .timescales import auto_steps_per_period

#: Newton iterations of one correction before it is given up [-].
MAX_CORRECTOR = 8
#: Largest turn of the tangent between two accepted points [rad]: a sharper bend is taken
#: in shorter steps (and a test function is bracketed by points that see the same branch).
MAX_TURN = 0.35
#: Relative precision in the parameter to which a bifurcation is located [-] (the issue
#: asks for 1e-6; the Illinois method gets there in a few more corrections).
LOCATE = 1e-8
#: A bifurcation located again within this distance of one already on the branch
#: (scaled components) means the branch has come round a loop [-].
REVISIT = 1e-6
#: A corrected point whose scaled M - I has no entry above this is refused [-]: the period
#: map is the identity to rounding there (a forcing period far shorter than every time
#: scale, 1e18 Hz for the paper's scene: M - I read 2e-10, the noise of rounding over the
#: monodromy's copies at period_map.CENTRAL), and any state passes for its orbit.
UNRESOLVED = 100 * np.finfo(float).eps / CENTRAL
#: A period-p branch point whose state comes back to itself after p/2 periods within this
#: (scaled components) is an orbit of period p/2: the doubled branch has met the orbit it
#: doubles (_collapsed) [-]. Newton leaves such an orbit's P^(p/2) residual near rounding
#: (1e-15 measured), a doubled orbit next to its birth is 1e-2 away.
COLLAPSED = 1e-6
#: Re-solves of a branch point at a finer step for the accuracy target [-]: more than a
#: sweep point's REFINEMENTS, as next to a period doubling's birth the doubled orbit's
#: distance from the orbit it doubles moves with the doubling's location, which wanders
#: with the step about its fourth-order trend, and the estimate with it (a point 2e-4 Hz
#: from the strong-coupling doubling at 145.32 Hz: 4.7e-5 at 1088 steps a period, then
#: 1.6e-7, 6.8e-7, 1.1e-7 and 4.7e-9 at 5584, 6928, 13856 and 15744 steps). The other
#: points stop where they meet the target, so this costs only where it is needed.
POINT_REFINEMENTS = 6
#: Steps of the five-point differences of the monodromy a period doubling's and a
#: Neimark-Sacker point's tests read where they are located (and such a point reports),
#: relative to each component's scale, tried in turn [-]: the RK4 map jumps by about its
#: own error where a switch crosses a step's end, and between the jumps its slope is off by
#: their size over their spacing, so that over period_map.CENTRAL's step the multipliers,
#: and the location, wander with the step; over these steps the jumps average out.
MULTIPLIER_STEPS = (5e-3, 1.25e-3)
#: ... a step is taken where the central differences over it and over twice it agree to
#: this (the scaled monodromy's largest entry) [-]; where neither does (an orbit of several
#: periods, or one that barely touches, bends at a smaller scale) the location reads the
#: Jacobian's monodromy, as the detection.
MULTIPLIER_AGREEMENT = 1e-3
#: Packed rows kept for parameter values already visited [-].
ROW_CACHE = 4096
#: Corrections the location of one bifurcation may take [-].
MAX_LOCATE = 60
#: Samples of the range on which the step per period is chosen [-].
STEP_SAMPLES = 9
#: ... and on which the closed-form amplitude without the stop is looked at [-].
SCALE_SAMPLES = 201
PERIOD_DOUBLING = ("mark", "switch")
#: The bifurcation (outputs.BIFURCATIONS) each test function of _Problem.tests flags.
TESTED = ("fold", "period_doubling", "neimark_sacker", "grazing", "grazing")
#: Defaults of the options, the one place they are written: continue_branch's keywords and
#: a continuation file's omitted keys (branch_file) read them. step, min_step and max_step
#: are in units of the parameter's range |stop - start| [-], max_points a count [-].
DEFAULTS = {"preset": DEFAULT_PRESET, "parameter": "frequency", "step": 0.01, "min_step": 1e-7,
            "max_step": 0.05, "max_points": 2000, "period_doubling": "mark"}


@dataclass(frozen=True)
class ContinuationSpec:
    """A checked continuation problem (:func:`check_continuation`), which
    :func:`continue_branch` takes as it is.

    Attributes
    ----------
    preset : str or None
        Preset the fixed parameters start from (``None``: the paper's).
    fixed : dict
        Fixed parameters by name (SI units), as given, without ``steps_per_period``.
    parameter : str
        The continued parameter.
    start, stop : float
        The range, in the parameter's SI unit.
    steps : int
        Steps per forcing period the branch is followed at (a point may be refined to
        more: ``accuracy``).
    step, min_step, max_step : float
        Initial, smallest and largest arclength step [-], relative to |stop - start|.
    max_points : int
        Budget of points on all branches [-].
    switch : bool
        True when the doubled branch is followed from each period doubling.
    base : dict
        The validated parameters at ``start`` and ``steps`` (SI units): the branch's first
        point, resolved once.
    accuracy : float
        The error target [-] every point and every bifurcation's location is refined to
        (the parameters' ``accuracy``); NaN where ``steps_per_period`` was given: the step
        is then kept as given, its estimates reported.
    max_steps : float
        The most steps per period a refinement may take [-] (``max_steps_per_period``).
    """

    preset: str | None
    fixed: dict
    parameter: str
    start: float
    stop: float
    steps: int
    step: float
    min_step: float
    max_step: float
    max_points: int
    switch: bool
    base: dict
    accuracy: float = math.nan
    max_steps: float = math.inf


class NoOrbitError(RuntimeError):
    """The motion from rest at the start value reached no periodic orbit to start from."""


@dataclass
class _Point:
    """One point of a branch (z scaled, the rest in SI units)."""

    z: np.ndarray  # (y / scale, lam / range)
    state: np.ndarray  # (4,) the orbit's state at forcing phase 0 (layouts.STATE)
    metrics: np.ndarray  # engine metric row of the orbit
    monodromy: np.ndarray  # (3, 3) dP^p/dy
    jacobian: np.ndarray  # (3, 4) scaled [M - I, dP/dlam]
    tangent: np.ndarray  # (4,) unit, scaled
    period: int
    branch: int
    lam: float = math.nan  # the parameter [its unit]
    bifurcation: int = 0
    arclength: float = 0.0  # from the branch's first point
    precision: float = 0.0  # half-width of the bracket in the parameter (located points)
    error: float = math.nan
    tested: np.ndarray = None  # the test functions, once computed (see _Problem.tests)
    shift: float = math.nan  # parameter change at twice the steps [parameter's unit]
    steps: int = 0  # steps per period of the orbit (the branch's, or refined: _refine)
    located: bool = False  # a bifurcation located to LOCATE (not the end of its step)
    # |change| of each multiplier (sorted_multipliers' order) at twice the steps, located
    # bifurcations only
    multiplier_shift: np.ndarray = None
    # the monodromy by differences over each of MULTIPLIER_STEPS once computed, and the
    # agreement of its two central differences (_Problem.multipliers)
    precise: dict = None
    # a doubled branch's head: the doubling direction (scaled, unit) it left the orbit it
    # doubles along, and the parameter of that doubling
    doubling: np.ndarray = None
    born: float = math.nan


@dataclass
class Branch:
    """What :func:`continue_branch` found, before it becomes a Dataset."""

    points: list = field(default_factory=list)
    stops: list = field(default_factory=list)  # why each branch ended
    run_time: float = 0.0


class _Problem:
    """The period map at any parameter value, scaled, and Newton on it."""

    def __init__(self, base: dict, preset, fixed: dict, parameter: str, lo: float, hi: float,
                 steps: int, scale: np.ndarray):
        self.preset, self.fixed, self.parameter = preset, fixed, parameter
        self.lo, self.hi = lo, hi
        self.range = hi - lo
        self.steps = steps
        self.scale = scale
        self.D = len(scale)  # components of the period map (period_map.state_size)
        self.tolerance = base["settle_tolerance"]
        self._rows = {}

    def row(self, lam: float, steps: int, coarse=None) -> np.ndarray:
        """The packed row at parameter value ``lam`` and ``steps`` steps per period; with
        ``coarse``, for the run that estimates the error of one at ``coarse`` steps
        (period_map.estimating_row)."""
        if coarse is not None:
            row = self.row(lam, coarse).copy()
            period_map.estimating_row(row, float(coarse), float(steps))
            return row
        key = (float(lam), steps)
        if len(self._rows) > ROW_CACHE:  # (a long branch visits ever new values)
            self._rows.clear()
        if key not in self._rows:
            with warnings.catch_warnings():  # (the step was checked on the range once)
                warnings.simplefilter("ignore")
                p = resolve_parameters(self.preset, **{**self.fixed, self.parameter: key[0],
                                                       "steps_per_period": steps})
            self._rows[key] = pack_parameters(p)
        return self._rows[key]

    def lam(self, z) -> float:
        return self.lo + z[self.D] * self.range

    def at(self, steps: int) -> _Problem:
        """The same problem at ``steps`` steps per period (the packed rows shared)."""
        other = copy.copy(self)
        other.steps = int(steps)
        return other

    def evaluate(self, z, period: int, carry: np.ndarray, steps: int, jacobian=True,
                 coarse=None):
        """P^p at z and, with ``jacobian``, the scaled [M - I, dP/dlam]: the end state (4,),
        the metric row, the monodromy (3, 3) and the scaled Jacobian (3, 4); None where the
        run diverged or the value is outside the parameter's range. ``coarse``: the map
        estimates the error of one at ``coarse`` steps per period (:meth:`row`)."""
        lam = self.lam(z)
        dlam = PERTURBATION * self.range
        try:
            row = self.row(lam, steps, coarse)
            shifted = self.row(lam + dlam, steps, coarse) if jacobian else None
        except ParameterError:
            return None
        state = carry.copy()
        state[:self.D] = z[:self.D] * self.scale
        batch = period_map.Batch(self.D, 0)
        if not jacobian:
            batch.add(row, state[None, :], period)
            (at,) = batch.run()
            return (at.ends[0], at.metrics[0], None, None) if at.ok[0] else None
        if period_map.carries_tangents(row):
            batch.add(row, state[None, :], period, copies="carried")
        else:
            batch.add(row, state[None, :], period, copies="spread", scale=self.scale[None, :])
        # (the perturbed runs' end states alone are read)
        batch.add(shifted, state[None, :], period, book=False)
        at, beside = batch.run()
        if not (at.ok[0] and beside.ok[0]):
            return None
        m = at.jacobian[0]
        scaled = np.empty((self.D, self.D + 1))
        scaled[:, :self.D] = m * self.scale[None, :] / self.scale[:, None] - np.eye(self.D)
        scaled[:, self.D] = ((beside.ends[0, :self.D] - at.ends[0, :self.D]) / dlam
                             * self.range / self.scale)
        return at.ends[0], at.metrics[0], m, scaled

    def phases(self, z, period: int, carry: np.ndarray) -> np.ndarray:
        """The states y(T) .. y(pT) (p, D) of the run from z, at the branch's step."""
        state = carry.copy()
        state[:self.D] = z[:self.D] * self.scale
        batch = period_map.Batch(self.D, period)
        batch.add(self.row(self.lam(z), self.steps), state[None, :], period)
        return batch.run()[0].strobes[0]

    def correct(self, predicted, tangent, period: int, carry, steps=None, fixed=None,
                coarse=None):
        """Newton on [F(z); tangent . (z - predicted)] = 0 from ``predicted``; a _Point
        (its tangent not yet set), or None when it does not converge. ``fixed``: a scaled
        Jacobian to reuse for every iterate (quasi-Newton, one lane a run); ``coarse``: as
        :meth:`evaluate`'s."""
        steps = self.steps if steps is None else steps
        z = predicted.copy()
        last = math.inf
        for _ in range(MAX_CORRECTOR):
            out = self.evaluate(z, period, carry, steps, jacobian=fixed is None,
                                coarse=coarse)
            if out is None:
                return None
            end, metrics, monodromy, scaled = out
            if fixed is not None:
                scaled = fixed
            a = np.vstack([scaled, tangent])
            residual = np.concatenate([(end[:self.D] - z[:self.D] * self.scale) / self.scale,
                                       [tangent @ (z - predicted)]])
            try:
                step = -np.linalg.solve(a, residual)
                cond = np.linalg.cond(a, p=np.inf)
            except np.linalg.LinAlgError:
                return None
            size = float(np.max(np.abs(step)))
            z = z + step
            if not np.isfinite(size) or size > 0.5 * last and last < math.inf:
                return None
            if size <= max(self.tolerance, ROUNDING * cond):
                state = end.copy()
                state[:self.D] = z[:self.D] * self.scale  # (the fixed point; V_imp carried)
                return _Point(z, state, metrics, monodromy, scaled, None, period, 0,
                              self.lam(z), steps=steps)
            last = size
            carry = end
        return None

    def tangent(self, scaled, previous) -> np.ndarray:
        """The unit null vector of the scaled [M - I, dP/dlam], oriented along
        ``previous``."""
        t = np.linalg.solve(np.vstack([scaled, previous]), np.eye(self.D + 1)[self.D])
        return t / np.linalg.norm(t)

    # -- test functions ----------------------------------------------------------------

    def tests(self, point: _Point) -> np.ndarray:
        """The test function of each bifurcation (outputs.BIFURCATIONS but none) at
        ``point`` (kept on it: each point is compared with both its neighbours)."""
        if point.tested is not None:
            return point.tested
        # the point's own stops (the continued parameter may be a gap)
        r = self.row(self.lam(point.z), self.steps)
        m = point.metrics
        upper = m[METRIC.x_max] - r[PARAM.gap] \
            if r[PARAM.stop_ratio] == 0 and r[PARAM.gap] < NO_STOP else math.nan
        lower = -r[PARAM.lower_gap] - m[METRIC.x_min] if r[PARAM.lower_gap] < NO_STOP \
            else math.nan
        point.tested = np.array([point.tangent[self.D], *_multiplier_tests(point.monodromy),
                                 upper / self.scale[0], lower / self.scale[0]])
        return point.tested

    def multipliers(self, point: _Point, h: float):
        """The monodromy of ``point``'s orbit by five-point central differences (moves of
        +-h and +-2h of each component's scale), at its own steps, and the largest entry
        of the scaled difference of the central differences over h and 2h: one engine call
        of 4 D lanes, kept on the point; None where a copy's run diverged."""
        if point.precise is None:
            point.precise = {}
        if h not in point.precise:
            D = self.D
            move = h * self.scale
            moved = np.repeat(point.state[None, :], 4 * D, axis=0)
            for j, factor in enumerate((1.0, -1.0, 2.0, -2.0)):
                moved[j * D + np.arange(D), np.arange(D)] += factor * move
            batch = period_map.Batch(D, 0)
            rows = np.repeat(self.row(self.lam(point.z), point.steps)[None, :], len(moved),
                             axis=0)
            batch.add(rows, moved, point.period, book=False)
            (run,) = batch.run()
            point.precise[h] = None
            if run.ok.all():
                e = run.ends[:, :D].reshape(4, D, D)  # (move, component moved, end state)
                near = ((e[0] - e[1]) / (2 * move[:, None])).T
                far = ((e[2] - e[3]) / (4 * move[:, None])).T
                apart = np.max(np.abs(near - far) * self.scale[None, :] / self.scale[:, None])
                point.precise[h] = ((4 * near - far) / 3, apart)  # (fourth order in h)
        return point.precise[h]

    def multiplier_step(self, *points):
        """The first of MULTIPLIER_STEPS whose monodromy (:meth:`multipliers`) is smooth
        to MULTIPLIER_AGREEMENT at every one of ``points``; None where none is."""
        for h in MULTIPLIER_STEPS:
            found = [self.multipliers(pt, h) for pt in points]
            if all(f is not None and f[1] <= MULTIPLIER_AGREEMENT for f in found):
                return h
        return None

    def locating(self, k: int, h):
        """Test function ``k`` (TESTED) as a bifurcation is located by it: a period
        doubling's and a Neimark-Sacker point's read the monodromy of
        :meth:`multipliers` over ``h`` (NaN where it diverged), the others and those
        where ``h`` is None are :meth:`tests`'."""
        if TESTED[k] not in MULTIPLIER_TESTED or h is None:
            return lambda pt: self.tests(pt)[k]

        def test(pt):
            m = self.multipliers(pt, h)
            return math.nan if m is None else \
                _multiplier_tests(m[0])[MULTIPLIER_TESTED.index(TESTED[k])]

        return test


#: The bifurcations whose test functions read the multipliers (_Problem.locating).
MULTIPLIER_TESTED = ("period_doubling", "neimark_sacker")


def _multiplier_tests(monodromy) -> tuple:
    """A period doubling's test function det(I + M) and a Neimark-Sacker point's
    |mu|^2 - 1 of the outermost complex pair (NaN without one) of ``monodromy``."""
    mult = np.linalg.eigvals(monodromy)
    pair = np.abs(mult.imag) > 1e-9 * np.abs(mult)
    # (the outermost pair: a moving stop adds a second one, and the first in eigvals'
    # order could be either, so that the sign changed where the order did)
    ns = np.abs(mult[pair]).max() ** 2 - 1 if pair.any() else math.nan
    return np.linalg.det(np.eye(len(monodromy)) + monodromy), ns


def _read_multipliers(point: _Point, k: int, h) -> None:
    """A bifurcation located by test ``k`` on the monodromy over ``h`` reports the
    multipliers its test read."""
    if TESTED[k] in MULTIPLIER_TESTED and h is not None and point.precise.get(h):
        point.monodromy = point.precise[h][0]


def continue_branch(preset: str | None | ContinuationSpec = DEFAULTS["preset"],
                    parameter: str = DEFAULTS["parameter"],
                    start: float | None = None, stop: float | None = None, *,
                    step: float = DEFAULTS["step"], min_step: float = DEFAULTS["min_step"],
                    max_step: float = DEFAULTS["max_step"],
                    max_points: int = DEFAULTS["max_points"],
                    period_doubling: str = DEFAULTS["period_doubling"], **parameters):
    """Follow the branch of periodic orbits reached from rest at ``start`` as
    ``parameter`` runs to ``stop``, through folds, with its stability and bifurcations.

    Parameters
    ----------
    preset : str, None or ContinuationSpec
        A preset name; ``None`` is the paper's. Or a problem already checked
        (:func:`check_continuation`, ``branch_file.load_continuation``), taken as it is:
        then no other argument is given.
    parameter : str
        The continued parameter: any numeric model parameter (see ``PARAMETERS``).
    start, stop : float
        The range, in the parameter's SI unit; the branch starts at ``start`` and ends
        where it leaves the range (either end) or after ``max_points``.
    step, min_step, max_step : float
        Initial, smallest and largest arclength step [-], relative to the range in the
        parameter (the state's components scaled alike by the start orbit's amplitudes).
    max_points : int
        Budget of points on all branches (located bifurcations included).
    period_doubling : str
        ``"mark"`` (locate period doublings) or ``"switch"`` (also continue the doubled
        branch from each).
    **parameters
        Fixed values by name in SI units, as :func:`harvester_sweep.run_scene`. Without
        ``steps_per_period``, the branch is followed at the step the accuracy target asks
        for at the most demanding of STEP_SAMPLES values across the range, and each point
        and bifurcation whose estimate is above ``accuracy`` is solved again at a finer
        step (its ``steps_per_period``); with it, every point stays at that step.

    Returns
    -------
    xarray.Dataset
        Along ``point``: the parameter (a variable named after it), the orbits' metrics,
        Floquet multipliers, ``stable`` and ``bifurcation`` (CF flags), ``branch`` and
        ``error_estimate``; see :func:`harvester_sweep.datasets.branch_dataset`.

    Raises
    ------
    ParameterError
        For bad input, before any work.
    NoOrbitError
        When the motion from rest at ``start`` settles on no periodic orbit.
    """
    from .datasets import branch_dataset

    options = dict(parameter=parameter, step=step, min_step=min_step, max_step=max_step,
                   max_points=max_points, period_doubling=period_doubling)
    if not isinstance(preset, ContinuationSpec):
        spec = check_continuation(preset, start=start, stop=stop, fixed=parameters, **options)
    elif parameters or start is not None or stop is not None or any(
            value != DEFAULTS[name] for name, value in options.items()):
        # (a checked problem holds every option: another beside it would be ignored)
        raise ParameterError("a ContinuationSpec is the whole problem: give no other "
                             "argument beside it")
    else:
        spec = preset
    branch = _continue(spec)
    return branch_dataset(branch, spec)


def check_continuation(preset, parameter, start, stop, step, min_step, max_step, max_points,
                       period_doubling, fixed: dict, prefix: str = "") -> ContinuationSpec:
    """The checked continuation problem, every value validated once here (bad input raises
    ParameterError naming it, after ``prefix``, with its unit and allowed range): the
    options in the units of :func:`continue_branch`, ``fixed`` the fixed parameters by
    name (SI units)."""
    if not isinstance(parameter, str) or parameter not in PARAMETERS \
            or PARAMETERS[parameter].kind != "float":
        floats = [n for n, p in PARAMETERS.items() if p.kind == "float"]
        raise ParameterError(f"{prefix}parameter = {parameter!r}: must be a numeric model "
                             "parameter, one of " + ", ".join(floats))
    check_names(fixed)
    if parameter in fixed:
        raise ParameterError(f"{parameter}: continued, so it cannot also be fixed; give "
                             f"{prefix}start and {prefix}stop instead")
    spec = PARAMETERS[parameter]
    ends = {}
    for name, value in (("start", start), ("stop", stop)):
        if value is None:
            raise ParameterError(f"{prefix}{name} [{spec.unit}]: missing; the continuation runs "
                                 f"{parameter} from start to stop")
        try:
            ends[name] = spec.check(value)
        except ParameterError as error:
            raise ParameterError(f"{prefix}{name}: {error}") from None
    if ends["start"] == ends["stop"]:
        raise ParameterError(f"{prefix}stop [{spec.unit}] = {ends['stop']!r}: must differ "
                             "from start")
    for name, value, high in (("step", step, 1.0), ("min_step", min_step, 1.0),
                              ("max_step", max_step, 1.0)):
        if not is_number(value) or not 0 < value <= high:  # (numpy's numbers too)
            raise ParameterError(f"{prefix}{name} [-] = {value!r}: must be a number in "
                                 f"(0, {high:g}] (relative to |stop - start|)")
    if min_step > max_step:
        raise ParameterError(f"{prefix}min_step [-] = {min_step!r}: must not exceed max_step = "
                             f"{max_step!r}")
    if not min_step <= step <= max_step:
        raise ParameterError(f"{prefix}step [-] = {step!r}: must lie in [min_step, max_step] = "
                             f"[{min_step!r}, {max_step!r}]")
    max_points = whole_number(f"{prefix}max_points", max_points, 2, 10**6)
    if period_doubling not in PERIOD_DOUBLING:
        raise ParameterError(f"{prefix}period_doubling = {period_doubling!r}: must be one of "
                             + ", ".join(f'"{m}"' for m in PERIOD_DOUBLING))
    base = resolve_parameters(preset, **fixed, **{parameter: ends["start"]})
    check_runnable(base)
    samples = np.linspace(ends["start"], ends["stop"], STEP_SAMPLES)
    steps = fixed.get("steps_per_period")
    # (an explicit step is kept as given, as a sweep's: no refinement, its estimates told)
    accuracy = base["accuracy"] if steps is None else math.nan
    if steps is None:
        steps = max(auto_steps_per_period(resolve_parameters(preset, **fixed,
                                                             **{parameter: float(v)}))
                    for v in samples)
    at_steps = []
    for v in samples:  # (a value too stiff at that step is refused here, not mid-branch)
        at_steps.append(resolve_parameters(preset, **{**fixed, parameter: float(v),
                                                      "steps_per_period": steps}))
        check_runnable(at_steps[-1])
    return ContinuationSpec(
        preset=preset, fixed={k: v for k, v in fixed.items() if k != "steps_per_period"},
        parameter=parameter, start=ends["start"], stop=ends["stop"], steps=int(steps),
        step=float(step), min_step=float(min_step), max_step=float(max_step),
        max_points=max_points, switch=period_doubling == "switch",
        base=at_steps[0],  # (samples[0] is start itself)
        accuracy=float(accuracy), max_steps=float(base["max_steps_per_period"]))


def _continue(spec: ContinuationSpec) -> Branch:
    """The branch from rest at ``spec.start`` (and, with ``spec.switch``, the doubled
    branches)."""
    began = time.perf_counter()
    preset, fixed, parameter, start, stop, steps = (spec.preset, spec.fixed, spec.parameter,
                                                    spec.start, spec.stop, spec.steps)
    step, min_step, max_step, max_points = (spec.step, spec.min_step, spec.max_step,
                                            spec.max_points)
    p0 = spec.base
    period_map.compile_engine()
    results = solve(pack_points([p0]))
    status = int(results.metrics[0, METRIC.status])
    if status != STATUS.settled:
        from .outputs import STATUS_NAMES

        raise NoOrbitError(f"the motion from rest at {parameter} = {start:g} "
                           f"[{PARAMETERS[parameter].unit}] reached no periodic orbit "
                           f"({STATUS_NAMES[status]} after "
                           f"{int(results.metrics[0, METRIC.periods_run])} periods): start "
                           "where the response settles")
    m = results.metrics[0]
    # the nearer stop's distance: the amplitude's order once the motion strikes it
    reach = min(abs(p0["gap"]), math.inf if p0["lower_gap"] is None else p0["lower_gap"])
    x = max(abs(m[METRIC.x_max]), abs(m[METRIC.x_min]), reach)
    # without a stop within reach the amplitude is the closed form's: scaled by its peak
    # over the range, a resonance is not taken in hundreds of steps of the amplitude
    free = [abs(linear_response(**resolve_parameters(preset, **{**fixed, parameter: float(v)}))[0])
            for v in np.linspace(start, stop, SCALE_SAMPLES)]
    if p0["hertz_stiffness"] == 0 or max(free) < reach:
        x = max(x, max(free))
    row = pack_parameters(p0)
    scale = orbit_scales(row, x, m[METRIC.v_peak], state_size(row[None]))
    # the voltage of that amplitude at the most of the range: a voltage that grows with the
    # parameter (a resistance continued from 100 Ohm, where w R C_p << 1) measured by the
    # start's would make Newton's tolerance and the copies' moves in V ever finer relative
    # to the orbit (the strong-coupling branch in resistance at 140 Hz stalled at 4.86 kOhm,
    # its V 50 times its start scale, its corrections failing on the copies' noise)
    samples = np.linspace(start, stop, STEP_SAMPLES)
    rows = np.array([pack_parameters(resolve_parameters(
        preset, **{**fixed, parameter: float(v), "steps_per_period": steps}))
        for v in samples])
    widest = orbit_scales(rows, np.full(len(rows), x), m[METRIC.v_peak],
                          len(scale)).max(axis=0)
    voltage = [k for k, c in enumerate(period_map.COMPONENTS[:len(scale)])
               if c.scale == "voltage"]
    scale[voltage] = widest[voltage]
    lo, hi = min(start, stop), max(start, stop)
    problem = _Problem(p0, preset, fixed, parameter, lo, hi, steps, scale)
    period = int(m[METRIC.orbit_period])
    z0 = np.concatenate([results.finals[0, :problem.D] / scale, [(start - lo) / (hi - lo)]])
    along = np.eye(problem.D + 1)[problem.D]  # first: the orbit at the start value itself
    first = problem.correct(z0, along, period, results.finals[0])
    if first is None:
        raise NoOrbitError(f"Newton did not converge on the orbit reached from rest at "
                           f"{parameter} = {start:g} [{PARAMETERS[parameter].unit}]")
    first.tangent = problem.tangent(first.jacobian, along * np.sign(stop - start))
    out = Branch()
    queue = [(first, None)]  # (a head, the branch whose doubling it was born at)
    met = set()  # (branch, doubling's parameter) where a doubled branch ended
    while queue and len(out.points) < max_points:
        head, parent = queue.pop(0)
        if (parent, head.born) in met:  # (that doubled branch is followed already)
            continue
        head.branch = number = len(out.stops)
        found, end, why = _follow(problem, head, step, min_step, max_step,
                                  max_points - len(out.points))
        out.points += found
        out.stops.append(why)
        if end is not None:  # (at the doubling of its parent nearest its end)
            doublings = [problem.lam(pt.z) for pt in out.points if pt.branch == parent
                         and pt.bifurcation == list(BIFURCATIONS).index("period_doubling")]
            if doublings:
                met.add((parent, min(doublings, key=lambda lam: abs(lam - end))))
        if spec.switch:
            for point in found:
                if (point.bifurcation == list(BIFURCATIONS).index("period_doubling")
                        and 2 * point.period <= MAX_ORBIT_PERIOD):
                    doubled = _doubled(problem, point, step)
                    # (a head that Newton took back to the orbit it doubles starts nothing)
                    if doubled is not None and not _collapsed(problem, doubled):
                        queue.append((doubled, number))
    out.points = [_accurate(problem, point, spec.accuracy, spec.max_steps)
                  for point in out.points]
    out.run_time = time.perf_counter() - began
    return out


def _follow(problem: _Problem, head: _Point, step, min_step, max_step, budget):
    """The points of one branch from ``head`` (included) to where it leaves the range,
    stalls or spends ``budget``; for a doubled branch that ended where it met the orbit it
    doubles, the parameter of its last point (else None); and why it ended. That meeting
    is where its orbit's offset after half its periods, along the doubling direction,
    changes sign (the branch passes through the orbit it doubles onto the same orbits
    shifted by half their periods), or where its orbit is the one it doubles
    (:func:`_collapsed`)."""
    points = [head]
    a, ds = head, step
    phases = problem.phases(head.z, head.period, head.state)  # the head's orbit, p phases
    phases = np.concatenate([phases / problem.scale,
                             np.full((head.period, 1), head.z[problem.D])], axis=1)
    unresolved = None  # the parameter where the last step found the map the identity
    side = None if head.doubling is None else np.sign(_half_offset(problem, head,
                                                                    head.doubling))
    while len(points) < budget:
        predicted = a.z + ds * a.tangent
        b = problem.correct(predicted, a.tangent, a.period, a.state)
        if b is not None and np.max(np.abs(b.jacobian[:, :problem.D])) < UNRESOLVED:
            unresolved, b = problem.lam(b.z), None  # (any state is its "orbit" there)
        elif b is not None:
            unresolved = None
        if b is not None:
            b.tangent = problem.tangent(b.jacobian, a.tangent)
            b.branch = a.branch
            turn = math.acos(min(1.0, float(a.tangent @ b.tangent)))
        if b is not None and turn <= MAX_TURN and (_collapsed(problem, b) or (
                side is not None and _half_offset(problem, b, head.doubling) * side < 0)):
            return points, problem.lam(a.z), (
                f"back on a period-{b.period // 2} orbit at {problem.parameter} = "
                f"{problem.lam(b.z):.9g} (the period-doubled orbit met the orbit it doubles, "
                "at a period doubling of that one)")
        if b is None or turn > MAX_TURN:
            ds *= 0.5
            if ds < min_step and unresolved is not None:
                return points, None, (
                    f"stopped at {problem.parameter} = {problem.lam(a.z):.9g}: at "
                    f"{unresolved:.3g} and beyond the period map is the identity to "
                    "rounding, and no orbit can be resolved; give a nearer stop")
            if ds < min_step:
                return points, None, (
                    f"stalled at {problem.parameter} = {problem.lam(a.z):.9g}: no correction "
                    f"within min_step = {min_step:g}")
            continue
        located, shorter = [], False
        tests_a, tests_b = problem.tests(a), problem.tests(b)
        for k, kind in enumerate(TESTED):
            if tests_a[k] * tests_b[k] < 0:
                h = problem.multiplier_step(a, b) if kind in MULTIPLIER_TESTED else None
                test = problem.locating(k, h)
                fa, fb = test(a), test(b)
                if not fa * fb < 0:  # (the multipliers read over h do not bracket it:
                    # located as detected)
                    h, test, fa, fb = None, problem.locating(k, None), tests_a[k], tests_b[k]
                found = _locate(problem, a, b, ds, test, fa, fb)
                if found is not None:
                    _read_multipliers(found[1], k, h)
                if found is None and kind == "grazing" and 0.5 * ds >= min_step:
                    # (flagged at the step's end, a grazing could be far from the stop: a
                    # shorter step brackets it nearer)
                    shorter = True
                    break
                if found is None:  # (a correction inside failed: flagged at the step's
                    # end, the whole step its bracket, rather than lost)
                    found = ds, replace(b, precision=problem.range * ds)
                s, point = found
                point.bifurcation = list(BIFURCATIONS).index(kind)
                point.arclength = a.arclength + s
                located.append((s, point))
        if shorter:
            ds *= 0.5
            continue
        lam = problem.lam(b.z)
        beyond = lam < problem.lo or lam > problem.hi
        if beyond:  # the branch's end: the point where it leaves the range
            bound = problem.lo if lam < problem.lo else problem.hi
            end = _locate(problem, a, b, ds, lambda pt: problem.lam(pt.z) - bound,
                          problem.lam(a.z) - bound, lam - bound)
            located = [(s, pt) for s, pt in located if end is None or s < end[0]]
        located.sort(key=lambda item: item[0])
        again = [pt for _, pt in located if any(
            q.bifurcation == pt.bifurcation and np.max(np.abs(q.z - pt.z)) < REVISIT
            for q in points)]
        points += [pt for _, pt in located][:budget - len(points)]
        if again:  # (a loop whose phases the chord test missed: it came back to a point)
            kind = list(BIFURCATIONS)[again[0].bifurcation]
            return points, None, (f"closed on itself: back at the {kind} at "
                                  f"{problem.parameter} = {problem.lam(again[0].z):.9g}")
        if beyond:
            if end is not None and len(points) < budget:
                end[1].arclength = a.arclength + end[0]
                points.append(end[1])
            return points, None, f"left the range at {problem.parameter} = {bound:.9g}"
        b.arclength = a.arclength + ds
        points.append(b)
        if b.arclength > 4 * ds and any(_passes(phase, a.z, b.z) for phase in phases):
            return points, None, (f"closed on itself at {problem.parameter} = "
                                  f"{problem.lam(b.z):.9g} (an isola or a loop)")
        a = b
        easy = turn < 0.3 * MAX_TURN
        ds = min(ds * (1.6 if easy else 1.0), max_step) if turn < 0.7 * MAX_TURN else 0.7 * ds
        ds = max(ds, min_step)
    return points[:budget], None, "the budget of points was spent"


def _half_offset(problem: _Problem, point: _Point, v: np.ndarray) -> float:
    """The offset along ``v`` (scaled) of ``point``'s orbit (of an even number of periods)
    after half its periods from its start (scaled): the doubled orbit's signed distance
    from the orbit it doubles."""
    half = problem.phases(point.z, point.period // 2, point.state)[-1] / problem.scale
    return float(v @ (half - point.z[:problem.D]))


def _collapsed(problem: _Problem, point: _Point) -> bool:
    """Whether the period-p orbit of ``point`` (p even) is an orbit of period p / 2: a
    period-doubled branch that has come back to the orbit it doubles, at a period doubling
    of that orbit, and gone on along it (every fixed point of P^(p/2) is one of P^p too).
    Followed further, it would repeat that branch labelled with twice its period, and the
    points beside the meeting, where two branches cross and the doubled orbit's distance
    from the other grows like the square root of the parameter's, have error estimates that
    do not fall with the step at RK4's order (docs/numerics.md)."""
    if point.period % 2:
        return False
    half = problem.phases(point.z, point.period // 2, point.state)[-1] / problem.scale
    return bool(np.max(np.abs(half - point.z[:problem.D])) < COLLAPSED)


def _passes(head, a, b) -> bool:
    """Whether the chord from ``a`` to ``b`` passes by ``head`` (within a tenth of its
    length): the branch has come back to its first orbit (at any of its phases)."""
    chord = b - a
    t = np.clip((head - a) @ chord / (chord @ chord), 0.0, 1.0)
    return bool(np.linalg.norm(a + t * chord - head) <= 0.1 * np.linalg.norm(chord))


def _locate(problem: _Problem, a: _Point, b: _Point, ds: float, test, fa: float, fb: float):
    """The point between ``a`` and ``b`` (``b`` at arclength ``ds`` from ``a``) where
    ``test`` changes sign, by the Illinois method on the arclength, every trial point
    corrected onto the branch: ``(s, point)``, or None when a correction fails."""
    lo, hi = (0.0, fa, a), (ds, fb, b)
    side = 0
    best = None
    for _ in range(MAX_LOCATE):
        width = problem.range * (hi[0] - lo[0])
        if width <= LOCATE * max(abs(problem.lam(lo[2].z)), problem.range):
            break
        s = (lo[0] * hi[1] - hi[0] * lo[1]) / (hi[1] - lo[1])
        if not lo[0] < s < hi[0]:
            s = 0.5 * (lo[0] + hi[0])
        point = problem.correct(a.z + s * a.tangent, a.tangent, a.period, a.state)
        if point is None:
            return None
        point.tangent = problem.tangent(point.jacobian, a.tangent)
        point.branch = a.branch
        f = test(point)
        if not np.isfinite(f):
            return None
        best = (s, point)
        if f == 0:
            break
        if np.sign(f) == np.sign(lo[1]):
            lo = (s, f, point)
            if side == -1:
                hi = (hi[0], 0.5 * hi[1], hi[2])
            side = -1
        else:
            hi = (s, f, point)
            if side == 1:
                lo = (lo[0], 0.5 * lo[1], lo[2])
            side = 1
    if best is None:
        return None
    best[1].precision = problem.range * (hi[0] - lo[0])
    best[1].located = True
    return best


def _doubled(problem: _Problem, point: _Point, step: float):
    """The first point of the period-2p branch born at a period doubling: from the orbit
    moved along the eigenvector of the multiplier nearest -1."""
    mult, vectors = np.linalg.eig(point.monodromy)
    k = int(np.argmin(np.abs(mult + 1)))
    v = np.real(vectors[:, k]) / problem.scale
    direction = np.concatenate([v / np.linalg.norm(v), [0.0]])
    head = problem.correct(point.z + step * direction, direction, 2 * point.period,
                           point.state)
    if head is None:
        return None
    head.tangent = problem.tangent(head.jacobian, direction)
    head.doubling, head.born = direction[:problem.D], problem.lam(point.z)
    return head


def _estimate(problem: _Problem, point: _Point) -> None:
    """Correct ``point`` again at twice the steps (its Jacobian reused): at the same
    parameter value for the relative change of its metrics (what a designer at that value
    gets wrong), or, where that does not converge (near a fold the orbit at twice the steps
    may not exist there), normal to the branch; normal to the branch also for the change
    of the parameter (at a fold, the fold's shift)."""
    normal = problem.correct(point.z, point.tangent, point.period, point.state,
                             steps=2 * point.steps, fixed=point.jacobian, coarse=point.steps)
    if normal is not None:
        point.shift = problem.lam(normal.z) - problem.lam(point.z)
    fine = problem.correct(point.z, np.eye(problem.D + 1)[problem.D], point.period,
                           point.state, steps=2 * point.steps, fixed=point.jacobian,
                           coarse=point.steps)
    fine = normal if fine is None else fine
    if fine is not None:
        point.error = float(halving_error(point.metrics, fine.metrics))


def _next_steps(steps: int, error: float, target: float, coarser, refine: int) -> int:
    """Steps per period of the next refinement of an estimate ``error`` [-] at ``steps``
    towards ``target`` [-] (accuracy.refined_steps, as for a sweep point: the fourth
    order's ask, or twice the steps after a refinement that gained less than SLOW_ORDER;
    ``coarser`` the steps and estimate before, ``refine`` the refinements so far)."""
    before, before_error = np.asarray(coarser, dtype=float)
    want = refined_steps(float(steps), float(error), float(target), before, before_error,
                         int(refine))
    return int(max(want, steps + STEPS_QUANTUM))


def _accurate(problem: _Problem, point: _Point, accuracy: float, max_steps: float) -> _Point:
    """``point`` with its error estimate, refined where it is above ``accuracy`` [-]: a
    located bifurcation by :func:`_accurate_bifurcation`, any other by
    :func:`_accurate_point`."""
    if point.bifurcation and point.located:
        return _accurate_bifurcation(problem, point, accuracy, max_steps)
    point = _accurate_point(problem, point, accuracy, max_steps)
    if point.bifurcation:  # (not located: no location whose change could be told)
        point.shift = math.nan
    return point


def _accurate_point(problem: _Problem, point: _Point, accuracy: float,
                    max_steps: float) -> _Point:
    """``point`` with its error estimate (:func:`_estimate`), solved again while the
    estimate is above ``accuracy`` at the step the fourth order asks for, as a sweep point
    (up to POINT_REFINEMENTS times, within ``max_steps`` steps per period): the branch is
    followed at one step, and a point whose estimate asks for a finer one is re-solved at
    it alone (:func:`_resolve`). A refinement that fails keeps the point it had."""
    _estimate(problem, point)
    coarser, refine = (math.nan, math.nan), 0
    while math.isfinite(accuracy) and point.error > accuracy and refine < POINT_REFINEMENTS:
        steps = _next_steps(point.steps, point.error, accuracy, coarser, refine)
        if steps > max_steps:
            break
        finer = _resolve(problem, point, steps)
        if finer is None:
            break
        _estimate(problem, finer)
        if not math.isfinite(finer.error):
            break
        coarser, refine = (point.steps, point.error), refine + 1
        point = finer
    return point


def _resolve(problem: _Problem, point: _Point, steps: int):
    """``point`` solved again at ``steps`` steps per period: at its own parameter value,
    or, where that does not converge (near a fold the orbit may not exist there), normal
    to the branch; quasi-Newton with its Jacobian, then one run for the monodromy at the
    new step, carried or by copies (the multipliers and test functions of the map
    reported).
    None where neither converges."""
    for constraint in (np.eye(problem.D + 1)[problem.D], point.tangent):
        finer = problem.correct(point.z, constraint, point.period, point.state, steps=steps,
                                fixed=point.jacobian)
        if finer is None:
            continue
        out = problem.evaluate(finer.z, point.period, finer.state, steps)
        if out is None:
            continue
        _, finer.metrics, finer.monodromy, finer.jacobian = out
        finer.tangent = problem.tangent(finer.jacobian, point.tangent)
        finer.branch, finer.arclength = point.branch, point.arclength
        finer.bifurcation, finer.precision = point.bifurcation, point.precision
        return finer
    return None


#: A bifurcation located again at another step is bracketed along its tangent at
#: +-RELOCATE_WIDTH (scaled arclength) from where it was, the bracket widened by
#: RELOCATE_GROWTH up to RELOCATE_TRIES times until its test function changes sign [-].
RELOCATE_WIDTH = 1e-5
RELOCATE_GROWTH = 8.0
RELOCATE_TRIES = 5


def _accurate_bifurcation(problem: _Problem, point: _Point, accuracy: float,
                          max_steps: float) -> _Point:
    """The located bifurcation ``point`` located again at twice its steps per period and at
    3/2 of them (:func:`_changes`): the larger change of its parameter value is its
    ``shift``, its location's discretization error (fold, period doubling, Neimark-Sacker
    and grazing alike). While that shift is above ``accuracy`` relative to the value (to
    the range where the value is 0), the bifurcation is located again at the step the
    fourth order asks for, and at twice and 3/2 that (up to REFINEMENTS times, within
    ``max_steps``), and so while the point's own error estimate (:func:`_estimate`,
    normal to the branch where the orbit at its value does not converge) is above it. The
    point returned is the location at the finest step whose changes were found. Where
    none was, ``shift`` is NaN and the point is refined as any other
    (:func:`_accurate_point`)."""
    k = _which_test(problem, point)
    scale = abs(point.lam) or problem.range
    coarser, refine = (math.nan, math.nan), 0
    changes = _changes(problem, point, k)
    _estimate(problem, point)
    while changes is not None:
        # (the point is a point of the branch too: its own estimate counts)
        error = max(abs(changes[0]) / scale, point.error)
        if not (math.isfinite(accuracy) and error > accuracy and refine < REFINEMENTS):
            break
        steps = _next_steps(point.steps, error, accuracy, coarser, refine)
        if 2 * steps > max_steps:
            break
        finer = _relocate(problem, changes[2], k, steps)  # (from the nearer location)
        finer_changes = None if finer is None else _changes(problem, finer, k)
        if finer_changes is None:
            break
        coarser, refine = (point.steps, error), refine + 1
        point, changes = finer, finer_changes
        _estimate(problem, point)
    if changes is None:
        # (no location at another step, so no shift to tell: the point is still a point
        # of the branch, refined as any other so that its own estimate meets the target)
        point = _accurate_point(problem, point, accuracy, max_steps)
        point.shift = math.nan
        return point
    point.shift, point.multiplier_shift = changes[0], changes[1]
    return point


def _changes(problem: _Problem, point: _Point, k: int):
    """The change of the location ``point`` of test function ``k`` when located again at
    twice its steps and at 3/2 of them, the larger (signed) [parameter's unit], the larger
    change of each multiplier [-] and the location at twice the steps (or at 3/2 where
    that one failed); None where neither was found. One step ratio is not enough: the map
    jumps where a contact switch crosses a step's end, and a location's error wanders with
    the step about its fourth-order trend, so that one change can happen to be small
    (docs/numerics.md)."""
    found = []
    for steps in (2 * point.steps,
                  STEPS_QUANTUM * math.ceil(1.5 * point.steps / STEPS_QUANTUM)):
        other = _relocate(problem, point, k, steps)
        if other is not None:
            found.append(other)
    if not found:
        return None
    shift = max((other.lam - point.lam for other in found), key=abs)
    multipliers = np.max([multiplier_shift(point.monodromy, other.monodromy)
                          for other in found], axis=0)
    return shift, multipliers, found[0]


def _which_test(problem: _Problem, point: _Point) -> int:
    """The index in TESTED of the test function that located ``point``'s bifurcation (of
    the two grazings, the stop whose test is nearer 0 there)."""
    kind = list(BIFURCATIONS)[point.bifurcation]
    tests = problem.tests(point)
    candidates = [k for k, name in enumerate(TESTED) if name == kind]
    return min(candidates, key=lambda k: abs(tests[k]) if np.isfinite(tests[k]) else math.inf)


def _relocate(problem: _Problem, point: _Point, k: int, steps: int):
    """The bifurcation of test function ``k`` located at ``point`` (at its own step),
    located again at ``steps`` steps per period: bracketed along the point's tangent
    (RELOCATE_WIDTH, widened until test ``k`` changes sign) and located by
    :func:`_locate` on the map at ``steps``. None where no bracket or correction is
    found."""
    fine = problem.at(steps)
    t = point.tangent
    w = RELOCATE_WIDTH
    for _ in range(RELOCATE_TRIES):
        ends = []
        for side in (-1.0, 1.0):
            end = fine.correct(point.z + side * w * t, t, point.period, point.state)
            if end is None:
                break
            end.tangent = fine.tangent(end.jacobian, t)
            end.branch = point.branch
            ends.append(end)
        if len(ends) < 2:
            return None
        h = fine.multiplier_step(*ends) if TESTED[k] in MULTIPLIER_TESTED else None
        test = fine.locating(k, h)
        fa, fb = test(ends[0]), test(ends[1])
        if fa * fb < 0:
            # (from the bracket's start along the point's tangent, as between two points
            # of the branch)
            origin = replace(ends[0], z=point.z - w * t, tangent=t)
            found = _locate(fine, origin, ends[1], 2 * w, test, fa, fb)
            if found is None:
                return None
            located = found[1]
            _read_multipliers(located, k, h)
            located.bifurcation, located.branch = point.bifurcation, point.branch
            located.arclength = point.arclength
            return located
        w *= RELOCATE_GROWTH
    return None


__all__ = ["Branch", "ContinuationSpec", "NoOrbitError", "check_continuation",
           "continue_branch"]
