"""The period map: the engine's RK4 runs over whole forcing periods, and their Jacobian.

``P^p: y(0) -> y(pT)`` is the stroboscopic map of the engine's own fixed-step RK4 with
located contact switches. Every analysis runs the engine through this module, the only
one outside ``_engine`` that calls its entry points (the solver uses ``_engine``'s cache
and layout helpers too): continuation evaluates the map (:class:`Batch`: many requests,
each alone, carrying its monodromy or with its perturbed copies, in one engine call), the
compiled orbit solver through compiled entries (:func:`run_lanes`,
:func:`free_monodromy_into`, :func:`copies_monodromy`), scenes and basins record a point's
steps (:func:`record`).

The monodromy ``dP^p/dy`` comes from the run itself, which carries the derivative of its
steps along (:func:`run_lanes` with PARAM.tangents, or a :class:`Batch` request of
"carried" points, where :func:`carries_tangents`), or
from perturbed copies of a state run beside it (:data:`COPIES`): ordinary points of the
lane engine, the same RK4 with its switches located, so that the matrix includes the
contact switches without any algebra of its own. Clear of the stops the model is linear,
and the monodromy has a closed form (:func:`contact_free_monodromy`;
:func:`free_monodromy_into` from compiled code).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from . import _engine
from ._engine import METRIC, N_RIGID, N_STROBE, PARAM, STATE, STATUS
from .jit import SOLVER_JIT, njit
from .models import tip_mass

#: Forward-difference step of the monodromy, relative to each component's scale [-].
PERTURBATION = 1e-6
#: Central-difference step of the monodromy an orbit is judged on and reports, relative to
#: each component's scale: near grazing the map bends too sharply for forward differences
#: at PERTURBATION (docs/numerics.md, "Periodic orbits") [-].
CENTRAL = 1e-7
#: The perturbed copies of a monodromy, by kind: each component's moves, relative to its
#: scale, in the order the copies follow their state: forward differences, central ones,
#: and the spread copies whose median slope steps over a jump of the map (monodromy) [-].
COPIES = {"forward": (PERTURBATION,), "central": (CENTRAL, -CENTRAL),
          "spread": (CENTRAL, -CENTRAL, 2 * CENTRAL, -2 * CENTRAL)}
#: The moves of the forward and the central copies, for compiled code (which reads no dict).
FORWARD, BOTH_WAYS = COPIES["forward"], COPIES["central"]
#: Newton's floor from rounding: a correction below this many rounding units of the
#: period map, times the conditioning of I - M, is converged [-].
ROUNDING = 100 * np.finfo(float).eps
#: Components of the period map's state, as the model declares them: with a rigid stop
#: the first D (x [m], v [m/s], V [V]); a moving stop adds its own displacement [m] and
#: velocity [m/s] (N_STROBE in all).
COMPONENTS = tip_mass.STATE + tip_mass.STOP_STATE
D = N_RIGID


def state_size(rows) -> int:
    """Components of the period map of packed rows (n, len(PARAM)) solved together: D, or
    N_STROBE where one of them has a moving stop."""
    return N_STROBE if (np.asarray(rows)[:, PARAM.stop_ratio] > 0).any() else D


#: The kind of scale of each component (models.state.Component.scale), coded for compiled
#: code: 0 displacement, 1 velocity, 2 voltage.
_SCALE_KINDS = tuple(("displacement", "velocity", "voltage").index(c.scale)
                     for c in COMPONENTS)


@njit(**SOLVER_JIT)
def point_scales(row, x, v_peak, out):
    """Write into ``out`` (size,) the component scales of an orbit of packed row ``row``
    of displacement amplitude ``x`` [m] and peak voltage ``v_peak`` [V], by the kind of
    scale the model declares for each of its first ``size`` components
    (models.state.Component): x [m], w x [m/s], the larger of v_peak and the voltage of
    that amplitude [V] (a moving stop's motion is measured against the tip's)."""
    for c in range(out.shape[0]):
        kind = _SCALE_KINDS[c]
        if kind == 0:
            out[c] = x
        elif kind == 1:
            out[c] = row[PARAM.v_per_x] * x
        else:
            voltage = row[PARAM.voltage_per_x] * x
            out[c] = np.maximum(v_peak, voltage)


def orbit_scales(rows, x, v_peak, size=D):
    """:func:`point_scales` of packed rows (..., len(PARAM)) and amplitudes and peak
    voltages that broadcast against them: (..., size)."""
    rows = np.asarray(rows, dtype=float)
    x, v_peak = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(v_peak, dtype=float))
    shape = np.broadcast_shapes(rows.shape[:-1], x.shape)
    rows = np.broadcast_to(rows, shape + rows.shape[-1:]).reshape(-1, rows.shape[-1])
    x, v_peak = np.broadcast_to(x, shape).ravel(), np.broadcast_to(v_peak, shape).ravel()
    out = np.empty((len(rows), size))
    for k in range(len(rows)):
        point_scales(np.ascontiguousarray(rows[k]), x[k], v_peak[k], out[k])
    return out.reshape(shape + (size,))


def copies_width(kind, D):
    """Lanes of a state and its perturbed copies of ``kind`` (COPIES) in D components."""
    return 1 + D * len(COPIES[kind])


def perturbed_copies(states, scale, kind="forward"):
    """Each state (n, len(STATE)) followed by its copies of ``kind`` (COPIES), each moved
    along one of its first D components by a move times ``scale`` (n, D), the D
    components in turn for each move: (n * copies_width(kind, D), len(STATE))
    (D = scale.shape[1])."""
    n, width = len(states), copies_width(kind, scale.shape[1])
    out = np.repeat(states, width, axis=0).reshape(n, width, states.shape[1])
    for k in range(n):
        perturb(out[k], np.ascontiguousarray(scale[k]), COPIES[kind])
    return out.reshape(-1, states.shape[1])


@njit(**SOLVER_JIT)
def perturb(block, scale, moves):
    """Move the copies ``block[1:]`` of the state ``block[0]`` (width, len(STATE)), each
    along one of the first D components by a move of ``moves`` times ``scale`` (D,): the D
    components in turn for each move (as :func:`perturbed_copies`)."""
    size = scale.shape[0]
    for k in range(len(moves)):
        for c in range(size):
            block[1 + k * size + c, c] += moves[k] * scale[c]


def monodromy(ends, scale):
    """The monodromy matrices (n, D, D) from the end states (n, width, >= D) of the runs
    of :func:`perturbed_copies` with the same ``scale`` (n, D), the kind of copies told by
    their width: by forward differences, by central ones, or (spread) by the median of the
    four slopes between the five states along each component."""
    D = scale.shape[-1]
    e = ends[..., :D]
    if e.shape[1] == copies_width("spread", D):
        # The RK4 map with located switches jumps by about its own error where a switch
        # crosses a step's end: a slope across such a jump is far off, the other three
        # are near the derivative (the median, to the first order in the step)
        row = [e[:, 3 * D + 1:], e[:, D + 1:2 * D + 1], np.repeat(e[:, :1], D, axis=1),
               e[:, 1:D + 1], e[:, 2 * D + 1:3 * D + 1]]  # at -2h, -h, 0, h, 2h
        slopes = np.sort(np.diff(np.stack(row), axis=0), axis=0)
        diff, h = (slopes[1] + slopes[2]) / 2, CENTRAL * scale
        return diff.transpose(0, 2, 1) / h[:, None, :]
    out = np.empty((len(e), D, D))
    central = e.shape[1] == copies_width("central", D)
    for k in range(len(e)):
        copies_monodromy(np.ascontiguousarray(e[k]), np.ascontiguousarray(scale[k]), central,
                         out[k])
    return out


def sorted_multipliers(jacobians):
    """Floquet multipliers (n, D) of monodromy matrices (n, D, D), largest modulus first."""
    mult = np.linalg.eigvals(jacobians)
    order = np.argsort(-np.abs(mult), axis=-1, kind="stable")
    return np.take_along_axis(mult, order, axis=-1)


def multiplier_shift(coarse, fine) -> np.ndarray:
    """|mu_fine - mu| [-] of each multiplier of monodromy ``coarse`` (in
    sorted_multipliers' order), each paired with the nearest of monodromy ``fine``'s."""
    mu = sorted_multipliers(coarse[None])[0]
    other = np.linalg.eigvals(fine)
    return np.abs(mu[:, None] - other[None, :]).min(axis=1)


def sane(metrics):
    """:func:`sane_run` of each of the metric rows (..., len(METRIC))."""
    metrics = np.ascontiguousarray(metrics, dtype=float)
    out = np.empty(metrics.shape[:-1], dtype=bool)
    _sane_rows(metrics.reshape(-1, len(METRIC)), out.reshape(-1))
    return out


@njit(**SOLVER_JIT)
def _sane_rows(rows, out):
    for k in range(rows.shape[0]):
        out[k] = sane_run(rows[k])


@njit(**SOLVER_JIT)
def sane_run(m):
    """Whether a run (its metric row ``m``) neither diverged nor went beyond the divergence
    limit."""
    return m[METRIC.status] != STATUS.diverged and np.isfinite(m[METRIC.power])


@njit(**SOLVER_JIT)
def copies_monodromy(ends, scale, central, out):
    """Write into ``out`` (D, D) the monodromy from the end states ``ends`` (width, >= D)
    of a state and its copies of :func:`perturbed_copies` with ``scale`` (D,): forward
    differences, or ``central`` ones (as :func:`monodromy`)."""
    n = scale.shape[0]
    for c in range(n):
        if central:
            h = CENTRAL * scale[c]
            for r in range(n):
                out[r, c] = (ends[1 + c, r] - ends[1 + n + c, r]) / 2 / h
        else:
            h = PERTURBATION * scale[c]
            for r in range(n):
                out[r, c] = (ends[1 + c, r] - ends[0, r]) / h


@njit(**SOLVER_JIT)
def run_lanes(params, states, metrics, strobes, most, derivatives):
    """Run independent points (parameter rows ``params``, ``states`` updated in place,
    outputs ``metrics`` and ``strobes`` as the engine's) in one engine call from compiled
    code, on at most ``most`` threads, the engine's steady-state test on (it never ends a
    run of MAX_ORBIT_PERIOD periods or fewer). A point whose row has PARAM.tangents set,
    and that can carry them (:func:`carries_tangents`), gets its run's monodromy (D, D) in
    ``derivatives[i]``, from the variational equations of its steps."""
    # (a bool, not the literal True: numba compiles a function again for each literal
    # value it is called with, and the engine's queue is compiled for a bool already, by
    # the calls from Python)
    _engine.run_independent(params, states, metrics, strobes, np.bool_(True), most,
                            derivatives)


@njit(**SOLVER_JIT)
def estimating_row(row, coarse, steps):
    """Set packed row ``row`` to ``steps`` steps per period for the run that estimates the
    error of a run of it at ``coarse`` (fewer): with multi-steps (the engine's, clear of
    the stops) of no more steps than at ``coarse``.

    A run places the turns of x and V clear of the stops on the cubic interpolant over a
    multi-step, whose error goes as the fourth power of its length. At twice the steps
    the engine would take multi-steps of twice the steps, as long as before: that error
    would be alike in both runs, and their change, the error estimate, would not hold it.
    With the coarse run's multi-steps it falls with the step as RK4's does."""
    row[PARAM.steps] = coarse
    row[PARAM.multi] = _engine.multi_steps(row)
    row[PARAM.steps] = steps


@njit(**SOLVER_JIT)
def carries_tangents(row):
    """Whether a run of packed row ``row`` can carry its monodromy along (PARAM.tangents):
    switches located, rigid stops, a fixed approach velocity."""
    return _engine.carries_tangents(row)


@njit(**SOLVER_JIT)
def free_monodromy_into(rows, steps, periods, out):
    """:func:`contact_free_monodromy`, written into ``out`` (n, D, D), from compiled code."""
    _engine.free_monodromy(rows, steps, periods, out)


def contact_free_monodromy(rows, steps, periods):
    """The monodromy (n, D, D) of ``periods`` (n,) periods at ``steps`` (n,) steps per
    period of packed rows (n, len(PARAM)) where the motion stays clear of the stops: the
    engine's contact-free RK4 step matrix to the power of the steps (_engine.monodromy)."""
    out = np.empty((len(rows), D, D))
    _engine.free_monodromy(np.ascontiguousarray(rows), np.asarray(steps, dtype=float),
                           np.asarray(periods, dtype=np.int64), out)
    return out


def contact_free_extent(rows, states, steps):
    """The largest and smallest x [m] (n, 2) over one period of each row's motion from
    ``states`` (n, len(STATE)) were it clear of the stops, at ``steps`` steps per period."""
    out = np.empty((len(rows), 2))
    _engine.free_extent(np.ascontiguousarray(rows), np.ascontiguousarray(states), steps, out)
    return out


def record(row, state, periods):
    """The point of packed row ``row`` at every step over ``periods`` forcing periods from
    ``state`` (not modified): (periods * steps_per_period + 1, len(SERIES)), columns as
    _engine.SERIES."""
    return _engine.record_series(row, state, periods)


def compile_engine():
    """Compile the engine, or load it from numba's on-disk cache."""
    _engine.warm_up()


def engine_ready() -> bool:
    """Whether the engine is in numba's on-disk cache (else its first run compiles it)."""
    return _engine.cache_warm()


def engine_at_hand() -> bool:
    """Whether this process has the engine, or can load it from numba's on-disk cache."""
    return _engine.compiled_or_cached()


@dataclass
class Evaluation:
    """One request of a :class:`Batch`, run: n points, each alone or with its copies.

    Attributes
    ----------
    metrics : numpy.ndarray
        float64 (n, len(METRIC)): the metrics of each point's own run.
    ends : numpy.ndarray
        float64 (n, len(STATE)): its end state.
    strobes : numpy.ndarray
        float64 (n, samples, size): its last stroboscopic samples.
    ok : numpy.ndarray
        bool (n,): every lane of the point (copies included) ran sane, and ended finite
        in the map's components.
    jacobian : numpy.ndarray or None
        float64 (n, size, size): the monodromy from the copies, or carried along the run;
        None without either.
    work : numpy.ndarray
        float64 (n,): RK4 steps run for the point, copies included.
    """

    metrics: np.ndarray
    ends: np.ndarray
    strobes: np.ndarray
    ok: np.ndarray
    jacobian: np.ndarray | None
    work: np.ndarray


class Batch:
    """Requests of the period map gathered into one engine call.

    ``size`` is the map's number of components (D, or N_STROBE with a moving stop) and
    ``samples`` the stroboscopic samples read back per point. Each request (:meth:`add`)
    is a set of points run for a number of periods, alone or each with its perturbed
    copies; :meth:`run` runs them all at once and gives one :class:`Evaluation` per
    request, in order. A point's bits do not depend on its lane, so gathering requests
    changes no result.
    """

    def __init__(self, size: int, samples: int):
        self.size, self.samples = size, samples
        self._requests = []

    def add(self, rows, states, periods, steps=None, copies=None, scale=None,
            book=True) -> int:
        """Add a request and return its index in :meth:`run`'s list.

        rows : float64 (n, len(PARAM)) packed rows (not modified).
        states : float64 (n, len(STATE)) start states (not modified).
        periods : int or (n,) periods to run (PARAM.max_periods).
        steps : float or (n,) steps per period; None keeps the rows'.
        copies : a kind of COPIES, or None for the points alone; then ``scale`` (n, size)
            gives each component's scale, as in :func:`perturbed_copies`. Or "carried":
            each point alone, carrying its monodromy along its run (rows that
            :func:`carries_tangents`).
        book : False: the points' own runs book no extrema or force peaks either
            (_engine.BOOKED_METRICS are NaN), as the copies never do.
        """
        rows = np.array(rows, dtype=float, ndmin=2)
        states = np.asarray(states, dtype=float)
        if steps is not None:
            rows[:, PARAM.steps] = steps
        rows[:, PARAM.max_periods] = periods
        width = 1
        carried = copies == "carried"
        if carried:
            if not all(carries_tangents(row) for row in rows):
                raise ValueError("copies='carried': a row that cannot carry its monodromy")
            rows[:, PARAM.tangents] = 1.0
            states = states.copy()
        elif copies is not None:
            width = copies_width(copies, self.size)
            states = perturbed_copies(states, scale, copies)
            rows = np.repeat(rows, width, axis=0)
            rows[np.arange(len(rows)) % width != 0, PARAM.book] = 0.0
        else:
            states = states.copy()
        if not book:
            rows[:, PARAM.book] = 0.0
        self._requests.append((rows, states, width, scale, carried))
        return len(self._requests) - 1

    def run(self, settle: bool = False) -> list:
        """Run every request in one engine call; ``settle``: the engine's steady-state test
        may end a run early (it never ends one of MAX_ORBIT_PERIOD periods or fewer)."""
        if not self._requests:
            return []
        rows = np.concatenate([request[0] for request in self._requests])
        states = np.concatenate([request[1] for request in self._requests])
        metrics = np.empty((len(rows), len(METRIC)))
        strobes = np.empty((len(rows), self.samples, self.size))
        # (in the calling thread: a call is short, so that an interrupt is seen between
        # calls, and a kernel run in a thread of its own costs a new thread team each call;
        # run_independent, where a request carries its monodromy, is the entry that
        # returns it)
        if any(carried for *_, carried in self._requests):
            derivatives = np.full((len(rows), D, D), np.nan)
            _engine.run_independent(rows, states, metrics, strobes, np.bool_(settle),
                                    numba.get_num_threads(), derivatives)
        else:
            _engine.run_points(rows, states, metrics, strobes, settle=settle)
        work = metrics[:, METRIC.periods_run] * rows[:, PARAM.steps]
        finite = np.all(np.isfinite(states[:, :self.size]), axis=1)
        out, start = [], 0
        for r, _, width, scale, carried in self._requests:
            n = len(r) // width
            part = slice(start, start + len(r))
            m = metrics[part].reshape(n, width, len(METRIC))
            f = states[part].reshape(n, width, len(STATE))
            ok = np.all(sane(m) & finite[part].reshape(n, width), axis=1)
            if carried:
                jacobian = derivatives[part].copy()
                ok &= np.all(np.isfinite(jacobian), axis=(1, 2))
            else:
                jacobian = monodromy(f, scale) if width > 1 else None
            out.append(Evaluation(
                m[:, 0], f[:, 0], strobes[part][::width], ok, jacobian,
                work[part].reshape(n, width).sum(axis=1)))
            start += len(r)
        self._requests = []
        return out
