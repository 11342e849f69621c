"""Shared helpers of the tests: independent references written from the model's equations
(docs/model.md), not from the package, and sweep helpers.

- ``phasor``: closed-form steady state of the linear harvester (no stop);
- ``Reference``: the same equations integrated by SciPy's ``solve_ivp`` at tight tolerance,
  restarted exactly at each contact onset and separation so that no step straddles the
  switch, with quadratures for the energy terms.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar


def phasor(mass, natural_frequency, damping_ratio, coupling, capacitance, resistance,
           amplitude, frequency, base_forcing_factor=1.0, **_):
    """Complex amplitudes (X [m], V [V]) of the linear steady state x = Im(X e^{j w t}) of
    m x'' + c x' + k x - theta V = m mu_1 A sin(w t), C_p V' + V / R + theta x' = 0."""
    wn = 2 * math.pi * natural_frequency
    w = 2 * math.pi * frequency
    k, c = mass * wn**2, 2 * damping_ratio * mass * wn
    electrical = 1j * w * coupling**2 * resistance / (1 + 1j * w * resistance * capacitance)
    X = mass * base_forcing_factor * amplitude / (k - mass * w**2 + 1j * w * c + electrical)
    V = -1j * w * coupling * resistance * X / (1 + 1j * w * resistance * capacitance)
    return X, V


def beam(p):
    """The beam's mass m [kg], stiffness k [N/m], damping c [N s/m] and the forcing's
    angular frequency w [rad/s] of parameter set ``p``."""
    wn = 2 * math.pi * p["natural_frequency"]
    return (p["mass"], p["mass"] * wn**2, 2 * p["damping_ratio"] * p["mass"] * wn,
            2 * math.pi * p["frequency"])


def lankarani_nikravesh_damping(restitution, impact_velocity):
    """c_h = 3 (1 - e^2) / (4 v_imp) [s/m]."""
    return 3 * (1 - restitution**2) / (4 * impact_velocity)


class Reference:
    """SciPy integration of m x'' + c x' + k x + F_c - theta V = m mu_1 A sin(w t),
    C_p V' + V/R + theta x' = 0, with F_c = max(k_h (x-g)^1.5 (1 + c_h x'), 0) in contact.

    The state carries five quadratures: int V^2 dt, and the work of the base forcing,
    the mechanical damping, the contact force and the load, each in J.
    """

    def __init__(self, p, rtol=1e-12, atol_scale=1e-14, method="DOP853"):
        self.p = p
        wn = 2 * math.pi * p["natural_frequency"]
        self.m = p["mass"]
        self.k = self.m * wn**2
        self.c = 2 * p["damping_ratio"] * self.m * wn
        self.w = 2 * math.pi * p["frequency"]
        self.ch = (p["contact_damping"] if p.get("contact_damping") is not None
                   else lankarani_nikravesh_damping(p["restitution"], p["impact_velocity"]))
        self.rtol = rtol
        self.method = method
        self.atol_scale = atol_scale
        self.onset_velocities = []

    def contact_force(self, x, v):
        p = self.p
        delta = x - p["gap"]
        if delta <= 0:
            return 0.0
        return max(p["hertz_stiffness"] * delta**1.5 * (1 + self.ch * v), 0.0)

    def rhs(self, t, y, in_contact):
        p = self.p
        x, v, V = y[0], y[1], y[2]
        fc = self.contact_force(x, v) if in_contact else 0.0
        forcing = self.m * p.get("base_forcing_factor", 1.0) * p["amplitude"] * math.sin(
            self.w * t)
        a = (forcing - self.c * v - self.k * x - fc + p["coupling"] * V) / self.m
        dV = -(V / p["resistance"] + p["coupling"] * v) / p["capacitance"]
        return [v, a, dV, V * V, forcing * v, self.c * v * v, fc * v, V * V / p["resistance"]]

    def integrate(self, y0, t0, t1, dense=False):
        """State (x, v, V) and quadratures at t1 from (x, v, V) at t0; optionally the pieces."""
        p = self.p
        y = np.concatenate([np.asarray(y0, float)[:3], np.zeros(5)])
        scale = np.array([abs(p["gap"]) + 1e-6, 1e-3, 1e-3 * max(p["coupling"] / 4e-7, 1e-3),
                          1e-9, 1e-9, 1e-9, 1e-9, 1e-9])
        atol = self.atol_scale * scale
        t = t0
        pieces = []
        in_contact = bool(y[0] > p["gap"])
        while t < t1:
            def switch(t, y, *_):
                return y[0] - p["gap"]

            switch.terminal = True
            switch.direction = -1.0 if in_contact else 1.0
            sol = solve_ivp(self.rhs, (t, t1), y, method=self.method, rtol=self.rtol, atol=atol,
                            events=switch, args=(in_contact,), dense_output=dense)
            if dense:
                pieces.append((sol, in_contact))
            if sol.status == 1:  # stopped on the switch: restart on the other side of it
                t, y = sol.t_events[0][0], sol.y_events[0][0].copy()
                if not in_contact:
                    self.onset_velocities.append(y[1])
                in_contact = not in_contact
            else:
                t, y = t1, sol.y[:, -1]
        return y, pieces


def dense_extreme(values, of, pieces, t, k=None):
    """The largest value of ``of(y)`` (y a state of the dense output: a force [N], a
    displacement [m], a voltage [V]) around the sample k of times ``t`` [s] (unset: the
    largest of ``values``, ``of`` at those times), searched on the dense output of each
    piece of a run that holds t[k - 1] ... t[k + 1] (SciPy's bounded scalar minimiser, to
    1e-15 of the run): samples alone fall a few 1e-6 short of a contact force's peak that
    lasts a thirtieth of the period, up to 1e-7 of a swing's top."""
    k = int(np.argmax(values)) if k is None else int(k)
    best = float(values[k])
    for sol in pieces:
        lo, hi = max(t[max(k - 1, 0)], sol.t[0]), min(t[min(k + 1, t.size - 1)], sol.t[-1])
        if lo < hi:
            found = minimize_scalar(lambda s, sol=sol: -of(sol.sol(s)), bounds=(lo, hi),
                                    method="bounded", options={"xatol": 1e-15 * t[-1]})
            best = max(best, -float(found.fun))
    return best


def reference_orbit(result, periods_to_settle=40, method="DOP853", rtol=1e-12):
    """Settle the reference from the engine's state, then measure one period densely."""
    p = result.parameters
    T = 1.0 / p["frequency"]
    ref = Reference(p, rtol=rtol, method=method)
    y, _ = ref.integrate(result.state, 0.0, periods_to_settle * T)
    start = y[:3].copy()
    ref.onset_velocities.clear()
    end, pieces = ref.integrate(start, 0.0, T, dense=True)
    t = np.linspace(0.0, T, 40001)
    samples = np.full((3, t.size), np.nan)
    for sol, _ in pieces:
        inside = (t >= sol.t[0]) & (t <= sol.t[-1])
        samples[:, inside] = sol.sol(t[inside])[:3]
    force = np.array([ref.contact_force(x, v) for x, v in samples[:2].T])
    sols = [sol for sol, _ in pieces]
    return {
        "start": start,
        "end": end[:3],
        "v_rms": math.sqrt(end[3] / T),
        "power": end[3] / T / p["resistance"],
        "v_peak": dense_extreme(np.abs(samples[2]), lambda y: abs(y[2]), sols, t),
        "x_max": dense_extreme(samples[0], lambda y: y[0], sols, t),
        "x_min": -dense_extreme(-samples[0], lambda y: -y[0], sols, t),
        "contact_force_max": dense_extreme(force, lambda y: ref.contact_force(y[0], y[1]),
                                           sols, t),
        "approach_velocity": float(np.mean(ref.onset_velocities)),
        "approach_velocity_min": float(np.min(ref.onset_velocities)),
        "impacts_per_period": len(ref.onset_velocities),
    }


FAST = {"steps_per_period": 256, "max_periods": 2000}


def secant(function, a, b, y, iterations=6):
    """The root of ``function(value, y) -> (residual, y, extra)`` by the secant method from
    ``a`` and ``b`` (both first evaluated from ``y``), each call's ``y`` (an orbit's state:
    a Newton guess) handed to the next; stops at 1e-10 of the value. Returns the last value
    and its ``extra`` (a reference's monodromy there)."""
    (fa, _, _), (fb, y, extra) = function(a, y), function(b, y)
    for _ in range(iterations):
        c = b - fb * (b - a) / (fb - fa)
        (fc, y, extra), a, fa = function(c, y), b, fb
        b, fb = c, fc
        if abs(b - a) < 1e-10 * abs(b):
            break
    return b, extra


def spec(grid, parameters=None, **options):
    """A sweep of the paper scene over ``grid`` at a fixed, fast step."""
    return {"preset": "paper", "parameters": {**FAST, **(parameters or {})}, "grid": grid,
            "sweep": options}


def assert_same_bits(a: xr.Dataset, b: xr.Dataset) -> None:
    """Same variables, coordinates and dims, every value identical bit for bit."""
    assert set(a.variables) == set(b.variables)
    for name in a.variables:
        assert a[name].dims == b[name].dims, name
        assert a[name].dtype == b[name].dtype, name
        assert a[name].values.tobytes() == b[name].values.tobytes(), name


def period_map_jacobian(p, y, periods=1, rel_step=3e-5, rtol=1e-12):
    """The reference's period map ``F: y(0) -> y(periods T)`` from forcing phase 0, and its
    Jacobian (the monodromy matrix) by central differences.

    Returns ``(F(y), J, scale)``: ``scale`` holds each component's largest magnitude on the
    unperturbed trajectory (dense output, 20001 samples), and column ``j`` of ``J`` uses the
    step ``rel_step * scale[j]``. The central difference's truncation error is of order
    ``rel_step^2`` times the squared ratio of the amplitude to the Hertz penetration (~10
    at Table 1); the integration's error, smooth in ``y`` between the restarts at the
    switches, enters divided by ``rel_step``. Between ``rel_step`` 1e-5 and 1e-4 the
    eigenvalues of ``J`` agree to ~1e-9 at both presets (rtol 1e-11 to 1e-13)."""
    y = np.asarray(y, float)[:3]
    t1 = periods / p["frequency"]
    image, pieces = Reference(p, rtol=rtol).integrate(y, 0.0, t1, dense=True)
    t = np.linspace(0.0, t1, 20001)
    scale = np.zeros(3)
    for sol, _ in pieces:
        inside = t[(t >= sol.t[0]) & (t <= sol.t[-1])]
        if inside.size:
            scale = np.maximum(scale, np.abs(sol.sol(inside)[:3]).max(axis=1))
    jacobian = np.empty((3, 3))
    for j in range(3):
        step = np.zeros(3)
        step[j] = rel_step * scale[j]
        ahead = Reference(p, rtol=rtol).integrate(y + step, 0.0, t1)[0][:3]
        behind = Reference(p, rtol=rtol).integrate(y - step, 0.0, t1)[0][:3]
        jacobian[:, j] = (ahead - behind) / (2 * step[j])
    return image[:3], jacobian, scale
