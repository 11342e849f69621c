"""Branches of the beam's periodic orbits through folds: pseudo-arclength continuation of
the fixed points of the modal engine's period map in one parameter.

The unknowns are the orbit's state at phase 0 (in units of each component's scale) and
the parameter (in units of the branch's range); the map and its derivatives (the
monodromy and the derivative in the parameter, by forward differences) come from the
engine's own period map (``modal_map.map_states``), at the step that meets ``accuracy``
at the branch's first point. Along the branch each bifurcation is located by
bisection of the arclength step where its test function changes sign: folds (the
tangent's parameter component), a period doubling (det(M + I)), Neimark-Sacker (a complex
pair's modulus less one), grazing (the orbit's reach past a stop).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from . import modal_map
from .beam_packing import pack_beam
from .beam_parameters import BEAM_PARAMETERS, DEFAULT_BEAM_PRESET, resolve_beam_parameters
from .beam_runs import PERTURBATION, point_outputs, solve_beam, system_of
from .outputs import BIFURCATION_FLAGS, BIFURCATIONS, OUTPUTS
from .parameters import ParameterError
from .version import __version__

#: Corrector iterations at most, and the largest correction (in scaled units) a step's
#: first iterate may make before the step is halved [-].
CORRECTOR = 8
MAX_CORRECTION = 0.3
#: Converged where the scaled residual is below this [-].
TOLERANCE = 1e-9
#: The outputs each branch point reports.
BRANCH_OUTPUTS = ("power", "v_peak", "x_max", "x_min", "root_strain_max",
                  "impacts_per_period", "contact_force_max")


class _Map:
    """The period map of a beam point as a function of the scaled state and parameter."""

    def __init__(self, p: dict, parameter: str, span: float, steps: int, substep: float):
        self.p, self.parameter, self.span = p, parameter, span
        self.steps, self.substep = steps, substep
        self.scale = system_of(p).scale
        self.D = len(self.scale)

    def point(self, value: float) -> dict:
        return resolve_beam_parameters(None, **{**_overrides(self.p),
                                                self.parameter: value})

    def packs(self, values):
        return [pack_beam(q, system_of(q), self.steps, self.substep)
                for q in (self.point(v) for v in values)]

    def residual_and_jacobian(self, u):
        """F(u) = (P(y) - y) / scale and dF/du (D, D + 1) at u = (y / scale, lambda / span)."""
        D, scale = self.D, self.scale
        y, lam = u[:D] * scale, u[D] * self.span
        h = PERTURBATION
        dlam = h * self.span
        packs = self.packs([lam] * (D + 1) + [lam + dlam])
        states = [y] + [y + h * scale[k] * np.eye(D)[k] for k in range(D)] + [y]
        ends, ok = modal_map.map_states(packs, states, np.ones(D + 2, dtype=np.int64))
        if not ok.all():
            raise FloatingPointError("the period map diverged")
        base = (ends[0] - y) / scale
        jac = np.empty((D, D + 1))
        jac[:, :D] = ((ends[1:D + 1] - ends[0]) / scale).T / h - np.eye(D)
        jac[:, D] = (ends[D + 1] - ends[0]) / scale / h
        return base, jac

    def outputs(self, u) -> dict:
        y, lam = u[:self.D] * self.scale, u[self.D] * self.span
        q = self.point(lam)
        # one period from the fixed point, then the orbit measured over the next: an
        # unstable orbit is left within a few periods, so the engine's settle test (which
        # would run on to the attractor) is not waited for
        pk = pack_beam(dict(q, max_periods=1), system_of(q), self.steps, self.substep)
        m, _, _ = modal_map.run([pk], [y])
        table, _ = point_outputs(q, system_of(q), m[0])
        return table


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
                 max_points: int) -> None:
    """Refuse, in one line, a branch's options out of their ranges."""
    if parameter not in BEAM_PARAMETERS or BEAM_PARAMETERS[parameter].kind != "float":
        raise ParameterError(f"parameter {parameter!r}: must be a real beam parameter")
    for value in (start, stop):
        BEAM_PARAMETERS[parameter].check(value)
    if not (isinstance(step, float) and 0 < step <= 0.2):
        raise ParameterError(f"step [-] = {step!r}: must be a number in (0, 0.2]")
    if isinstance(max_points, bool) or not isinstance(max_points, int) or max_points < 2:
        raise ParameterError(f"max_points [-] = {max_points!r}: must be an integer >= 2")


def continue_beam_branch(parameter: str, start: float, stop: float,
                         preset: str | None = DEFAULT_BEAM_PRESET, *, step: float = 0.01,
                         max_points: int = 400, **overrides) -> xr.Dataset:
    """The branch of periodic orbits (period one forcing period) of a beam point from
    ``parameter`` = ``start`` towards ``stop`` (SI units), through folds, by
    pseudo-arclength steps of ``step`` (in units of the range, halved where the corrector
    fails, up to twice that after easy steps). Returns a CF dataset over ``point``."""
    check_branch(parameter, start, stop, step, max_points)
    p = resolve_beam_parameters(preset, **overrides, **{parameter: start})
    first = solve_beam([p])
    if first.values["status"][0] != 0 or first.values["orbit_period"][0] != 1:
        raise ParameterError(f"{parameter} = {start:g}: the start has no settled orbit of "
                             "one forcing period to continue")
    span = float(stop - start)
    f = _Map(p, parameter, abs(span), int(first.values["steps_per_period"][0]),
             float(first.values["contact_step"][0]))
    direction = math.copysign(1.0, span)
    u = np.append(first.ends[0] / f.scale, start / f.span)
    u, jac = _correct(f, u, None, None)
    t = _tangent(jac)
    if t[-1] * direction < 0:
        t = -t
    points = [(u, jac, t, "none")]
    ds_step = step
    while len(points) < max_points:
        u0, _, t0, _ = points[-1]
        lam = u0[-1] * f.span
        if (lam - stop) * direction >= 0:
            break
        guess = u0 + ds_step * t0
        try:
            u1, jac1 = _correct(f, guess, t0, guess)
        except (ArithmeticError, np.linalg.LinAlgError):
            ds_step /= 2
            if ds_step < step * 1e-4:
                break
            continue
        t1 = _tangent(jac1, t0)
        found = []  # each bifurcation between the two points, located and marked there
        for test in _TESTS:
            if test(f, u0, points[-1][1], t0) * test(f, u1, jac1, t1) < 0:
                where, located = _locate(f, u0, t0, ds_step, test)
                if located is not None:
                    found.append((where, located + (_KINDS[test],)))
        points.extend(point for _, point in sorted(found, key=lambda item: item[0]))
        points.append((u1, jac1, t1, "none"))
        ds_step = min(ds_step * 1.5, 2 * step)
    return _dataset(f, points, parameter, preset)


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


def _locate(f: _Map, u0, t0, ds: float, test):
    """The point between u0 and u0 + ds along t0 where ``test`` changes sign, by
    bisection of the arclength step (each trial corrected onto the branch), to 1e-9 of
    the branch's range in the parameter: (its arclength from u0, the point), the point
    None where a trial fails."""
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
        if (hi - lo) * abs(t0[-1]) <= 1e-9 and (hi - lo) <= 1e-7:
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


def _dataset(f: _Map, points, parameter: str, preset) -> xr.Dataset:
    D = f.D
    n = len(points)
    values = np.array([u[D] * f.span for u, *_ in points])
    mult = [np.linalg.eigvals(jac[:, :D] + np.eye(D)) for _, jac, *_ in points]
    rho = np.array([np.abs(m).max() for m in mult])
    outputs = [f.outputs(u) for u, *_ in points]
    names = list(BIFURCATIONS)
    flags = np.array([names.index(kind) for *_, kind in points], dtype="i1")
    unit = BEAM_PARAMETERS[parameter].unit
    data = {parameter: (("point",), values, {"units": unit, "long_name":
                                             BEAM_PARAMETERS[parameter].description}),
            "spectral_radius": (("point",), rho, OUTPUTS["spectral_radius"].attrs),
            "stable": (("point",), (rho < 1).astype("i1"), OUTPUTS["stable"].attrs),
            "bifurcation": (("point",), flags, {**OUTPUTS["bifurcation"].attrs,
                                                **BIFURCATION_FLAGS})}
    for name in BRANCH_OUTPUTS:
        data[name] = (("point",), np.array([o[name] for o in outputs], dtype=float),
                      OUTPUTS[name].attrs)
    ds = xr.Dataset(data, coords={"point": ("point", np.arange(n),
                                            {"units": "1", "long_name": "branch point"})})
    ds.attrs.update({"Conventions": "CF-1.8", "model": "beam", "parameter": parameter,
                     "title": "harvester_sweep a branch of the beam model's orbits",
                     "source": f"harvester_sweep {__version__} modal engine",
                     "preset": preset or DEFAULT_BEAM_PRESET,
                     "steps_per_period": f.steps, "contact_step": f.substep})
    return ds
