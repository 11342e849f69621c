"""Branches of the beam's periodic orbits through folds: pseudo-arclength continuation of
the fixed points of the modal engine's period map in one parameter.

The unknowns are the orbit's state at phase 0 (in units of each component's scale) and
the parameter (in units of the branch's range); the map and its derivatives (the
monodromy and the derivative in the parameter, by finite differences) come from the
engine's own period map (``modal_map``), at the step that meets ``accuracy`` at the
branch's first point. Along the branch each bifurcation is located by bisection of the
arclength step where its test function changes sign: folds (the tangent's parameter
component), a period doubling (det(M + I)), Neimark-Sacker (a complex pair's modulus less
one), grazing (the orbit's reach past a stop). Then every point is brought to the step
that meets ``accuracy``, each bifurcation located again at twice its steps
(:func:`_accurate`; docs/numerics.md, "Branches of the beam").
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from . import modal_map
from .beam_packing import pack_beam
from .beam_parameters import BEAM_PARAMETERS, DEFAULT_BEAM_PRESET, resolve_beam_parameters
from .beam_runs import (
    MAX_LEVELS,
    PERTURBATION,
    point_outputs,
    relative_change,
    solve_beam,
    system_of,
)
from .continuation import NoOrbitError
from .datasets import multiplier_coordinate
from .outputs import BIFURCATION_FLAGS, BIFURCATIONS, OUTPUTS
from .parameters import ParameterError, is_number, whole_number
from .period_map import multiplier_shift, sorted_multipliers
from .version import __version__

#: Corrector iterations at most, and the largest correction (in scaled units) a step's
#: first iterate may make before the step is halved [-].
CORRECTOR = 8
MAX_CORRECTION = 0.3
#: Converged where the scaled residual is below this [-].
TOLERANCE = 1e-9
#: Central differences' step where a period doubling or Neimark-Sacker point is located
#: (its test reads the multipliers), relative to each component's scale and to the range
#: in the parameter [-]: the period map is smooth only up to its discretization (a state
#: moved by a rounding error can change where a contact sub-step falls), and at 1e-6 the
#: map's own jumps came into the monodromy, moving a doubling's location by 1e-7 of its
#: value from one step choice to the next. A fold or grazing (read from the tangent, near
#: the Hertz law's singular curvature at first touch) keeps PERTURBATION: at 1e-4 the
#: differences' truncation moved a fold beside a grazing by what changed its outputs 1e-5.
MULTIPLIER_PERTURBATION = 1e-4
#: Bisection locates a bifurcation to this width of scaled arclength [-] (so to this
#: fraction of the branch's range in the parameter, or better): at a fold the parameter
#: hardly changes along the branch but the orbit does, and its outputs are wanted to
#: the accuracy target too.
LOCATE = 1e-10
#: A located bifurcation is located again at twice the steps in a bracket along its
#: tangent this wide (scaled arclength), widened RELOCATE_GROWTH-fold up to
#: RELOCATE_TRIES times until its test function changes sign in it [-].
RELOCATE_WIDTH = 1e-5
RELOCATE_GROWTH = 8.0
RELOCATE_TRIES = 5
#: Orbits of at most this many forcing periods are followed past a period doubling [-].
MAX_PERIODS = 8
#: An orbit of 2p periods that comes back to within this of the scales after p periods is
#: the orbit of p periods it doubles [-].
SAME = 1e-6
#: The outputs each branch point reports.
BRANCH_OUTPUTS = ("power", "v_peak", "x_max", "x_min", "root_strain_max",
                  "impacts_per_period", "contact_force_max")


class _Map:
    """The period map of a beam point as a function of the scaled state and parameter;
    its derivatives by forward differences, or by central ones (``central``: twice the
    runs, the error of the derivatives about 1e-10 instead of 1e-6) where a bifurcation is
    located: its test functions read them."""

    def __init__(self, p: dict, parameter: str, span: float, steps: int, substep: float,
                 central: bool = False, periods: int = 1, perturbation: float = PERTURBATION):
        self.p, self.parameter, self.span = p, parameter, span
        self.steps, self.substep, self.central = steps, substep, central
        self.perturbation = perturbation
        self.periods = periods
        self.scale = system_of(p).scale
        self.D = len(self.scale)

    def point(self, value: float) -> dict:
        return resolve_beam_parameters(None, **{**_overrides(self.p),
                                                self.parameter: value})

    def packs(self, values):
        try:
            points = [self.point(v) for v in values]
        except ParameterError as error:  # (a corrector iterate beyond the parameter's range)
            raise ArithmeticError(str(error)) from None
        return [pack_beam(q, system_of(q), self.steps, self.substep) for q in points]

    def finer(self) -> _Map:
        """The same map at twice the grid steps and half the contact sub-step."""
        return _Map(self.p, self.parameter, self.span, 2 * self.steps, self.substep / 2,
                    self.central, self.periods, self.perturbation)

    def precise(self, test) -> _Map:
        """The same map with central differences, their step chosen for ``test``."""
        h = MULTIPLIER_PERTURBATION if test in (_doubling, _torus) else PERTURBATION
        return _Map(self.p, self.parameter, self.span, self.steps, self.substep, True,
                    self.periods, h)

    def doubled(self) -> _Map:
        """The map of twice the periods (the orbits born at a period doubling)."""
        return _Map(self.p, self.parameter, self.span, self.steps, self.substep, self.central,
                    2 * self.periods, self.perturbation)

    def residual_and_jacobian(self, u):
        """F(u) = (P(y) - y) / scale and dF/du (D, D + 1) at u = (y / scale, lambda / span)."""
        D, scale = self.D, self.scale
        y, lam = u[:D] * scale, u[D] * self.span
        h = self.perturbation
        sides = (1.0, -1.0) if self.central else (1.0,)
        here, *moved = self.packs([lam] + [lam + side * h * self.span for side in sides])
        monodromy, image, ok = modal_map.monodromies([here], y[None], [self.periods],
                                                     (h * scale)[None], central=self.central)
        shifted, ok_moved = modal_map.map_states(moved, np.repeat(y[None], len(moved), 0),
                                                 np.full(len(moved), self.periods))
        if not (ok.all() and ok_moved.all()):
            raise FloatingPointError("the period map diverged")
        jac = np.empty((D, D + 1))
        jac[:, :D] = monodromy[0] * scale[None, :] / scale[:, None] - np.eye(D)
        lower = shifted[1] if self.central else image[0]
        jac[:, D] = (shifted[0] - lower) / scale / (h * len(sides))
        return (image[0] - y) / scale, jac

    def outputs(self, u) -> dict:
        """The outputs of the orbit through u, measured over its periods from u (an
        unstable orbit is left within a few periods: the engine's settle test, which would
        run on to the attractor, is not waited for)."""
        y, lam = u[:self.D] * self.scale, u[self.D] * self.span
        q = self.point(lam)
        pk = pack_beam(q, system_of(q), self.steps, self.substep)
        m, _, _ = modal_map.measure([pk], [y], [self.periods])
        table, _ = point_outputs(q, system_of(q), m[0])
        return table

    def half_offset(self, u, v) -> float:
        """How far the orbit through u (of an even number of periods) is from coming back
        to itself after half its periods, along ``v`` (scaled): the doubled orbit's
        distance, signed, from the orbit it doubles. It changes sign where the branch of
        doubled orbits passes through that orbit (onto the same orbit shifted by half its
        periods)."""
        y = u[:self.D] * self.scale
        half, ok = modal_map.map_states(self.packs([u[self.D] * self.span]), y[None],
                                        [self.periods // 2])
        if not ok[0]:
            raise FloatingPointError("the period map diverged")
        return float(v @ ((half[0] - y) / self.scale))


def _overrides(p: dict) -> dict:
    return {k: v for k, v in p.items() if k in BEAM_PARAMETERS}


def _tangent(jac: np.ndarray, previous=None) -> np.ndarray:
    """The unit null vector of the (D, D + 1) Jacobian, oriented along ``previous``."""
    _, _, vt = np.linalg.svd(jac)
    t = vt[-1]
    if previous is not None and t @ previous < 0:
        t = -t
    elif previous is None and t[-1] < 0:
        t = -t
    return t


def check_branch(parameter: str, start: float, stop: float, step: float,
                 max_points: int) -> int:
    """Refuse, in one line, a branch's options out of their ranges; returns max_points as
    an int."""
    if parameter not in BEAM_PARAMETERS or BEAM_PARAMETERS[parameter].kind != "float":
        raise ParameterError(f"parameter {parameter!r}: must be a real beam parameter")
    for value in (start, stop):
        BEAM_PARAMETERS[parameter].check(value)
    if stop == start:
        unit = BEAM_PARAMETERS[parameter].unit
        raise ParameterError(f"stop [{unit}] = {stop!r}: must differ from start, the branch's "
                             "direction")
    if not (is_number(step) and 0 < step <= 0.2):
        raise ParameterError(f"step [-] = {step!r}: must be a number in (0, 0.2]")
    return whole_number("max_points", max_points, 2)


def continue_beam_branch(parameter: str, start: float, stop: float,
                         preset: str | None = DEFAULT_BEAM_PRESET, *, step: float = 0.01,
                         max_points: int = 400, period_doubling: str = "mark",
                         **overrides) -> xr.Dataset:
    """The branch of periodic orbits (period one forcing period) of a beam point from
    ``parameter`` = ``start`` towards ``stop`` (SI units), through folds, by
    pseudo-arclength steps of ``step`` (in units of the range, halved where the corrector
    fails, up to twice that after easy steps). ``period_doubling``: "mark" locates the
    doublings, "switch" also follows each doubled branch (orbits of twice the periods, up
    to MAX_PERIODS) within the range. Returns a CF dataset over ``point``, the branches
    one after another (``branch``, ``orbit_period``)."""
    max_points = check_branch(parameter, start, stop, step, max_points)
    if period_doubling not in ("mark", "switch"):
        raise ParameterError(f"period_doubling [-] = {period_doubling!r}: must be 'mark' or "
                             "'switch'")
    if parameter in overrides:
        raise ParameterError(f"{parameter}: continued, so it cannot also be fixed; give start "
                             "and stop instead")
    # (the stop must be a point of the model too, or the branch ends short of it unsaid)
    resolved = {}
    for end, value in (("stop", stop), ("start", start)):
        try:
            resolved[end] = resolve_beam_parameters(preset, **overrides, **{parameter: value})
        except ParameterError as error:
            raise ParameterError(f"{end}: {error}") from None
    p = resolved["start"]
    first = solve_beam([p])
    if first.values["status"][0] != 0 or first.values["orbit_period"][0] != 1:
        raise NoOrbitError(f"{parameter} = {start:g}: the start has no settled orbit of "
                           "one forcing period to continue")
    span = float(stop - start)
    f = _Map(p, parameter, abs(span), int(first.values["steps_per_period"][0]),
             float(first.values["contact_step"][0]))
    u = np.append(first.ends[0] / f.scale, start / f.span)
    u, jac = _correct(f, u, None, None)
    t = _tangent(jac)
    if t[-1] * span < 0:
        t = -t
    bounds = sorted((start / f.span, stop / f.span))
    branches = [(f, _follow(f, (u, jac, t, "none"), bounds, step, max_points)[0])]
    if period_doubling == "switch":
        met = set()  # (branch, point) of the doublings a doubled branch has ended at
        for b, (g, points) in enumerate(branches):  # (grows as doubled branches are found)
            doublings = [k for k, point in enumerate(points) if point[3] == "period_doubling"]
            for k in doublings if g.periods * 2 <= MAX_PERIODS else ():
                left = max_points - sum(len(part) for _, part in branches)
                start_v = None if (b, k) in met or left < 2 else _doubled_start(
                    g.doubled(), points[k][0], points[k][1], step)
                if start_v is None:
                    continue
                part, ended = _follow(g.doubled(), start_v[0], bounds, step, left,
                                      start_v[1])
                branches.append((g.doubled(), part))
                if ended:  # (at the doubling nearest its end: not followed again from there)
                    end = part[-1][0][-1]
                    met.add((b, min(doublings, key=lambda j: abs(points[j][0][-1] - end))))
    return _dataset(f, [[_accurate(g, *point, p["accuracy"]) for point in points]
                        for g, points in branches], parameter, preset)


def _follow(f: _Map, first, bounds, step: float, max_points: int, doubling=None) -> list:
    """A branch of f's fixed points from ``first`` (point, Jacobian, tangent, kind) until
    the parameter leaves ``bounds`` (scaled), the step fails below 1e-4 of ``step``, or
    ``max_points``; each bifurcation between two points located and put between them. A
    branch of doubled orbits (``doubling``: the doubling direction, scaled) ends where it
    meets the orbit it doubles (:meth:`_Map.half_offset` changes sign): beyond it, it
    would follow the same orbits again, shifted by half their periods. Returns (the
    points, whether it ended so)."""
    points = [first]
    side = None if doubling is None else np.sign(f.half_offset(first[0], doubling))
    ds_step = step
    while len(points) < max_points:
        u0, jac0, t0, _ = points[-1]
        if len(points) > 1 and not bounds[0] < u0[-1] < bounds[1]:
            break
        guess = u0 + ds_step * t0
        try:
            u1, jac1 = _correct(f, guess, t0, guess)
            crossed = side is not None and np.sign(f.half_offset(u1, doubling)) != side
        except (ArithmeticError, np.linalg.LinAlgError):
            ds_step /= 2
            if ds_step < step * 1e-4:
                break
            continue
        if crossed:
            return points, True
        t1 = _tangent(jac1, t0)
        found = []  # each bifurcation between the two points, located and marked there
        for test in _TESTS:
            if test(f, u0, jac0, t0) * test(f, u1, jac1, t1) < 0:
                where, located = _locate(f.precise(test), u0, t0, ds_step, test)
                if located is not None:
                    found.append((where, located + (_KINDS[test],)))
        points.extend(point for _, point in sorted(found, key=lambda item: item[0]))
        points.append((u1, jac1, t1, "none"))
        ds_step = min(ds_step * 1.5, 2 * step)
    return points, False


def _doubled_start(f: _Map, u, jac, step: float):
    """The first point of the doubled branch (on ``f``, twice the periods) born at the
    period doubling ``u`` (Jacobian ``jac`` of the map it doubles), and the doubling
    direction: the located point moved along the eigenvector of the multiplier nearest
    -1, corrected with that direction as its tangent. None where the correction fails or
    comes back to the orbit it doubles."""
    D = f.D
    mult, vectors = np.linalg.eig(jac[:, :D] + np.eye(D))
    v = vectors[:, np.argmin(np.abs(mult + 1))].real
    v /= np.linalg.norm(v)
    t = np.append(v, 0.0)
    for ds in (step, step / 4, step / 16):
        guess = u + ds * t
        try:
            u1, jac1 = _correct(f, guess, t, guess)
            offset = f.half_offset(u1, v)
        except (ArithmeticError, np.linalg.LinAlgError):
            continue
        if abs(offset) > SAME:
            return (u1, jac1, _tangent(jac1, t), "none"), v
    return None


def _fold(f, u, jac, t) -> float:
    """The tangent's parameter component: it changes sign at a fold."""
    return t[-1]


def _doubling(f, u, jac, t) -> float:
    """det(M + I) of the monodromy M: it changes sign where a multiplier passes -1."""
    return float(np.linalg.det(jac[:, :f.D] + 2 * np.eye(f.D)))


def _torus(f, u, jac, t) -> float:
    """The largest modulus of a complex pair of multipliers less one (-1 without a pair):
    it changes sign where the pair leaves the unit circle (Neimark-Sacker)."""
    mult = np.linalg.eigvals(jac[:, :f.D] + np.eye(f.D))
    pair = np.abs(mult[np.abs(mult.imag) > 1e-9])
    return float(pair.max() - 1) if len(pair) else -1.0


def _grazing(f, u, jac, t) -> float:
    """How far the orbit reaches past a stop at the contact point [m] (the upper's, or the
    lower's where that is further): it changes sign where impacts start or stop."""
    out = f.outputs(u)
    q = f.point(u[f.D] * f.span)
    reach = out["contact_displacement_max"] - q["gap"]
    if q["lower_gap"] is not None:
        reach = max(reach, -out["contact_displacement_min"] - q["lower_gap"])
    return float(reach)


_TESTS = (_fold, _doubling, _torus, _grazing)
#: The kind of bifurcation (outputs.BIFURCATIONS) where each test changes sign.
_KINDS = {_fold: "fold", _doubling: "period_doubling", _torus: "neimark_sacker",
          _grazing: "grazing"}
#: The test function of each kind of bifurcation.
_TEST_OF = {kind: test for test, kind in _KINDS.items()}


def _locate(f: _Map, u0, t0, ds: float, test):
    """The point between u0 and u0 + ds along t0 where ``test`` changes sign, by
    bisection of the arclength step (each trial corrected onto the branch), to LOCATE:
    (its arclength from u0, the point), the point None where a trial fails."""
    jac0 = f.residual_and_jacobian(u0)[1]
    sign0 = np.sign(test(f, u0, jac0, t0))
    lo, hi, best = 0.0, ds, None
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        guess = u0 + mid * t0
        try:
            um, jm = _correct(f, guess, t0, guess)
        except (ArithmeticError, np.linalg.LinAlgError):
            return mid, best
        tm = _tangent(jm, t0)
        best = (um, jm, tm)
        if np.sign(test(f, um, jm, tm)) == sign0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= LOCATE:
            break
    return mid, best


def _correct(f: _Map, u, t, guess):
    """Newton on F(u) = 0 with the arclength condition t . (u - guess) = 0 (none at the
    first point: the parameter held)."""
    u = np.array(u, dtype=float)
    D = f.D
    for k in range(CORRECTOR):
        res, jac = f.residual_and_jacobian(u)
        if np.abs(res).max() <= TOLERANCE and k > 0:
            return u, jac
        if t is None:
            delta = np.linalg.solve(jac[:, :D], -res)
            delta = np.append(delta, 0.0)
        else:
            A = np.vstack([jac, t])
            b = np.append(-res, -(t @ (u - guess)))
            delta = np.linalg.solve(A, b)
        if k == 0 and np.abs(delta).max() > MAX_CORRECTION:
            raise ArithmeticError("the predictor landed too far from the branch")
        u = u + delta
    res, jac = f.residual_and_jacobian(u)
    if np.abs(res).max() > 1e3 * TOLERANCE:
        raise ArithmeticError("the corrector did not converge")
    return u, jac


def _accurate(f: _Map, u, jac, t, kind: str, accuracy: float) -> dict:
    """A branch point (found on ``f``) at the step that meets ``accuracy``.

    A point that is not a bifurcation is corrected at twice its steps with the parameter
    held (normal to the branch where that fails), and again at twice those while its
    outputs change by more than ``accuracy``: its ``estimate`` is the last change, the
    outputs reported the finest's. A located bifurcation is located again at twice its
    steps: the change of its location is its ``shift`` and the change of its outputs its
    ``estimate``; while either exceeds ``accuracy`` (the shift relative to the location)
    the finer location is taken and located again at twice its steps. Returns the point's
    values as a dict; ``shift`` is NaN where no location at twice the steps was found,
    ``estimate`` NaN where no correction at twice the steps converged."""
    out, estimate, shift, mult_shift = f.outputs(u), math.nan, math.nan, None
    test = _TEST_OF.get(kind)
    best = None
    for level in range(MAX_LEVELS):
        g = f.finer()
        if test is not None:
            fine = _relocated(g.precise(test), u, t, test)
            if fine is None:
                break
            u2, jac2, t2 = fine
            shift = (u2[f.D] - u[f.D]) * f.span
            mult_shift = multiplier_shift(jac[:, :f.D] + np.eye(f.D),
                                          jac2[:, :f.D] + np.eye(f.D))
        else:
            t2 = t
            try:
                u2, jac2 = _correct(g, u, None, None)
            except (ArithmeticError, np.linalg.LinAlgError):
                try:
                    u2, jac2 = _correct(g, u, t, u)
                except (ArithmeticError, np.linalg.LinAlgError):
                    break
        out2 = g.outputs(u2)
        estimate = relative_change(out, out2)
        if test is None:  # (the finer point is reported, its change the estimate)
            f, u, jac, t, out = g, u2, jac2, t2, out2
            if estimate <= accuracy:
                break
            continue
        scale = abs(u[f.D] * f.span) or f.span
        error = max(estimate, abs(shift) / scale)
        if error <= accuracy or level == MAX_LEVELS - 1:
            break
        if best is not None and error >= best[-1]:  # (not converging: the best kept)
            f, u, jac, t, out, shift, mult_shift, estimate, _ = best
            break
        best = (f, u, jac, t, out, shift, mult_shift, estimate, error)
        # (the finer location, located again at twice its steps)
        f, u, jac, t, out = g, u2, jac2, t2, out2
        shift, mult_shift, estimate = math.nan, None, math.nan
    return {"value": u[f.D] * f.span, "outputs": out, "estimate": estimate,
            "steps": f.steps, "substep": f.substep, "periods": f.periods,
            "monodromy": jac[:, :f.D] + np.eye(f.D),
            "kind": kind, "shift": shift, "multiplier_shift": mult_shift}


def _relocated(f: _Map, u, t, test):
    """The bifurcation of ``test`` found at ``u`` (tangent ``t``) on a coarser map, located
    again on ``f``: bracketed along ``t`` (RELOCATE_WIDTH, widened until the test changes
    sign) and bisected (:func:`_locate`). (point, Jacobian, tangent), or None where no
    bracket or correction is found."""
    w = RELOCATE_WIDTH
    for _ in range(RELOCATE_TRIES):
        ends = []
        for side in (-1.0, 1.0):
            guess = u + side * w * t
            try:
                end, jac = _correct(f, guess, t, guess)
            except (ArithmeticError, np.linalg.LinAlgError):
                return None
            ends.append((end, jac, _tangent(jac, t)))
        (a, ja, ta), (b, jb, tb) = ends
        if test(f, a, ja, ta) * test(f, b, jb, tb) < 0:
            # (along a's own tangent: the bisection's sign is the test's at its start, and
            # a fold's test, the tangent's parameter component, is about 0 along t)
            return _locate(f, a, ta, float(ta @ (b - a)), test)[1]
        w *= RELOCATE_GROWTH
    return None


def _dataset(f: _Map, branches: list, parameter: str, preset) -> xr.Dataset:
    """The CF dataset over ``point`` of ``branches`` (each a list of the points of
    :func:`_accurate`), one after another."""
    points = [dict(pt, branch=b) for b, part in enumerate(branches) for pt in part]
    D, n = f.D, len(points)
    mult = sorted_multipliers(np.array([pt["monodromy"] for pt in points]))
    rho = np.abs(mult[:, 0])
    names = list(BIFURCATIONS)
    flags = np.array([names.index(pt["kind"]) for pt in points], dtype="i1")
    unit = BEAM_PARAMETERS[parameter].unit
    mult_shift = np.full((n, D), np.nan)
    for k, pt in enumerate(points):
        if pt["multiplier_shift"] is not None:
            mult_shift[k] = pt["multiplier_shift"]

    def column(key):
        return np.array([pt[key] for pt in points], dtype=float)

    data = {parameter: (("point",), column("value"), {
                "units": unit, "long_name": BEAM_PARAMETERS[parameter].description}),
            "spectral_radius": (("point",), rho, OUTPUTS["spectral_radius"].attrs),
            "floquet_multipliers_real": (("point", "multiplier"), mult.real,
                                         OUTPUTS["floquet_multipliers_real"].attrs),
            "floquet_multipliers_imag": (("point", "multiplier"), mult.imag,
                                         OUTPUTS["floquet_multipliers_imag"].attrs),
            "stable": (("point",), (rho < 1).astype("i1"), OUTPUTS["stable"].attrs),
            "bifurcation": (("point",), flags, {**OUTPUTS["bifurcation"].attrs,
                                                **BIFURCATION_FLAGS}),
            "branch": (("point",), column("branch").astype("i4"), OUTPUTS["branch"].attrs),
            "orbit_period": (("point",), column("periods").astype("i4"),
                             OUTPUTS["orbit_period"].attrs),
            "error_estimate": (("point",), column("estimate"), {
                **OUTPUTS["error_estimate"].attrs,
                "comment": "the change of power, v_peak, x_max, x_min, root_strain_max and "
                           "stop_face_max when the point is corrected again at twice its "
                           "steps with the parameter held (normal to the branch where that "
                           "fails, as at a fold); NaN where no correction at twice the steps "
                           "converged"}),
            "steps_per_period": (("point",), column("steps").astype("i8"),
                                 OUTPUTS["steps_per_period"].attrs),
            "contact_step": (("point",), column("substep"), OUTPUTS["contact_step"].attrs),
            f"{parameter}_shift": (("point",), column("shift"), {
                "units": unit,
                "long_name": f"change of a located bifurcation's {parameter} when it is "
                             "located again at twice its steps (its discretization error)",
                "comment": "NaN at points that are not located bifurcations, and where no "
                           "location at twice the steps was found"}),
            "floquet_multipliers_shift": (("point", "multiplier"), mult_shift, {
                "units": "1",
                "long_name": "change of each Floquet multiplier, |mu at twice the steps - "
                             "mu|, when a located bifurcation is located again at twice its "
                             "steps",
                "comment": "NaN at points that are not located bifurcations"})}
    for name in BRANCH_OUTPUTS:
        data[name] = (("point",), np.array([pt["outputs"][name] for pt in points],
                                           dtype=float), OUTPUTS[name].attrs)
    ds = xr.Dataset(data, coords={"point": ("point", np.arange(n),
                                            {"units": "1", "long_name": "branch point"}),
                                  **multiplier_coordinate(D)})
    ds.attrs.update({"Conventions": "CF-1.8", "model": "beam", "parameter": parameter,
                     "title": "harvester_sweep a branch of the beam model's orbits",
                     "source": f"harvester_sweep {__version__} modal engine",
                     "preset": preset or DEFAULT_BEAM_PRESET,
                     "accuracy": f.p["accuracy"]})
    return ds
