"""The beam model's analyses: points to steady state at the accuracy asked, sweeps over
any parameters (frequency up and down, continuing each line's state), a scene's orbit
recorded step by step; their CF datasets.

Each point is solved at its first step choice and again with the grid and the contact
sub-step halved, and halved again where the two disagree by more than ``accuracy``: the
error estimate reported is that change (docs/numerics.md, "The beam").
"""

from __future__ import annotations

import functools
import itertools
import math
from collections import namedtuple
from dataclasses import dataclass

import numpy as np
import xarray as xr

from . import modal_map
from ._engine.modal import HEAD, METRIC_HEAD
from .acceptance import (
    NEAR,
    PROOF_MARGIN,
    closing_period,
    norm,
    on_its_way,
    periods_to_near,
    suggested_period,
)
from .beam_packing import BeamSystem, beam_system, contact_steps, first_steps, pack_beam
from .beam_parameters import (
    BEAM_PARAMETERS,
    BEAM_PRESET_NOTES,
    DEFAULT_BEAM_PRESET,
    bimorph,
    moving_stop,
    resolve_beam_parameters,
)
from .datasets import multiplier_coordinate
from .orbits import EXPANDING, FIRST_CHUNK
from .outputs import OUTPUTS, STATUS_FLAGS
from .parameters import ParameterError
from .period_map import sorted_multipliers
from .version import __version__

#: Halvings of the grid and the contact sub-step the accuracy check may take beyond the
#: first choice [-].
MAX_LEVELS = 5
#: The metrics whose change at halved steps is the error estimate (relative to their own
#: size; the extremes of displacement relative to the larger of them) [-]. A rigid stop's
#: stop_face_max is 0 at every step, and adds nothing.
ESTIMATED = ("power", "v_peak", "x_max", "x_min", "root_strain_max", "stop_face_max")
_SETTLED, _NOT_SETTLED, _DIVERGED = 0, 1, 2
#: Periods of transient before Newton on the period map takes over [-].
TRANSIENT = 24
#: Newton iterations at the first step choice, chord iterations (the first level's
#: monodromy reused) at each finer one [-].
NEWTON = 8
CHORD = 8
#: The move of an iterate below which Newton keeps its monodromy, and the step of a
#: monodromy by forward differences (the beam's continuation), relative to each
#: component's scale [-].
PERTURBATION = 1e-6
#: A fixed point whose monodromy's spectral radius exceeds this is unstable: not the
#: motion's steady state (the margin: the monodromy's error at the first steps, 1e-5 to
#: 1e-4 on the presets) [-].
UNSTABLE = 1.0 + 1e-3
#: The scalar outputs of a beam point, in the order of a solution's table.
SCALARS = ("power", "v_rms", "v_peak", "power_peak", "x_max", "x_min",
           "contact_displacement_max", "contact_displacement_min", "contact_force_max",
           "impacts_per_period", "approach_velocity", "root_strain_max", "root_stress_piezo",
           "root_stress_substrate", "stop_face_max", "orbit_period", "status", "periods_run",
           "error_estimate", "steps_per_period", "contact_step", "spectral_radius")


@functools.lru_cache(maxsize=512)
def _system(key: tuple) -> BeamSystem:
    return beam_system(dict(key))


def system_of(p: dict) -> BeamSystem:
    """The model of a validated beam parameter set, remembered for the points of a sweep
    that share it."""
    return _system(tuple(sorted(p.items())))


@dataclass
class BeamSolution:
    """Points solved: each output (SCALARS, ``modal_amplitude`` (n, N) and the Floquet
    multipliers' real and imaginary parts (n, D), NaN beyond a point's own) as an array
    over the points, with the end states (n, D) at phase 0 and the last strobes (n,
    SAMPLES, D)."""

    values: dict
    ends: np.ndarray
    strobes: np.ndarray


def point_outputs(p: dict, bs: BeamSystem, row: np.ndarray) -> dict:
    """A point's outputs (a dict of SCALARS but those made around the engine, and its
    modal amplitudes (N,)) from its engine metric row."""
    names = bs.system.output_names
    K = len(names)
    nh = len(METRIC_HEAD)
    hi = dict(zip(names, row[nh:nh + K]))
    lo = dict(zip(names, row[nh + K:nh + 2 * K]))
    beam = bimorph(p)
    strain = max(abs(hi["root_strain"]), abs(lo["root_strain"]))
    v_peak = max(abs(hi["voltage"]), abs(lo["voltage"]))
    half = beam.substrate_thickness / 2
    out = {
        "power": row[HEAD.power], "v_rms": row[HEAD.voltage_rms], "v_peak": v_peak,
        "power_peak": v_peak ** 2 / p["resistance"],
        "x_max": hi["tip_displacement"], "x_min": lo["tip_displacement"],
        "contact_displacement_max": hi["contact_displacement"],
        "contact_displacement_min": lo["contact_displacement"],
        "contact_force_max": row[HEAD.contact_force],
        "impacts_per_period": row[HEAD.impacts],
        "approach_velocity": row[HEAD.approach_velocity],
        "root_strain_max": strain,
        "root_stress_piezo": beam._piezo("youngs_modulus") * strain,
        "root_stress_substrate": beam._substrate("youngs_modulus") * strain * half
        / (half + beam.piezo_thickness),
        "stop_face_max": max(hi["stop_face"], 0.0),
        "orbit_period": row[HEAD.period], "status": row[HEAD.status],
        "periods_run": row[HEAD.periods_run],
    }
    modal = np.array([max(abs(hi[f"eta_{r}"]), abs(lo[f"eta_{r}"]))
                      for r in range(1, len(bs.modes.omega) + 1)])
    if row[HEAD.status] == _DIVERGED:  # (its row holds what the run booked before it blew up)
        out.update({name: math.nan for name in out if name not in _COUNTED})
        modal[:] = math.nan
    return out, modal


#: The outputs a diverged point still reports: how its run ended, not what it measured.
_COUNTED = ("orbit_period", "status", "periods_run")


def _change(a: dict, b: dict) -> float:
    """The relative change of the ESTIMATED metrics from a to b (NaN where either did not
    settle)."""
    if a["status"] != _SETTLED or b["status"] != _SETTLED:
        return math.nan
    return relative_change(a, b)


def relative_change(a: dict, b: dict) -> float:
    """The largest change of the ESTIMATED metrics from outputs a to outputs b, each
    relative to its size in b (the extremes of displacement to the larger of them) [-]."""
    reach = max(abs(b["x_max"]), abs(b["x_min"]), 1e-300)
    worst = 0.0
    for name in ESTIMATED:
        size = reach if name in ("x_max", "x_min") else max(abs(b[name]), 1e-300)
        worst = max(worst, abs(a[name] - b[name]) / size)
    return worst


def solve_beam(points: list, starts=None) -> BeamSolution:
    """Each validated beam parameter set of ``points`` to steady state from ``starts``
    ((n, D) states at phase 0; None: each point from rest), at the step that meets its
    ``accuracy``. Points of different state sizes are solved in groups.

    The steady state is the attractor the motion reaches: a short transient, then Newton
    attempts on the period map from where the motion got to, an orbit taken where it is
    stable and the motion is on its way to it, the motion integrated on between attempts
    (_attempts)."""
    n = len(points)
    systems = [system_of(p) for p in points]
    dims = [len(bs.system.matrix) for bs in systems]
    values = {name: np.full(n, np.nan) for name in SCALARS}
    modal, multipliers = [None] * n, [None] * n
    ends, strobes = [None] * n, [None] * n
    for D in sorted(set(dims)):
        idx = [i for i in range(n) if dims[i] == D]
        _solve_group([points[i] for i in idx], [systems[i] for i in idx],
                     None if starts is None else [starts[i] for i in idx], idx, values,
                     modal, multipliers, ends, strobes)
    values["modal_amplitude"] = _padded(modal)
    values["floquet_multipliers_real"] = _padded([m.real for m in multipliers])
    values["floquet_multipliers_imag"] = _padded([m.imag for m in multipliers])
    return BeamSolution(values, ends, strobes)


def _padded(rows: list) -> np.ndarray:
    """Rows of different lengths as one array, NaN beyond each row's own."""
    out = np.full((len(rows), max(len(r) for r in rows)), np.nan)
    for i, r in enumerate(rows):
        out[i, :len(r)] = r
    return out


#: Newton's fixed points of ``_Group.newton``: the iterates (n, D), their monodromies (n,
#: D, D), which converged, the images P^p of the first iterates (n, D), and for an attempt
#: whether it ended at its first run and the distance it measured there (relative to the
#: scales) [-].
Newton = namedtuple("Newton", "states jacobians converged images far distance")


def spectral_radii(jacobians) -> np.ndarray:
    """The spectral radius [-] of each monodromy (n, D, D), inf where one is not finite."""
    out = np.full(len(jacobians), np.inf)
    good = np.isfinite(jacobians).all(axis=(1, 2))
    if good.any():
        out[good] = np.abs(sorted_multipliers(jacobians[good])[:, 0])
    return out


class _Group:
    """Points of one state size solved level by level: their rows at a level, the period
    map's fixed points by Newton, the orbit measured."""

    def __init__(self, points, systems, starts):
        self.points, self.systems = points, systems
        self.first = [first_steps(p, bs) for p, bs in zip(points, systems)]
        self.starts = [np.zeros(len(bs.system.matrix)) if y is None
                       else np.asarray(y, dtype=float) for bs, y in zip(systems, starts)]
        self.scale = [bs.scale for bs in systems]

    def packs(self, which, lv, budget=None):
        """Rows of points ``which`` at level ``lv``; ``budget``: each one's own budget of
        periods (a sequence over ``which``), else their max_periods."""
        out = []
        for j, k in enumerate(which):
            steps, sub = self.first[k]
            p = self.points[k] if budget is None else dict(self.points[k],
                                                           max_periods=budget[j])
            out.append(pack_beam(p, self.systems[k], steps * 2 ** lv, sub / 2 ** lv))
        return out

    def newton(self, packs, which, states, periods, jac=None, rounds=NEWTON,
               touched=None, retry=None) -> Newton:
        """Fixed points of P^p from ``states`` (len(which), D): full Newton with
        monodromies by the variational equations (the last one reused by an iterate within
        PERTURBATION of where it was taken), or chord steps with ``jac`` where given.
        Attempts from the motion's states (``touched``: whether each motion touches a
        stop) end at their first run where a motion that touches is not in a stable
        orbit's linear regime: Newton's first step beyond NEAR, or the monodromy there
        expanding (EXPANDING; not in a ``retry`` at the period of the orbit the last
        attempt turned away, which the motion nears along a multiplier near -1), as the
        tip-mass solver's attempts."""
        states = np.array(states, dtype=float)
        n, D = states.shape
        conv = np.zeros(n, dtype=bool)
        jacs = np.full((n, D, D), np.nan) if jac is None else np.array(jac)
        tol = np.array([self.points[k]["settle_tolerance"] for k in which])
        scale = np.array([self.scale[k] for k in which])
        live = np.isfinite(jacs).all(axis=(1, 2)) if jac is not None else np.ones(n, bool)
        last = np.full(n, np.inf)  # each point's last residual, relative to its scales
        moved = np.full(n, np.inf)  # each point's last Newton step, relative to its scales
        images = np.full((n, D), np.nan)
        far = np.zeros(n, dtype=bool)
        distance = np.full(n, np.inf)
        for iteration in range(rounds):
            idx = np.flatnonzero(live & ~conv)
            if not len(idx):
                break
            # full Newton takes the monodromy again (by the variational equations, along
            # the iterate's run) unless the iterate moved less than PERTURBATION from
            # where it was taken: it then changed by less than its own error (as the
            # tip-mass solver's CHORD), and the iterate runs alone, at a run's cost
            fresh = (moved[idx] > PERTURBATION) if jac is None else np.zeros(len(idx), bool)
            image, ok = np.empty((len(idx), D)), np.empty(len(idx), dtype=bool)
            taken, alone = idx[fresh], idx[~fresh]
            if len(taken):
                jacs[taken], image[fresh], ok[fresh] = modal_map.variational_monodromies(
                    [packs[j] for j in taken], states[taken], periods[taken])
            if len(alone):
                image[~fresh], ok[~fresh] = modal_map.map_states(
                    [packs[j] for j in alone], states[alone], periods[alone])
            if iteration == 0:
                images[idx] = image
            J = jacs[idx]
            residual = image - states[idx]
            size = np.abs(residual / scale[idx]).max(axis=1)
            small = size <= tol[idx]
            conv[idx[small & ok]] = True
            live[idx[~ok]] = False
            # a chord step that does not halve the residual is given up: its monodromy is
            # too far from the map's for the iterates to reach the fixed point in the
            # rounds left
            if jac is not None:
                stalled = ~small & (size > 0.5 * last[idx])
                live[idx[stalled]] = False
                ok = ok & ~stalled
            last[idx] = size
            step = idx[~small & ok]
            if len(step):
                pick = np.isin(idx, step)
                delta = np.linalg.solve(J[pick] - np.eye(D), -residual[pick][..., None])[..., 0]
                before = moved[step].copy()
                moved[step] = np.abs(delta / scale[step]).max(axis=1)
                if touched is not None and iteration > 0:
                    # an attempt's step that does not halve the last has stalled: it is
                    # given up rather than run (as the tip-mass solver's); a step that
                    # grew can take the iterate thousands of scales deep into a stop,
                    # where the contact's sub-steps take the engine minutes a period
                    stalled = moved[step] > 0.5 * before
                    live[step[stalled]] = False
                    delta[stalled] = 0.0
                if touched is not None and iteration == 0:
                    # (the distance from the orbit: about the first step, and at least
                    # half the motion's move over the run)
                    distance[step] = np.maximum(moved[step], 0.5 * size[pick])
                    expands = (spectral_radii(J[pick]) > EXPANDING) & ~retry[step]
                    far[step] = touched[step] & ((distance[step] > NEAR) | expands)
                    live[step[far[step]]] = False
                    delta[far[step]] = 0.0
                states[step] += delta
        return Newton(states, jacs, conv, images, far, distance)

    def measure(self, packs, which, states, periods):
        """The orbits of the fixed points ``states`` (n, D) of P^p, p = ``periods`` (n,),
        of points ``which`` (``packs``), measured over p periods (modal_map.measure): the
        metric rows, end states and strobes, as modal_map.run's. An orbit that closes after
        a divisor d of p too (its strobe after d periods within the settle tolerance of
        its start, as the tip-mass solver checks) is of period d, its metric row says so.
        The engine's own test, which a run would settle it by first, finds no orbit longer
        than modal_map.MAX_ORBIT periods: Newton's orbits of up to SAMPLES - 1 periods
        were then run to the end of their budget and reported not settled."""
        m, e, s = modal_map.measure(packs, states, periods)
        for j, (k, p) in enumerate(zip(which, periods)):
            m[j, HEAD.period] = closing_period(s[j], states[j], int(p), self.scale[k],
                                               self.points[k]["settle_tolerance"])
        return m, e, s


def _solve_group(points, systems, starts, idx, values, modal, multipliers, ends, strobes):
    g = _Group(points, systems, [None] * len(points) if starts is None else starts)
    n = len(points)
    todo = list(range(n))
    # level 0: a short transient, then attempts from where the motion got to (_attempts);
    # a motion proved never to reach a stop from its start settles on the linear steady
    # state, without either (_take_free)
    packs0 = g.packs(todo, 0)
    D = len(g.starts[0])
    e = np.array(g.starts, dtype=float)
    s = np.full((n, modal_map.SAMPLES, D), np.nan)
    m = np.full((n, packs0[0].metric_width), np.nan)
    run, period = np.zeros(n), np.ones(n, dtype=np.int64)
    orbit, jac = np.full((n, D), np.nan), np.full((n, D, D), np.nan)
    free = [k for k in todo if _never_reaches(packs0[k], e[k])]
    for k in free:
        _take_free(packs0[k], k, orbit, jac, period)
    moving = [k for k in todo if k not in free]
    if moving:
        short = [min(TRANSIENT, points[k]["max_periods"]) for k in moving]
        m[moving], e[moving], s[moving] = modal_map.run(g.packs(moving, 0, budget=short),
                                                        e[moving])
        run[moving] = m[moving, HEAD.periods_run]
        tested = m[moving, HEAD.status] == _SETTLED
        period[moving] = np.where(tested, np.maximum(m[moving, HEAD.period], 1), 1)
    ended = {k: (m[k], e[k], s[k]) for k in moving if m[k, HEAD.status] == _DIVERGED}
    _attempts(g, packs0, [k for k in moving if k not in ended], e, run, period,
              np.array([_touched(row) for row in m]), orbit, jac, ended)
    taken = [k for k in todo if k not in ended]
    m, e, s = np.empty_like(m), np.empty_like(e), np.empty_like(s)
    if taken:
        m[taken], e[taken], s[taken] = g.measure([packs0[k] for k in taken], taken,
                                                 orbit[taken], period[taken])
        run[taken] += m[taken, HEAD.periods_run]
    for k, (row, end, strobe) in ended.items():
        m[k], e[k], s[k] = row, end, strobe
    # an orbit the motion settled on by the engine's own test has no monodromy yet, and
    # one Newton took at a multiple of its period (a fixed point of P^p that repeats
    # sooner, as the measure found) has that of the longer map: take it there, at the
    # orbit's period, for the finer steps' chord steps (without one, each finer step
    # settles again by a plain run from the coarser orbit, tens to hundreds of periods at
    # an orbit of period 2 or more), as the tip-mass solver takes one at an orbit its
    # engine's test found
    found = [k for k in todo if m[k, HEAD.status] == _SETTLED
             and (k in ended or m[k, HEAD.period] != period[k])]
    if found:
        J, _, ok = modal_map.variational_monodromies(
            [packs0[k] for k in found], e[found],
            np.maximum(m[found, HEAD.period], 1).astype(np.int64))
        jac[found] = np.where(ok[:, None, None], J, np.nan)
    coarse = {k: (point_outputs(points[k], systems[k], m[k]), e[k], s[k], 0) for k in todo}
    periods_run = {k: run[k] for k in todo}
    # a point that did not settle (or diverged) at the first step is reported as it is,
    # with no estimate: a finer step would only run its whole budget again
    done = {k: (coarse[k], math.nan) for k in todo if m[k, HEAD.status] != _SETTLED}
    todo = [k for k in todo if k not in done]
    lv, estimate = 1, dict.fromkeys(todo, math.nan)
    most = BEAM_PARAMETERS["steps_per_period"].high
    while todo and lv <= MAX_LEVELS:
        # a level whose grid, or whose contact sub-steps a period, would pass the
        # steps_per_period the parameter table allows is not run (a scene records every
        # step): the point keeps the estimate it has, none at its first step
        for k in [k for k in todo if 2 ** lv * max(
                g.first[k][0], contact_steps(g.points[k], g.first[k][1])) > most]:
            done[k] = coarse[k], estimate[k]
            todo.remove(k)
        if not todo:
            break
        packs = g.packs(todo, lv)
        start = np.array([coarse[k][1] for k in todo])
        per = np.array([max(int(coarse[k][0][0]["orbit_period"]), 1) for k in todo],
                       dtype=np.int64)
        # (the last monodromy taken serves the chord steps of every finer level)
        nt = g.newton(packs, todo, start, per, jac=jac[todo], rounds=CHORD)
        nt = _newton_at_level(g, packs, todo, start, per, nt, jac)
        m, e, s = _finer_orbits(g, packs, todo, start, per, nt)
        nxt = []
        for j, k in enumerate(todo):
            fine = (point_outputs(points[k], systems[k], m[j]), e[j], s[j], lv)
            periods_run[k] += m[j, HEAD.periods_run]
            est = _change(coarse[k][0][0], fine[0][0])
            if est <= points[k]["accuracy"] or not math.isfinite(est) or lv == MAX_LEVELS:
                done[k] = fine, est
            else:
                coarse[k], estimate[k] = fine, est
                nxt.append(k)
        todo, lv = nxt, lv + 1
    mult = _multipliers(g, done)
    for k in range(n):
        ((table, amp), end, strobe, lv_k), est = done[k]
        i = idx[k]
        for name, v in table.items():
            values[name][i] = v
        values["error_estimate"][i] = est
        values["periods_run"][i] = periods_run[k]
        steps, sub = g.first[k]
        values["steps_per_period"][i] = steps * 2 ** lv_k
        values["contact_step"][i] = sub / 2 ** lv_k
        values["spectral_radius"][i] = abs(mult[k][0]) if k in mult else np.nan
        modal[i], ends[i], strobes[i] = amp, end, strobe
        multipliers[i] = mult.get(k, np.full(len(end), complex(math.nan, math.nan)))


def _newton_at_level(g, packs, todo, start, per, chord, jac) -> Newton:
    """The chord steps ``chord`` at a finer level (over points ``todo``, from their coarser
    orbits ``start`` (n, D) of periods ``per`` (n,)), with Newton at that level from the
    coarser orbit where they did not converge and the motion from there would take
    longer to settle by the engine's test than (D + 2) p periods (what that Newton took
    when its monodromy took D + 1 copies, and a run to confirm; kept as the rule, so that
    the same points take it): its stable fixed points are taken as converged, and their
    monodromies serve the next levels' chord steps (into ``jac``, by point).

    Near a multiplier of modulus near 1 the chord steps with a coarser monodromy stall
    (I - M nearly singular amplifies its error), and the motion settles slowly too: a
    point whose coarser orbit settled could spend its whole budget at the finer step and
    be reported not settled. How long it would take is foretold from the monodromy's
    spectral radius and the residual at ``start`` (acceptance.periods_to_near)."""
    D = start.shape[1]
    slow = []
    for j, k in enumerate(todo):
        if chord.converged[j] or not np.isfinite(chord.images[j]).all():
            continue
        residual = norm(chord.images[j] - start[j], g.scale[k])
        radius = spectral_radii(jac[k][None])[0]
        # (the engine's test finds no orbit longer than MAX_ORBIT periods)
        settling = (periods_to_near(per[j], 2 * g.points[k]["settle_tolerance"], residual,
                                    radius)
                    if radius < 1 and per[j] <= modal_map.MAX_ORBIT else math.inf)
        if settling > (D + 2) * per[j]:
            slow.append(j)
    if not slow:
        return chord
    nt = g.newton([packs[j] for j in slow], [todo[j] for j in slow], start[slow], per[slow])
    taken = nt.converged & (spectral_radii(nt.jacobians) <= UNSTABLE)
    states, converged = chord.states.copy(), chord.converged.copy()
    for i, j in enumerate(slow):
        if taken[i]:
            states[j], converged[j], jac[todo[j]] = nt.states[i], True, nt.jacobians[i]
    return chord._replace(states=states, converged=converged)


def _finer_orbits(g, packs, todo, start, per, chord) -> tuple:
    """The orbits at a finer level of points ``todo`` from the coarser ones ``start``
    (n, D) of periods ``per`` (n,), and the chord steps there (``chord``): an orbit the
    chord steps converged to is measured over its period (_Group.measure: their last map
    already repeated it within the settle tolerance); where they did not, the motion from
    the coarser orbit settles by the engine's own test and is measured (modal_map.run).
    Returns the metric rows, end states and strobes, as modal_map.run's."""
    n, D = start.shape
    m = np.empty((n, packs[0].metric_width))
    e, s = np.empty((n, D)), np.empty((n, modal_map.SAMPLES, D))
    took, left = np.flatnonzero(chord.converged), np.flatnonzero(~chord.converged)
    if len(took):
        m[took], e[took], s[took] = g.measure([packs[j] for j in took],
                                              [todo[j] for j in took], chord.states[took],
                                              per[took])
    if len(left):
        m[left], e[left], s[left] = modal_map.run([packs[j] for j in left], start[left])
    return m, e, s


def _touched(row) -> bool:
    """Whether a run of metric row ``row`` touched a stop: a contact force, or an impact."""
    return bool(row[HEAD.contact_force] > 0 or row[HEAD.impacts] > 0)


def _never_reaches(pack, y) -> bool:
    """Whether the motion from state y (D,) at phase 0 of ``pack`` provably never reaches
    a stop (ModalPoint.reach, with PROOF_MARGIN of its bound for rounding)."""
    reach = pack.reach(y)
    return bool((reach + PROOF_MARGIN * np.abs(reach) < pack.gaps).all())


def _take_free(pack, k, orbit, jac, period) -> None:
    """Point k, whose motion never reaches a stop, settles on the linear steady state, the
    particular solution (the fixed point of its exact contact-free flow, of period 1): its
    state at phase 0 into ``orbit``, its monodromy in closed form into ``jac``."""
    orbit[k], jac[k], period[k] = pack.particular.imag, pack.free_monodromy(1), 1


def _on_its_way(g, pack, k, t0, t1, y, jac) -> bool:
    """Whether point k's motion at ``t0``, one map of the period map later at ``t1``, is
    on its way to the stable fixed point ``y`` of monodromy ``jac`` (pack: the point at
    the first steps), as the tip-mass solver judges it: an orbit clear of the stops where
    it is proved that the motion never reaches one either (ModalPoint.reach: the
    contact-free motion's excursion is bounded, and that orbit is the motion's only
    one clear of them); an orbit with contact where the motion is in its linear regime
    (acceptance.on_its_way)."""
    if (pack.reach(y) < pack.gaps).all():  # (an orbit clear of the stops)
        return _never_reaches(pack, t0)
    return on_its_way(t0, t1, 1, y, jac, g.scale[k], g.points[k]["settle_tolerance"], NEAR)


def _attempts(g, packs, trying, e, run, period, touched, orbit, jac, ended) -> None:
    """Newton attempts at the first steps for the points ``trying``, from the motion's
    states ``e`` (n, D) after ``run`` (n,) periods, at the orbit
    periods ``period`` (n,), whether the motion ``touched`` (n,) a stop in its last run,
    as the tip-mass solver makes them (orbits, "Newton only accelerates"): a stable
    orbit the motion is on its way to (_on_its_way) is taken (its state into
    ``orbit``, its monodromy into ``jac``); else the motion, moved on by the attempt's
    first run, is integrated on (as long as it has run, at least FIRST_CHUNK periods, or
    for the periods the attempt's monodromy says it needs to come NEAR the orbit) and
    tried again at the period its strobes suggest. A motion that settles by the engine's
    own test, diverges or spends its budget ends (``ended``: point -> its last run's
    metric row, end state and strobes). ``e`` and ``run`` are updated in place.

    Newton converges as readily to a stable orbit of another attractor, which coexists
    with the motion's own near a period doubling or a fold, as to the motion's own: it
    only accelerates the motion to an orbit it is seen to reach."""
    refused = {}  # point -> period of the stable orbit with contact last turned away
    left = {}  # point -> periods of its piece of motion still to run
    while trying or left:
        if trying:
            _attempt(g, packs, trying, e, run, period, touched, orbit, jac, refused, left)
        moving = list(left)
        if not moving:
            return
        budget = [int(left[k]) for k in moving]
        m, end, strobes = modal_map.run(g.packs(moving, 0, budget=budget), e[moving])
        trying = []
        for j, k in enumerate(moving):
            e[k], touched[k] = end[j], _touched(m[j])
            run[k] += m[j, HEAD.periods_run]
            left[k] -= m[j, HEAD.periods_run]
            if m[j, HEAD.status] != _NOT_SETTLED or run[k] >= g.points[k]["max_periods"]:
                ended[k] = (m[j], end[j], strobes[j])
                del left[k]
            elif left[k] <= 0:
                del left[k]
                # (a motion nearing a stable orbit along a multiplier near -1 repeats
                # after twice its period better than after it: where the strobes suggest
                # twice the period of the orbit last turned away, the period is that
                # orbit's, as in the tip-mass solver)
                period[k] = suggested_period(strobes[j], g.scale[k])
                if refused[k] > 0 and period[k] == 2 * refused[k]:
                    period[k] = refused[k]
                trying.append(k)


def _attempt(g, packs, trying, e, run, period, touched, orbit, jac, refused, left) -> None:
    """One Newton attempt of each point of ``trying`` (_attempts): a stable orbit the
    motion is on its way to is taken; else the motion moves on by the attempt's first run
    and its next piece (``left``: periods) is set, as long as it has run (at least
    FIRST_CHUNK periods), or the periods the attempt's monodromy says it needs to come
    NEAR the orbit, within its budget."""
    proved = [k for k in trying if _never_reaches(packs[k], e[k])]
    for k in proved:
        _take_free(packs[k], k, orbit, jac, period)
    trying = [k for k in trying if k not in proved]
    if not trying:
        return
    retry = np.array([period[k] == refused.get(k, 0) for k in trying])
    nt = g.newton([packs[k] for k in trying], trying, e[trying], period[trying],
                  touched=touched[trying], retry=retry)
    radius = spectral_radii(nt.jacobians)
    for j, k in enumerate(trying):
        p = period[k]
        if nt.converged[j] and radius[j] <= UNSTABLE and _on_its_way(
                g, packs[k], k, e[k], nt.images[j], nt.states[j], nt.jacobians[j]):
            orbit[k], jac[k] = nt.states[j], nt.jacobians[j]
            continue
        d0 = nt.distance[j] if nt.far[j] else np.abs((e[k] - nt.states[j]) / g.scale[k]).max()
        stable = radius[j] < 1 and (nt.far[j] or nt.converged[j])
        hint = periods_to_near(p, NEAR, d0, radius[j]) if stable and d0 > NEAR else 0.0
        refused[k] = p if stable and nt.converged[j] and touched[k] else 0
        if np.isfinite(nt.images[j]).all():  # (the attempt's first run is the motion's)
            e[k] = nt.images[j]
            run[k] += p
        chunk = max(run[k], FIRST_CHUNK)
        if hint > 0:
            chunk = min(max(hint, p), 4 * chunk)
        # (a piece that ends short of the budget leaves room for an attempt and a last
        # run as long as the strobes it reports; at least one period, which the run
        # measures, where the attempt's own run spent the budget)
        rest = g.points[k]["max_periods"] - run[k]
        whole = chunk >= rest or rest <= 2 * modal_map.SAMPLES
        left[k] = max(rest, 1) if whole else min(chunk, rest - 2 * modal_map.SAMPLES)


def _multipliers(g: _Group, done: dict) -> dict:
    """The Floquet multipliers (largest modulus first) of each settled point of ``done``
    (point -> ((outputs, end state, strobes, level), estimate)): the monodromy of its
    orbit by the variational equations at the level reported, or the contact-free map's
    in closed form where the orbit provably never reaches a stop. Newton's monodromy at
    the first level is off by that level's discretization error (1e-5 to 1e-4 in the
    multipliers on the presets)."""
    settled = [k for k, ((out, *_), _) in done.items() if out[0]["status"] == _SETTLED]
    found = {}
    for lv in sorted({done[k][0][3] for k in settled}):
        which = [k for k in settled if done[k][0][3] == lv]
        packs = g.packs(which, lv)
        periods = np.array([max(int(done[k][0][0][0]["orbit_period"]), 1) for k in which])
        ends = np.array([done[k][0][1] for k in which])
        # (an orbit the motion from it provably never leaves for a stop has the
        # contact-free map's monodromy, in closed form)
        free = np.array([_never_reaches(pk, y) for pk, y in zip(packs, ends)], dtype=bool)
        for j in np.flatnonzero(free):
            found[which[j]] = sorted_multipliers(packs[j].free_monodromy(periods[j])[None])[0]
        touching = np.flatnonzero(~free)
        if not len(touching):
            continue
        jac, _, ok = modal_map.variational_monodromies(
            [packs[j] for j in touching], ends[touching], periods[touching])
        for i, j in enumerate(touching):
            if ok[i]:
                found[which[j]] = sorted_multipliers(jac[i][None])[0]
    return found


def points_of(preset: str | None, fixed: dict, axes: dict) -> tuple[list, list]:
    """The validated points of a grid: ``axes`` (name -> values, in order), each point
    the preset with ``fixed`` and its coordinates; returns (points, shape)."""
    for name in axes:
        if name not in BEAM_PARAMETERS:
            raise ParameterError(f"unknown beam parameter {name!r} on a sweep axis: known "
                                 f"parameters are {', '.join(BEAM_PARAMETERS)}")
    shape = [len(v) for v in axes.values()]
    points = [resolve_beam_parameters(preset, **fixed, **dict(zip(axes, combo)))
              for combo in itertools.product(*axes.values())]
    return points, shape


def beam_sweep(axes: dict, preset: str | None = DEFAULT_BEAM_PRESET, directions=None,
               progress=None, **fixed) -> xr.Dataset:
    """Steady states of the beam over a grid (``axes``: parameter name -> values, SI
    units), solved in this process and kept in memory. With ``directions`` ("up", "down"
    or both) and a ``frequency`` axis, each line along frequency is swept in that
    direction, every point starting from the previous one's orbit (the stop's
    hysteresis); otherwise every point starts from rest.
    ``progress(done, total, what)``, if given, is called after each step of the lines (or
    once for an unswept grid). Returns a CF dataset (``model`` = "beam").

    The same grid in chunks kept as they finish (an output file, ``resume``), or on Dask:
    beam_cluster.run_beam_sweep, or a sweep file run by beam_cluster.run_beam_file; the
    numbers are these, bit for bit."""
    kinds = {"float": float, "int": np.int64}
    for name in axes:
        if name not in BEAM_PARAMETERS:
            raise ParameterError(f"unknown beam parameter {name!r} on a sweep axis: known "
                                 f"parameters are {', '.join(BEAM_PARAMETERS)}")
    axes = {name: np.asarray(v, dtype=kinds.get(BEAM_PARAMETERS[name].kind, object))
            for name, v in axes.items()}
    directions = (directions,) if isinstance(directions, str) else directions
    for d in directions or ():
        if d not in ("up", "down"):
            raise ParameterError(f"directions [-] = {d!r}: must be 'up', 'down' or both")
    if directions and "frequency" not in axes:
        raise ParameterError("directions [-]: a sweep up or down needs a frequency axis")
    points, shape = points_of(preset, fixed, axes)
    solved = solve_grid(points, axes, shape, directions, progress)
    return _dataset([sol.values for sol in solved], axes, directions, points[0],
                    any(moving_stop(p) for p in points), preset or DEFAULT_BEAM_PRESET)


def solve_grid(points, axes, shape, directions=None, progress=None) -> list:
    """The grid's points (``shape``, over ``axes``) solved in this process: a list of one
    BeamSolution per direction (each line along frequency swept), or of one (each point
    from rest) where there is none; ``progress`` as for beam_sweep."""
    if not directions:
        solved = solve_beam(points)
        if progress is not None:
            progress(1, 1, f"{len(points)} points")
        return [solved]
    return [_swept(points, axes, shape, d, progress, (k, len(directions)))
            for k, d in enumerate(directions)]


def _swept(points, axes, shape, direction, progress=None, part=(0, 1)) -> BeamSolution:
    """The grid solved line by line along frequency in ``direction``; ``progress`` told
    after each step (of ``part`` = (index, count) of the directions run)."""
    names = list(axes)
    f_axis = names.index("frequency")
    grid = np.arange(len(points)).reshape(shape)
    lines = np.moveaxis(grid, f_axis, -1).reshape(-1, shape[f_axis])
    # up: rising frequency, down: falling, whatever the axis's order
    rising = np.argsort(np.asarray(axes["frequency"], dtype=float), kind="stable")
    order = [int(k) for k in (rising if direction == "up" else rising[::-1])]
    out = None
    ends = {}
    for k in order:
        ids = lines[:, k]
        starts = [ends.get(int(line)) for line in range(len(lines))]
        sol = solve_beam([points[i] for i in ids],
                    None if k == next(iter(order)) else starts)
        for line, end in enumerate(sol.ends):
            ends[line] = end
        if out is None:
            out = BeamSolution({n: np.empty((len(points),) + v.shape[1:])
                                for n, v in sol.values.items()},
                               [None] * len(points), None)
        for n, v in sol.values.items():
            out.values[n][ids] = v
        for i, end in zip(ids, sol.ends):
            out.ends[int(i)] = end
        if progress is not None:
            count = shape[f_axis]
            done = part[0] * count + list(order).index(k) + 1
            progress(done, part[1] * count, f"{direction} sweep, frequency = "
                     f"{points[ids[0]]['frequency']:g} Hz, {len(ids)} line(s)")
    return out


def _dataset(solved: list, axes: dict, directions, first: dict, moving: bool,
             preset: str) -> xr.Dataset:
    """The CF dataset of a grid solved: ``solved`` one dict of outputs (as
    BeamSolution.values, over the points in the order of itertools.product of ``axes``)
    per direction, or one where there is none; ``first`` the grid's first point (its
    parameters not on an axis are the file's attributes); ``moving``: whether any point's
    stop moves (else the stop face's metric is absent, not NaN)."""
    shape = [len(v) for v in axes.values()]
    parts = [_variables(values, axes, shape, moving) for values in solved]
    if not directions:
        ds = parts[0]
    else:
        ds = xr.concat(parts, dim=xr.DataArray(list(directions), dims="direction",
                                               name="direction"))
        ds["direction"].attrs = {"long_name": "direction of the frequency sweep",
                                 "units": "1"}
    return _attributes(ds, first, preset)


def _variables(values: dict, axes, shape, moving) -> xr.Dataset:
    """One direction's outputs on the grid, with the axes and modes as coordinates."""
    coords = {name: (name, np.asarray(v), {"units": _unit(name),
                                           "long_name": BEAM_PARAMETERS[name].description})
              for name, v in axes.items()}
    data = {}
    for name, v in values.items():
        o = OUTPUTS[name]
        if o.dims:  # (the modes, the multipliers)
            data[name] = (list(axes) + list(o.dims), v.reshape(shape + [v.shape[-1]]),
                          o.attrs)
        else:
            dtype = o.dtype if name != "status" else "int8"
            arr = v.reshape(shape)
            if np.issubdtype(np.dtype(dtype), np.integer):
                arr = np.nan_to_num(arr, nan=-1).astype(dtype)
            data[name] = (list(axes), arr, o.attrs)
    ds = xr.Dataset(data, coords=coords)
    ds = ds.assign_coords(_mode_coordinate(ds.sizes["mode"]))
    if "multiplier" in ds.dims:
        ds = ds.assign_coords(multiplier_coordinate(ds.sizes["multiplier"]))
    if "status" in ds:
        ds["status"].attrs.update(STATUS_FLAGS)
    if not moving:  # a metric the model lacks: absent, not NaN
        ds = ds.drop_vars("stop_face_max")
    return ds


def _mode_coordinate(n: int) -> dict:
    """The coordinate of the modal amplitudes (dims ("mode",)): modes 1 to n."""
    return {"mode": ("mode", np.arange(1, n + 1),
                     {"units": "1", "long_name": "bending mode number"})}


def _unit(name: str) -> str:
    """The CF unit of a beam parameter."""
    return BEAM_PARAMETERS[name].unit


def _attributes(ds: xr.Dataset, p: dict, preset: str) -> xr.Dataset:
    ds.attrs.update({
        "Conventions": "CF-1.8", "title": "harvester_sweep steady states of the beam model",
        "source": f"harvester_sweep {__version__} modal engine", "model": "beam",
        "preset": preset, "notes": "; ".join(BEAM_PRESET_NOTES.get(preset, [])),
    })
    for name, value in p.items():
        if name not in ds.coords and value is not None:
            ds.attrs[f"parameter_{name}"] = value if not isinstance(value, bool) else int(value)
    return ds


def beam_scene(preset: str | None = DEFAULT_BEAM_PRESET, periods: int = 2,
               **overrides) -> tuple[dict, xr.Dataset]:
    """One beam point to steady state, then ``periods`` forcing periods of its orbit
    recorded at every grid step, contact sub-step and switch (none where it diverged):
    (its outputs, a CF dataset of the time history: time [s], tip and contact
    displacement [m], voltage [V], power [W], contact force [N], root strain [-], rod face
    [m]; with the outputs, the preset and the parameters, as ``beam-scene --output``
    writes it)."""
    p = resolve_beam_parameters(preset, **overrides)
    sol = solve_beam([p])
    bs = system_of(p)
    steps = int(sol.values["steps_per_period"][0])
    pk = pack_beam(p, bs, steps, float(sol.values["contact_step"][0]))
    S = len(bs.system.surfaces)
    names = bs.system.output_names
    rec = np.empty((0, 1 + S + len(names)))  # (a diverged point has no orbit to record)
    rows = periods * (steps + 4096) + 16  # (grown until the record fits: never cut short)
    while sol.values["status"][0] != _DIVERGED:
        rec = modal_map.record_motion(pk, sol.ends[0], periods, rows)
        if len(rec) < rows:
            break
        rows *= 4
    col = {name: 1 + S + k for k, name in enumerate(names)}
    t = rec[:, 0] - (rec[0, 0] if len(rec) else 0.0)  # (from the orbit's start)
    series = xr.Dataset(
        {"tip_displacement": ("time", rec[:, col["tip_displacement"]],
                              {"units": "m", "long_name": "tip displacement relative to the "
                               "base"}),
         "contact_displacement": ("time", rec[:, col["contact_displacement"]],
                                  {"units": "m", "long_name": "displacement at the contact "
                                   "position"}),
         "voltage": ("time", rec[:, col["voltage"]],
                     {"units": "V", "long_name": "voltage across the load"}),
         "instantaneous_power": ("time", rec[:, col["voltage"]] ** 2 / p["resistance"],
                                 {"units": "W", "long_name": "instantaneous power V^2/R"}),
         "contact_force": ("time", rec[:, 1:1 + S].sum(axis=1) if S == 1 else
                           rec[:, 1] - rec[:, 2],
                           {"units": "N", "long_name": "contact force: the upper stop's "
                            "positive, a lower stop's negative"}),
         "root_strain": ("time", rec[:, col["root_strain"]],
                         {"units": "1", "long_name": "bending strain at the root's outer "
                          "piezo surface"}),
         "stop_face": ("time", rec[:, col["stop_face"]],
                       {"units": "m", "long_name": "rod stop's face displacement"})},
        coords={"time": ("time", t, {"units": "s", "long_name": "time from the orbit's "
                                     "start"})})
    if not moving_stop(p):
        series = series.drop_vars("stop_face")
    outputs = {name: sol.values[name][0] for name in SCALARS}
    outputs["modal_amplitude"] = sol.values["modal_amplitude"][0]
    return outputs, _scene_dataset(series, outputs, p, preset or DEFAULT_BEAM_PRESET)


def _scene_dataset(series: xr.Dataset, outputs: dict, p: dict, preset: str) -> xr.Dataset:
    """A scene's time history with what its file needs to stand alone: its outputs as
    variables (CF attributes from outputs.OUTPUTS; a metric the model lacks absent, not
    NaN), the preset and the parameters."""
    for name, value in outputs.items():
        o = OUTPUTS[name]
        if name == "stop_face_max" and not moving_stop(p):
            continue
        if name == "modal_amplitude":
            series[name] = ("mode", np.ravel(value), o.attrs)
            continue
        dtype = o.dtype if name != "status" else "int8"
        if np.issubdtype(np.dtype(dtype), np.integer):
            value = np.nan_to_num(value, nan=-1)
        series[name] = ((), np.asarray(value).astype(dtype), o.attrs)
    series["status"].attrs.update(STATUS_FLAGS)
    series = series.assign_coords(_mode_coordinate(series.sizes["mode"]))
    series.attrs.update({"title": "harvester_sweep: a beam orbit's time history",
                         "model": "beam", "Conventions": "CF-1.8", "preset": preset})
    series.attrs.update({f"parameter_{name}": value if not isinstance(value, bool)
                         else int(value) for name, value in p.items() if value is not None})
    return series


__all__ = ["BeamSolution", "beam_scene", "beam_sweep", "solve_beam"]
