"""The modal engine's period map: a linear system with contact surfaces
(``models.beam.LinearSystem``) packed into the engine's rows (the system in the
eigen-coordinates of its linear part, relative to its linear steady state), and its runs.
The only module outside ``_engine`` that calls the modal engine.

The eigenvectors are taken of the balanced matrix (``scipy.linalg.matrix_balance``): a
beam's rates are its displacements times frequencies up to 1e6 1/s, and an unbalanced
eigenvector basis would lose those digits in every change of coordinates.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numba
import numpy as np
import scipy.linalg

from ._engine import modal
from ._engine.modal import REAL, RealFields, complex_fields, real_fields
from ._engine.scheduler import SHORT_CALL, run_watched

#: The largest condition number of the eigenvector basis accepted: beyond it the linear
#: part is too near a defective matrix (two equal eigenvalues sharing one eigenvector)
#: for its eigen-coordinates to keep the state's digits [-].
MAX_CONDITION = 1e8
#: Stroboscopic samples a run returns, the last ones, oldest first [-].
SAMPLES = modal.SAMPLES
#: The longest orbit a run's own steady-state test finds [forcing periods].
MAX_ORBIT = modal.MAX_ORBIT


@dataclass
class ModalPoint:
    """A point packed: its rows and the change of coordinates.

    crow, rrow: the complex and real rows (``_engine.modal.layout``); basis W (D, D) and
    its inverse, with y = y_p(t) + Re(W z); particular P (D,) complex, y_p(t) =
    Im(P exp(i w t)); dims (D, S, K).
    """

    crow: np.ndarray
    rrow: np.ndarray
    basis: np.ndarray
    inverse: np.ndarray
    particular: np.ndarray
    dims: tuple

    def to_modal(self, y) -> np.ndarray:
        """Eigen-coordinates z (D,) complex of a state y (D,) at phase 0."""
        return self.inverse @ (np.asarray(y, dtype=float) - self.particular.imag)

    def to_state(self, z) -> np.ndarray:
        """The state y (D,) at phase 0 of eigen-coordinates z (D,)."""
        return (self.basis @ z).real + self.particular.imag

    def reach(self, y) -> np.ndarray:
        """How far [m] (S,) towards each surface, against its gap (``gaps``), the motion
        from state y (D,) at phase 0 can come at any later time were it clear of the
        surfaces: its particular solution's amplitude there, |pen_p|, plus sum_d |pen_sd|
        |z_d| of its eigen-coordinates z, none of which grows (every eigenvalue has
        Re <= 0; else +inf)."""
        D, S, _ = self.dims
        lam, _, pen, _, pen_p, *_ = complex_fields(D, S, 0)
        if (self.crow[lam:lam + D].real > 0).any():
            return np.full(S, np.inf)
        return (np.abs(self.crow[pen:pen + S * D]).reshape(S, D) @ np.abs(self.to_modal(y))
                + np.abs(self.crow[pen_p:pen_p + S]))

    def free_monodromy(self, periods: int) -> np.ndarray:
        """The monodromy (D, D) of ``periods`` forcing periods of the motion clear of the
        surfaces, in closed form: the engine's flow there is exact, exp(lambda t) in the
        eigen-coordinates, so the map is W exp(Lambda p T) W^-1."""
        D, S, _ = self.dims
        lam = complex_fields(D, S, 0)[0]
        span = periods * 2.0 * np.pi / self.rrow[RealFields(*real_fields(D, S, 0)).omega]
        return ((self.basis * np.exp(self.crow[lam:lam + D] * span)) @ self.inverse).real

    @property
    def metric_width(self) -> int:
        """Columns of the point's metric rows (a run's, a measure's)."""
        return modal.metric_size(self.dims[2])

    @property
    def gaps(self) -> np.ndarray:
        """Each surface's gap [m] (S,)."""
        D, S, _ = self.dims
        gap = RealFields(*real_fields(D, S, 0)).gap
        return self.rrow[gap:gap + S]


def pack(system, frequency, amplitude, hertz_stiffness, contact_damping, resistance, steps,
         substep, max_periods, settle, limit, scale) -> ModalPoint:
    """Pack a point.

    system: models.beam.LinearSystem; frequency [Hz]; amplitude A [m/s^2] of the base
    acceleration -A sin(w t); hertz_stiffness (S,) [N/m^1.5] and contact_damping (S,)
    [s/m] of each surface; resistance [Ohm] (the power's V^2/R); steps: grid steps per
    forcing period; substep: the RK4 sub-step in contact [s]; max_periods: budget of
    periods; settle: the settle tolerance relative to each component's scale (D,)
    ``scale``; limit: the divergence limit in units of the scales.
    """
    M = np.asarray(system.matrix, dtype=float)
    D, S, K = len(M), len(system.surfaces), len(system.outputs)
    omega = 2.0 * np.pi * frequency
    lam, W, Winv = _eigenbasis(M.tobytes(), D)
    P = np.linalg.solve(1j * omega * np.eye(D) - M, np.asarray(system.forcing) * amplitude)
    h = 1.0 / (frequency * steps)
    lam_o, grid_o, pen_o, inp_o, penp_o, out_o, outp_o, strobe_o, size = complex_fields(D, S, K)
    c = np.zeros(size, dtype=complex)
    c[lam_o:lam_o + D] = lam
    c[grid_o:grid_o + D] = np.exp(lam * h)
    c[pen_o:pen_o + S * D] = (system.surfaces @ W).ravel()
    c[inp_o:inp_o + S * D] = (Winv @ system.inputs.T).T.ravel()
    c[penp_o:penp_o + S] = system.surfaces @ P
    c[out_o:out_o + K * D] = (system.outputs @ W).ravel()
    c[outp_o:outp_o + K] = system.outputs @ P
    c[strobe_o:strobe_o + D * D] = W.ravel()
    fields = real_fields(D, S, K)
    r = np.zeros(fields[-1])
    head = dict(omega=omega, steps=steps, substep=substep, max_periods=max_periods,
                settle=settle, limit=limit, resistance=resistance,
                volt_out=list(system.output_names).index("voltage"))
    for k, (name, _) in enumerate(REAL[:len(head)]):
        r[fields[k]] = head[name]
    gap_o, kh_o, ch_o, outf_o, scale_o, yp_o = fields[8:14]
    r[gap_o:gap_o + S] = system.gaps
    r[kh_o:kh_o + S] = hertz_stiffness
    r[ch_o:ch_o + S] = contact_damping
    r[outf_o:outf_o + K * S] = (system.outputs @ system.inputs.T).ravel()
    r[scale_o:scale_o + D] = scale
    r[yp_o:yp_o + D] = P.imag
    return ModalPoint(c, r, W, Winv, P, (D, S, K))


@functools.lru_cache(maxsize=64)
def _eigenbasis(matrix: bytes, D: int) -> tuple:
    """The eigenvalues lam (D,) of the matrix (D, D) given by its float64 bytes, and its
    eigenvector basis W (D, D) and inverse, of the balanced matrix; remembered, as the
    points of a sweep share their system whatever their frequency, gap or step (read-only
    arrays)."""
    M = np.frombuffer(matrix, dtype=float).reshape(D, D)
    balanced, (t, _) = scipy.linalg.matrix_balance(M, permute=False, separate=True)
    lam, vectors = np.linalg.eig(balanced)
    if np.linalg.cond(vectors) > MAX_CONDITION:
        raise ValueError("the linear system is too near a defective matrix for its "
                         "eigen-coordinates (condition number of its eigenvectors "
                         f"{np.linalg.cond(vectors):.3g} > {MAX_CONDITION:.0e})")
    W = t[:, None] * vectors
    Winv = np.linalg.inv(vectors) / t[None, :]
    for a in (lam, W, Winv):
        a.flags.writeable = False
    return lam, W, Winv


def run(packs, starts) -> tuple:
    """Run points to steady state: ``packs`` (list of :class:`ModalPoint` of one model's
    dimensions), ``starts`` (n, D) states at phase 0. Returns the metric rows
    (n, _engine.modal.metric_size(K)), the end states (n, D) at phase 0 and the last
    SAMPLES strobes (n, SAMPLES, D), oldest first."""
    D, S, K = packs[0].dims
    z = np.array([pk.to_modal(y) for pk, y in zip(packs, starts)], dtype=complex)
    crows = np.array([pk.crow for pk in packs])
    rrows = np.array([pk.rrow for pk in packs])
    metrics = np.empty((len(packs), modal.metric_size(K)))
    strobes = np.empty((len(packs), modal.SAMPLES, D))
    _take(modal.SETTLE, crows, rrows, z, None, metrics, strobes, None, None,
          _threads(rrows, None, D), (D, S, K))
    ends = np.array([pk.to_state(zi) for pk, zi in zip(packs, z)])
    return metrics, ends, strobes


def measure(packs, states, periods) -> tuple:
    """Each orbit measured over its ``periods`` (n,) forcing periods from its state (n, D)
    at phase 0 (``packs`` as run), taken to be on the orbit: the metric rows, as run's,
    with the status settled unless the run diverged; the end states (n, D) at phase 0; the
    last SAMPLES strobes (n, SAMPLES, D), oldest first, the measured ones repeated before
    them, as the orbit's."""
    D, S, K = packs[0].dims
    z = np.array([pk.to_modal(y) for pk, y in zip(packs, states)], dtype=complex)
    rrows = np.array([pk.rrow for pk in packs])
    periods = np.asarray(periods, dtype=np.int64)
    metrics = np.empty((len(packs), modal.metric_size(K)))
    strobes = np.empty((len(packs), modal.SAMPLES, D))
    _take(modal.MEASURE, np.array([pk.crow for pk in packs]), rrows, z, periods, metrics,
          strobes, None, None, _threads(rrows, periods, D), (D, S, K))
    ends = np.array([pk.to_state(zi) for pk, zi in zip(packs, z)])
    back = np.arange(SAMPLES) - SAMPLES  # (periods before the end)
    for i, p in enumerate(np.clip(periods, 1, SAMPLES)):
        strobes[i] = strobes[i, SAMPLES - p + back % p]
    return metrics, ends, strobes


def map_states(packs, states, periods) -> tuple:
    """The period map: each state (n, D) at phase 0 after ``periods`` (n,) forcing periods
    of its point (``packs``, one model's dimensions). Returns (end states (n, D), ok (n,):
    False where the run diverged)."""
    D = packs[0].dims[0]
    ends, ok, _ = _map(packs, states, periods, np.empty((len(packs), 2, D, 0)))
    return ends, ok


def variational_monodromies(packs, states, periods) -> tuple:
    """The Jacobian of the period map P^p at each state by its variational equations,
    carried along one run of each point (map_states' arguments): exact clear of the
    surfaces, the contact sub-steps' own RK4 inside them, and at the end of a contact
    that began at a located switch, the move of the sub-steps laid out from it. It is the
    derivative of the engine's own map but for the sub-steps' lengths near the
    separation, held: on the one-mode beam within 1e-5 of the size of the map's central
    differences at the first steps (tests/physics/test_beam.py). Returns (the Jacobians
    (n, D, D), the images P^p(state) (n, D), ok (n,): False where the run diverged or a
    Jacobian is not finite)."""
    # (the tangents start as the changes of z of a unit change of each component of y,
    # W^-1's columns, and end as the changes of z those bring at the run's end)
    tangents = np.array([(pk.inverse.real, pk.inverse.imag) for pk in packs])
    ends, ok, tangents = _map(packs, states, periods, tangents)
    jac = np.array([pk.basis.real @ t[0] - pk.basis.imag @ t[1]
                    for pk, t in zip(packs, tangents)])
    return jac, ends, ok & np.isfinite(jac).all(axis=(1, 2))


def _map(packs, states, periods, tangents) -> tuple:
    """map_states, with ``tangents`` (n, 2, D, m) (m changes of z: real and imaginary
    parts, component by tangent) carried along; returns (end states, ok, tangents)."""
    D, S, K = packs[0].dims
    z = np.array([pk.to_modal(y) for pk, y in zip(packs, states)], dtype=complex)
    ok = np.empty(len(packs), dtype=bool)
    rrows = np.array([pk.rrow for pk in packs])
    periods = np.asarray(periods, dtype=np.int64)
    tangents = np.ascontiguousarray(tangents, dtype=float)
    _take(modal.MAP, np.array([pk.crow for pk in packs]), rrows, z, periods, None, None,
          tangents, ok, _threads(rrows, periods, D), (D, S, K))
    return np.array([pk.to_state(zi) for pk, zi in zip(packs, z)]), ok, tangents


def monodromies(packs, states, periods, steps, central=False) -> tuple:
    """The Jacobian of the period map P^p at each state by finite differences: ``packs``
    and ``states`` (n, D) as map_states, ``periods`` (n,), ``steps`` (n, D) the step of
    each component (its unit). Forward differences take D + 1 runs of each point, central
    ones (``central``) 2 D + 1. Returns (the Jacobians (n, D, D), the images P^p(state)
    (n, D), ok (n,): False where a run diverged)."""
    states = np.asarray(states, dtype=float)
    steps = np.asarray(steps, dtype=float)
    n, D = states.shape
    copies = 2 * D + 1 if central else D + 1
    moved = np.repeat(states[:, None, :], copies, axis=1)
    moved[:, 1:D + 1] += steps[:, None, :] * np.eye(D)
    if central:
        moved[:, D + 1:] -= steps[:, None, :] * np.eye(D)
    ends, ok = map_states([pk for pk in packs for _ in range(copies)], moved.reshape(-1, D),
                          np.repeat(np.asarray(periods, dtype=np.int64), copies))
    ends = ends.reshape(n, copies, D)
    if central:
        jac = (ends[:, 1:D + 1] - ends[:, D + 1:]).transpose(0, 2, 1) / (2 * steps[:, None, :])
    else:
        jac = (ends[:, 1:D + 1] - ends[:, :1]).transpose(0, 2, 1) / steps[:, None, :]
    return jac, ends[:, 0], ok.reshape(n, copies).all(axis=1)


def _take(kind, crows, rrows, z, periods, metrics, strobes, tangents, ok, threads, dims):
    """The modal engine's take_points of ``kind`` on points of dimensions ``dims`` (D, S,
    K), on ``threads`` threads of the engine's pool taking their points from one counter,
    in a way an interrupt reaches: it stops the threads taking points, and is raised once
    they have returned. The arrays a kind does not use are None here (empty ones of their
    types are passed, so that every kind calls one compiled entry)."""
    D, S, K = dims
    n = len(crows)
    if periods is None:
        periods = np.zeros(n, dtype=np.int64)
    if metrics is None:
        metrics, strobes = np.empty((n, 0)), np.empty((n, 0, 0))
    if tangents is None:
        tangents, ok = np.empty((n, 2, D, 0)), np.empty(n, dtype=bool)
    taken = np.zeros(2, dtype=np.int64)  # the next point; nonzero: stop taking points

    def task():
        modal.take_points(kind, crows, rrows, z, periods, metrics, strobes, tangents, ok,
                          taken, D, S, K)

    def stop():
        taken[1] = 1

    run_watched([task] * threads, lambda: 0, stop)


def _threads(rrows, periods, D) -> int:
    """Threads for a call of the engine on points ``rrows`` of state size D over
    ``periods`` each (None: their budgets): numba's count, at most one per point, but one
    for a short call.

    A call whose work is below the lane engine's scheduler.SHORT_CALL runs on one thread:
    on a shared machine every thread of a call waits for the slowest, one that is
    descheduled most of all, and Newton's rounds make many such calls. The work is counted
    in that engine's unit, an RK4 step of one point, of which a grid step of this engine
    costs about D: a complex product and a share of each surface's penetration for each of
    its D components, in scalar code, against an RK4 step of the three-state tip-mass model
    shared by a vector's lanes (benchmarks/results/modal_period.md); contact costs more."""
    f = RealFields(*real_fields(0, 0, 0))
    periods = rrows[:, f.max_periods] if periods is None else periods
    if float(np.sum(periods * rrows[:, f.steps])) * D < SHORT_CALL:
        return 1
    return max(1, min(numba.get_num_threads(), len(rrows)))


def record_motion(packed: ModalPoint, start, periods: int, rows: int) -> np.ndarray:
    """Every sample of ``periods`` forcing periods from state ``start`` (D,) at phase 0,
    at most ``rows``: (n, 1 + S + K) with time [s], each surface's force [N], each
    output."""
    D, S, K = packed.dims
    z = packed.to_modal(start).astype(complex)
    rec = np.empty((rows, 1 + S + K))
    n = modal.record_samples(packed.crow, packed.rrow, z, periods, rec, D, S, K)
    return rec[:n]
