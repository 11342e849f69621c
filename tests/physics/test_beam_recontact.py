"""A touch that starts and ends inside one grid step of the modal engine (issue 43): a rod
stop ringing faster than the grid taps the beam between two grid times, where the
penetration is negative at both ends of the step and its rate has the same sign at both.
The engine's period map against SciPy (DOP853, restarted at every switch of the force) on
the same modal equations, and against itself on a grid 1024 times finer."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from harvester_sweep import modal_map
from harvester_sweep._engine.modal import kernel
from harvester_sweep.beam_packing import first_steps, pack_beam
from harvester_sweep.beam_parameters import resolve_beam_parameters
from harvester_sweep.beam_runs import system_of
from harvester_sweep.modal_map import ModalPoint

#: The rod face's ringing [m] (the gap is 1 um), and the grid: a 140 Hz period in 64 steps
#: of 112 us, each 3.5 cycles of the rod's 32 kHz mode.
RINGING = 1e-7
STEPS = 64


def _case():
    """The one-mode beam against a one-mode rod (mak_rod's), the beam held at rest half the
    ringing short of the face's rest position and the face displaced by the ringing's
    amplitude: the face comes back at the beam once each rod cycle, for a few microseconds
    each time, well inside a grid step."""
    p = resolve_beam_parameters("mak_rod", n_modes=1, rod_modes=1, steps_per_period=STEPS,
                                max_periods=1)
    bs = system_of(p)
    surface = bs.system.surfaces[0]
    phi, face = surface[0], -surface[3]  # (eta_1, eta_1', V, q_1, q_1')
    y0 = np.zeros(5)
    y0[0] = (p["gap"] - 0.5 * RINGING) / phi
    y0[3] = RINGING / face
    return p, bs, y0


def _reference(p, bs, y0, periods, rtol=1e-11):
    """The modal equations from y0 over ``periods`` forcing periods by DOP853, restarted at
    every switch of the force (touch, separation, the damping law's clip): (the state at
    each period's end, touches in the last period, mean power over the last period [W])."""
    sysm, A, w = bs.system, p["amplitude"], 2 * math.pi * p["frequency"]
    kh, ch = p["hertz_stiffness"], bs.contact_damping
    M, f, C, g, B = sysm.matrix, sysm.forcing, sysm.surfaces, sysm.gaps, sysm.inputs
    out_v = sysm.outputs[list(sysm.output_names).index("voltage")]
    T = 2 * math.pi / w

    def pushing(y):
        d, r = C @ y - g, C @ (M @ y)
        return (d > 0) & (1 + ch * r > 0)

    def rhs(t, y, on):
        yy = y[:-1]
        d, r = C @ yy - g, C @ (M @ yy)
        F = np.where(on, kh * np.maximum(d, 0) ** 1.5 * np.maximum(1 + ch * r, 0), 0.0)
        return np.append(M @ yy + f * A * math.sin(w * t) + B.T @ F, (out_v @ yy) ** 2)

    events = []
    for s in range(len(g)):
        def touch(t, y, on, s=s):
            return C[s] @ y[:-1] - g[s]

        def clip(t, y, on, s=s):
            return 1 + ch * (C[s] @ (M @ y[:-1]))
        for ev in (touch, clip):
            ev.terminal = True
            events.append(ev)
    atol = np.append(1e-13 * bs.scale, 1e-30)
    t, y, on = 0.0, np.append(y0, 0.0), pushing(y0)
    touches, energy_start, ends = 0, None, []
    for k in range(1, periods + 1):
        if k == periods:
            touches, energy_start = 0, y[-1]
        while t < k * T:
            res = solve_ivp(rhs, (t, k * T), y, method="DOP853", rtol=rtol, atol=atol,
                            events=events, args=(on,))
            t, y = res.t[-1], res.y[:, -1]
            if res.status == 1:
                # the side the motion goes on to: a tiny Euler step ahead, then a step clear
                # of the switch (where its event would fire again at once)
                nudge = 1e-10 * T
                was = on
                on = pushing((y + nudge * rhs(t, y, on))[:-1])
                touches += int(np.sum(on & ~was & (C @ y[:-1] - g <= 1e-9 * p["gap"])))
                step = solve_ivp(rhs, (t, min(t + nudge, k * T)), y, method="DOP853",
                                 rtol=rtol, atol=atol, args=(on,))
                t, y = step.t[-1], step.y[:, -1]
        ends.append(y[:-1])
    return ends, touches, (y[-1] - energy_start) / T / p["resistance"]


def _engine(pk: ModalPoint, y0):
    """The engine from y0: its state after one period (the period map), and its booked
    impacts and mean power over the second period (a run of a one-period budget, not
    settled, is measured over the next period)."""
    (y1,), ok = modal_map.map_states([pk], y0[None], np.array([1]))
    assert ok.all()
    metrics, _, _ = modal_map.run([pk], y0[None])
    head = modal_map.modal.HEAD
    return y1, metrics[0, head.impacts], metrics[0, head.power]


def test_a_touch_inside_a_grid_step_is_found():
    """Every tap of the ringing face is found on a grid of 3.5 rod cycles a step. The
    period map and the next period's impacts and power agree with SciPy within the
    engine's own error estimate (the change from its first step choice to twice the grid
    and half the contact sub-step, as solve_beam takes it), and with the engine on a grid
    1024 times finer to rounding. Before the fix the coarse grid found 1 of the second
    period's 5 taps, its map was off by 9e-3 of the scales and its power by 24 %."""
    p, bs, y0 = _case()
    steps, sub = first_steps(p, bs)
    assert steps == STEPS
    first = _engine(pack_beam(p, bs, STEPS, sub), y0)
    finer = _engine(pack_beam(p, bs, 2 * STEPS, sub / 2), y0)
    # the same integrator on a grid that resolves the rod (1/290 of its cycle a step):
    # the same touches, located on the same exact flow
    fine = _engine(pack_beam(p, bs, 1024 * STEPS, sub), y0)
    assert np.abs((first[0] - fine[0]) / bs.scale).max() <= 1e-9
    assert first[1] == fine[1]
    ends, touches, power = _reference(p, bs, y0, 2)
    assert touches == 5
    assert first[1] == finer[1] == touches
    estimate = np.abs(finer[0] - first[0]) / bs.scale
    assert np.all(np.abs(finer[0] - ends[0]) / bs.scale <= estimate + 1e-12)
    assert abs(finer[2] - power) <= abs(finer[2] - first[2])
    assert abs(finer[2] - first[2]) <= 1e-4 * power


def test_a_steps_rise_above_its_ends_is_within_the_bound_the_engine_skips_by():
    """The engine searches a contact-free grid step for a touch its ends do not show (a
    peak of the penetration inside it, a tap of the ringing rod) only where the larger end
    value plus its bound on the rise above the chord (kernel._rise) reaches zero. Along
    the exact flow, sampled 4096 times a step in numpy, from random states of the beam
    against the five-mode rod (modes ringing many times a grid step), the penetration
    never exceeds that bound; and it does rise well above its ends, so a bound too small
    would be seen."""
    p = resolve_beam_parameters("mak_rod", rod_modes=5)
    bs = system_of(p)
    pk = pack_beam(p, bs, *first_steps(p, bs))
    D, S, K = pk.dims
    tables = kernel._tables(pk.crow, pk.rrow, D, S, K)
    lam, pen, pen_p, gap = tables[0], tables[2], tables[5], tables[8]
    omega = 2 * math.pi * p["frequency"]
    h = 2 * math.pi / omega / pk.rrow[1]
    assert np.abs(lam).max() * h > 4 * math.pi  # (the fastest mode: 2 cycles a step)
    tau = np.linspace(0.0, h, 4097)
    rng = np.random.default_rng(7)
    rises = []
    for _ in range(200):
        # each mode's share of the penetration about a gap, the start anywhere in a period
        z = (rng.normal(size=D) + 1j * rng.normal(size=D)) * gap[0] / np.abs(pen[0]) / D
        t0 = rng.uniform(0.0, 2 * math.pi / omega)
        d = ((pen[0] * z * np.exp(np.outer(tau, lam))).sum(axis=1).real
             + (pen_p[0] * np.exp(1j * omega * (t0 + tau))).imag - gap[0])
        ends = max(d[0], d[-1])
        bound = ends + kernel._rise(0, z, h, omega, lam, pen, pen_p, D)
        assert d.max() <= bound + 1e-12 * gap[0]
        rises.append((d.max() - ends) / gap[0])
    assert max(rises) > 0.1
