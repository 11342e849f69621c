"""The beam model run by the modal engine, against references written apart from it: the
modal phasor sum without contact, the tip-mass model for one mode at the tip, and SciPy
(DOP853, events at every switch of the contact force) on the same modal equations."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp

from harvester_sweep import bimorph as bm
from harvester_sweep import modal_map, run_scene
from harvester_sweep import rod as rd
from harvester_sweep._engine import STATUS
from harvester_sweep.beam_packing import (
    contact_duration,
    contact_step_bound,
    first_steps,
    pack_beam,
)
from harvester_sweep.beam_parameters import bimorph, resolve_beam_parameters
from harvester_sweep.beam_runs import beam_scene, solve_beam, system_of
from harvester_sweep.models import beam as beam_model
from harvester_sweep.parameters import StabilityWarning


def _solve(preset="bimorph_tip", **overrides):
    p = resolve_beam_parameters(preset, **overrides)
    return p, solve_beam([p])


@pytest.mark.parametrize("n_modes, position, ratios", [(5, None, None),
                                                       (3, 0.6, (0.01, 0.03, 0.002))])
def test_without_contact_the_beam_is_its_modal_phasor_sum(n_modes, position, ratios):
    """Clear of the stop the engine's flow is exact: the orbit is the modal phasor sum
    (bimorph.modal_response, written from the modal equations apart from the engine),
    with one damping ratio for all modes or one per mode."""
    over = dict(gap=1e-2, n_modes=n_modes, frequency=170.0, mode_damping_ratios=ratios)
    if position is not None:
        over["contact_position"] = position * resolve_beam_parameters()["length"]
    p, sol = _solve(**over)
    W, V = bm.modal_response(bimorph(p), p["frequency"], p["resistance"], n_modes=n_modes,
                             damping_ratio=p["damping_ratio"] if ratios is None else ratios,
                             amplitude=p["amplitude"])
    v = sol.values
    assert v["status"][0] == 0 and v["impacts_per_period"][0] == 0
    assert v["x_max"][0] == pytest.approx(abs(W), rel=1e-9)
    assert v["x_min"][0] == pytest.approx(-abs(W), rel=1e-9)
    assert v["v_peak"][0] == pytest.approx(abs(V), rel=1e-9)
    assert v["power"][0] == pytest.approx(abs(V) ** 2 / (2 * p["resistance"]), rel=1e-9)


@pytest.mark.parametrize("lower_gap", [None, 5e-7])
def test_a_stop_of_no_stiffness_is_no_stop(lower_gap):
    """hertz_stiffness 0 is no stop (the parameter table's word), as for the tip mass: at
    the preset's 1-um gap, far inside the motion near resonance, the orbit is the modal
    phasor sum and no impact is counted (it raised ZeroDivisionError estimating the
    contact's duration)."""
    p, sol = _solve(hertz_stiffness=0.0, frequency=150.0, lower_gap=lower_gap)
    W, V = bm.modal_response(bimorph(p), p["frequency"], p["resistance"],
                             n_modes=p["n_modes"], damping_ratio=p["damping_ratio"],
                             amplitude=p["amplitude"])
    v = sol.values
    assert abs(W) > 5 * p["gap"]  # (the stop would be struck, were it one)
    assert v["status"][0] == 0 and v["impacts_per_period"][0] == 0
    assert v["x_max"][0] == pytest.approx(abs(W), rel=1e-9)
    assert v["v_peak"][0] == pytest.approx(abs(V), rel=1e-9)


@pytest.mark.parametrize("length", [1e-6, 1e-9])
def test_a_beam_whose_modes_ask_too_many_steps_is_refused_in_one_line(length):
    """A micrometre beam's first mode asks 3e7 grid steps a period: refused before any
    integration, naming the limit (it ran for minutes in 13 GB and reported 6.7e7 steps,
    or ended in a numba MemoryError traceback)."""
    from harvester_sweep.parameters import TooStiffError

    p = resolve_beam_parameters("bimorph_tip", n_modes=1, length=length)
    with pytest.raises(TooStiffError, match=r"^too stiff: the beam's mode 1, at .* Hz, asks "
                       r".* beyond the 1e\+07 steps_per_period \[-\] allows"):
        solve_beam([p])


@pytest.mark.parametrize("overrides, words", [
    (dict(contact_step=1e-10), "contact_step [s] = 1e-10 asks 7.14e+07 RK4 sub-steps"),
    (dict(contact_step=1e-300), "contact_step [s] = 1e-300 asks 7.14e+297 RK4 sub-steps"),
    (dict(hertz_stiffness=1e40), "the contact, estimated to last"),
])
def test_a_contact_step_too_short_to_run_is_refused_in_one_line(overrides, words):
    """A contact sub-step of 1e-10 s at 140 Hz is 7e7 RK4 steps a period in contact, more
    than steps_per_period's range allows the grid: refused before any integration (1e-10
    ran past a minute, 1e-300 without end and deaf to Ctrl-C)."""
    from harvester_sweep.parameters import TooStiffError

    p = resolve_beam_parameters("bimorph_tip", n_modes=1, **overrides)
    with pytest.raises(TooStiffError) as info:
        solve_beam([p])
    assert str(info.value).startswith(f"too stiff: {words}") and "\n" not in str(info.value)


@pytest.mark.parametrize("preset, overrides, rate", [
    ("bimorph_tip", dict(n_modes=1, frequency=220.0), "stiffness"),
    ("mak_rod", dict(frequency=150.0), "damping")])
def test_a_contact_step_beyond_rk4s_bound_is_warned_of(preset, overrides, rate):
    """A contact sub-step beyond RK4's stability bound at the expected impact warns, naming
    the rate that sets the bound, as an explicit tip-mass step does; the automatic one,
    and one within the bound, do not. At mak_rod's 150 Hz the bound (set by the contact's
    damping) is a fifth of the contact's duration: a sub-step of half the duration left the
    point unsettled, one of twice it diverged."""
    p = resolve_beam_parameters(preset, **overrides)
    bs = system_of(p)
    bound, what = contact_step_bound(p, bs)
    assert what == f"the contact's {rate}" and bound < contact_duration(p, bs)
    with pytest.warns(StabilityWarning, match=r"contact_step = .* s is beyond the estimated "
                      r"RK4 stability bound 2.5/rate = .* s of the contact's " + rate):
        first_steps(resolve_beam_parameters(preset, contact_step=1.5 * bound, **overrides), bs)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert first_steps(p, bs)[1] < bound / 10  # (the automatic sub-step)
        first_steps(resolve_beam_parameters(preset, contact_step=0.9 * bound, **overrides), bs)


@pytest.mark.parametrize("levels", [0, 1])
def test_the_accuracy_check_takes_no_grid_beyond_the_largest_steps_per_period(
        monkeypatch, levels):
    """With steps_per_period's largest between the first step (the grid's, or the contact
    sub-steps a period, whichever the more) times 2^levels and 2^(levels + 1), the
    halvings stop there: the point reports that level's grid and the
    estimate it has (none at its first step), as the table's bound says."""
    from dataclasses import replace

    from harvester_sweep.beam_packing import contact_steps
    from harvester_sweep.beam_parameters import BEAM_PARAMETERS

    p = resolve_beam_parameters("bimorph_tip", n_modes=1, frequency=150.0, accuracy=1e-13)
    first, substep = first_steps(p, system_of(p))
    most = max(first, contact_steps(p, substep))  # (the grid's, or the contact's sub-steps)
    monkeypatch.setitem(BEAM_PARAMETERS, "steps_per_period",
                        replace(BEAM_PARAMETERS["steps_per_period"],
                                high=1.5 * most * 2 ** levels))
    v = solve_beam([p]).values
    assert v["status"][0] == 0 and v["steps_per_period"][0] == first * 2 ** levels
    assert math.isnan(v["error_estimate"][0]) == (levels == 0)
    if levels:
        assert v["error_estimate"][0] > p["accuracy"]


def test_the_contact_free_map_and_its_reach_are_the_linear_systems():
    """Clear of the stop: the monodromy in closed form is SciPy's expm of the linear
    system over the periods; the reach that proves a motion never comes to the stop bounds
    the surface's motion that SciPy integrates from a state off the orbit, and on the
    orbit it is the orbit's own amplitude there."""
    p = resolve_beam_parameters(n_modes=3, frequency=150.0, gap=1e-2)
    bs = system_of(p)
    pack = pack_beam(p, bs, *first_steps(p, bs))
    M, T = bs.system.matrix, 1.0 / p["frequency"]
    expm = scipy.linalg.expm(M * 2 * T)
    assert np.abs(pack.free_monodromy(2) - expm).max() <= 1e-9 * np.abs(expm).max()
    orbit = pack.particular.imag
    rng = np.random.default_rng(3)
    y0 = orbit + 3.0 * bs.scale * rng.standard_normal(len(orbit))
    w, A, C = 2 * math.pi * p["frequency"], p["amplitude"], bs.system.surfaces[0]

    def motion(y, periods):
        res = solve_ivp(lambda t, y: M @ y + bs.system.forcing * A * math.sin(w * t),
                        (0.0, periods * T), y, method="DOP853", rtol=1e-11,
                        atol=1e-14 * bs.scale, dense_output=True)
        return C @ res.sol(np.linspace(0.0, periods * T, 1000 * periods + 1))

    assert np.abs(motion(y0, 20)).max() <= pack.reach(y0)[0] * (1 + 1e-9)
    # (1000 samples a period find the peak to (pi / 1000)^2 / 2 = 5e-6 of it)
    assert pack.reach(orbit)[0] == pytest.approx(np.abs(motion(orbit, 1)).max(), rel=1e-5)


def test_newtons_monodromy_is_the_period_maps_derivative():
    """The monodromy by the variational equations (modal_map.variational_monodromies):
    clear of the stop it is SciPy's expm of the linear system over the periods; on an
    orbit with contact it is the derivative that central differences take of the engine's
    own map, to a difference that falls as the contact step does. Without the correction
    for the touch's move (the contact's sub-steps are laid out from it) the two part by
    1.9e-3 of the monodromy at the first steps, and by 3.7e-4 two halvings on."""
    free = resolve_beam_parameters(n_modes=3, frequency=150.0, gap=1e-2)
    bs = system_of(free)
    pack = pack_beam(free, bs, *first_steps(free, bs))
    y = pack.particular.imag + 3.0 * bs.scale  # (off the orbit: the map is affine)
    J, _, ok = modal_map.variational_monodromies([pack], y[None], [2])
    expm = scipy.linalg.expm(bs.system.matrix * 2.0 / free["frequency"])
    assert ok[0] and np.abs(J[0] - expm).max() <= 1e-9 * np.abs(expm).max()
    p = resolve_beam_parameters(n_modes=1, frequency=230.0, gap=1e-6)
    solved = solve_beam([p])
    assert solved.values["impacts_per_period"][0] == 1
    y, bs = solved.ends[0], system_of(p)
    steps, sub = first_steps(p, bs)
    s = bs.scale[:, None] / bs.scale[None, :]  # (the monodromy in units of the scales)
    apart = []
    for level in (0, 2):
        pk = pack_beam(p, bs, steps * 2 ** level, sub / 2 ** level)
        J, _, ok = modal_map.variational_monodromies([pk], y[None], [1])
        C, _, ok_c = modal_map.monodromies([pk], y[None], [1], (1e-6 * bs.scale)[None],
                                           central=True)
        assert ok[0] and ok_c[0]
        apart.append(np.abs((J[0] - C[0]) / s).max() / np.abs(C[0] / s).max())
    assert apart[0] < 1e-4 and apart[1] < apart[0] / 3


def test_one_rod_mode_is_the_stop_on_a_spring():
    """A rod in one mode is the lumped stop on a spring (rod.equivalent: m_s, k_s): the
    same linear system in the stop's displacement x_s = psi_1(L_r) q_1, but for the base's
    forcing, which a distributed rod feels as m_s (4/pi) A where a lumped mass feels m_s A."""
    p = resolve_beam_parameters("mak_rod", n_modes=1, rod_modes=1)
    bs = system_of(p)
    face = float(bs.rod_modes.face[0])
    eq = rd.equivalent(rd.Rod(p["rod_length"], p["rod_area"], p["rod_material"]))
    M, q, rate = bs.system.matrix, 3, 4  # (eta, eta', V, q, q')
    assert -M[rate, q] == pytest.approx(eq.stiffness / eq.mass, rel=1e-12)
    assert bs.system.inputs[0][rate] * face == pytest.approx(1.0 / eq.mass, rel=1e-12)
    assert bs.system.surfaces[0][q] == pytest.approx(-face, rel=1e-15)
    assert bs.system.forcing[rate] * face == pytest.approx(4 / math.pi, rel=1e-12)


def _reference_period(p, bs, y0, periods, rtol=1e-12):
    """The modal equations y' = M y + f A sin(w t) + sum_s b_s F_s over ``periods`` forcing
    periods from y0, by SciPy's DOP853 restarted at every switch of a surface's force
    (touch, separation and the clip of the damping law): (end state, mean power [W])."""
    sysm, A, w = bs.system, p["amplitude"], 2 * math.pi * p["frequency"]
    kh, ch = p["hertz_stiffness"], bs.contact_damping
    M, f, C, g, B = sysm.matrix, sysm.forcing, sysm.surfaces, sysm.gaps, sysm.inputs
    volt = list(sysm.output_names).index("voltage")
    out_v = sysm.outputs[volt]

    def forces(y, on):
        d = C @ y - g
        r = C @ (M @ y)
        return np.where(on, kh * np.maximum(d, 0) ** 1.5 * np.maximum(1 + ch * r, 0), 0.0)

    def rhs(t, y, on):
        yy = y[:-1]
        dy = M @ yy + f * A * math.sin(w * t) + B.T @ forces(yy, on)
        return np.append(dy, (out_v @ yy) ** 2)

    def pushing(y):
        d = C @ y - g
        r = C @ (M @ y)
        return (d > 0) & (1 + ch * r > 0)

    t, T = 0.0, periods * 2 * math.pi / w
    y = np.append(y0, 0.0)
    on = pushing(y0)
    atol = np.append(1e-13 * bs.scale, 1e-30)

    def switch(tt, yy, on, s, kind):
        r = C[s] @ (M @ yy[:-1])
        return C[s] @ yy[:-1] - g[s] if kind == 0 else 1 + ch * r

    events = []
    for s in range(len(g)):
        for kind in (0, 1):
            def event(tt, yy, on, s=s, kind=kind):
                return switch(tt, yy, on, s, kind)
            event.terminal = True
            events.append(event)
    while t < T:
        res = solve_ivp(rhs, (t, T), y, method="DOP853", rtol=rtol, atol=atol, events=events,
                        args=(on,))
        t, y = res.t[-1], res.y[:, -1]
        if res.status == 1:
            # which side of the switch the motion goes on to: one tiny Euler step ahead;
            # then a step clear of the switch, where its event would fire again at once
            # (the force is near zero there, so the step's own error is of rounding size)
            nudge = 1e-10 * (T / periods)
            on = pushing((y + nudge * rhs(t, y, on))[:-1])
            step = solve_ivp(rhs, (t, min(t + nudge, T)), y, method="DOP853", rtol=rtol,
                             atol=atol, args=(on,))
            t, y = step.t[-1], step.y[:, -1]
    return y[:-1], y[-1] / T / p["resistance"]


@pytest.mark.parametrize("preset, overrides", [
    ("bimorph_tip", dict(n_modes=3, contact_position=0.8 * 28.81e-3)),
    ("mak_rod", dict(n_modes=2, rod_modes=2)),
    ("bimorph_tip", dict(n_modes=2, lower_gap=1e-6)),
    # the motion hugs the damping law's clip (each side's flow pushing towards it): the
    # engine located every crossing, in steps of 1e-10 s, and never ended the period
    ("bimorph_tip", dict(gap=4.2857142857142857e-07, frequency=123.80952380952381)),
    # an orbit of period 2 that the whole transient settled on (Newton from the short one
    # took the period-1 orbit, unstable), then solved at twice the steps by chord steps
    # with the monodromy taken there
    ("bimorph_tip", dict(gap=3e-6, frequency=130.0)),
    # an orbit of period 12, beyond the 8 the engine's own test looks for: Newton took
    # it, then the run that was to settle it again spent its budget (not settled)
    ("bimorph_tip", dict(gap=3.2857142857142857e-06, frequency=135.71428571428572)),
])
def test_the_orbit_with_contact_is_an_orbit_of_the_equations(preset, overrides):
    """The engine's steady state, run again by SciPy on the same modal equations from the
    engine's own state at the period's start, comes back to that state after its period,
    with the power the engine booked."""
    p, sol = _solve(preset, **overrides)
    bs = system_of(p)
    v = sol.values
    period = int(v["orbit_period"][0])
    assert v["status"][0] == 0 and v["impacts_per_period"][0] * period >= 1  # (an impact an orbit)
    y0 = sol.ends[0]
    y1, power = _reference_period(p, bs, y0, period)
    scale = np.abs(y0).max()
    assert np.abs(y1 - y0).max() <= 1e-5 * scale
    assert power == pytest.approx(v["power"][0], rel=1e-5)


def test_the_steady_state_is_the_one_the_motion_from_rest_reaches():
    """Near a period doubling a stable period-1 orbit coexists with the period-2 orbit
    that the motion from rest settles on; Newton from the short transient converged to the
    period-1 one, and it was reported. SciPy on the same modal equations, from rest, comes
    to the orbit reported, and its strobes alternate: period 2."""
    p, sol = _solve(gap=2.5e-7, frequency=160.0, n_modes=2)
    bs = system_of(p)
    assert sol.values["status"][0] == 0
    y = np.zeros(len(bs.system.matrix))
    for _ in range(40):
        y, _ = _reference_period(p, bs, y, 1, rtol=1e-10)
    after, _ = _reference_period(p, bs, y, 1, rtol=1e-10)
    period = int(sol.values["orbit_period"][0])
    orbit = sol.strobes[0][-period:]  # (each of its phases)
    distance = np.abs((orbit - y) / bs.scale).max(axis=1).min()
    assert distance <= 1e-5
    assert np.abs((after - y) / bs.scale).max() > 1e-2
    assert period == 2


def test_a_graze_found_again_at_its_separation_does_not_stop_time():
    """A point of the rod's 64 x 64 grid where a Newton copy only grazes the rod: its
    separation's root lay at the touch itself, the flow from there met the touch again at
    once, and the period never ended. It runs to its budget now, every period accounted."""
    p = resolve_beam_parameters("mak_rod", rod_modes=5, gap=6.071428571428572e-07,
                                frequency=247.61904761904762)
    sol = solve_beam([p])
    v = sol.values
    assert v["status"][0] in (0, 1) and v["periods_run"][0] <= p["max_periods"] + 2 * 24
    assert np.isfinite(v["power"][0]) and np.isfinite(sol.ends[0]).all()


def test_a_diverged_point_reports_no_values():
    """A contact sub-step of 1 s cannot resolve the contact: the run diverges, and every
    value the point would report is NaN (the engine's row holds what it booked before the
    run blew up: a power of 0 W, an x_max of -inf m; its multipliers had imaginary parts
    0); its status and periods run remain."""
    p = resolve_beam_parameters("bimorph_tip", n_modes=1, contact_step=1.0, frequency=220.0)
    with pytest.warns(StabilityWarning, match="contact_step = 1 s is beyond"):
        v = solve_beam([p]).values
    assert v["status"][0] == STATUS.diverged and v["periods_run"][0] > 0
    told = {"orbit_period", "status", "periods_run", "steps_per_period", "contact_step"}
    for name in set(v) - told:
        assert np.isnan(v[name][0]).all(), name


@pytest.mark.parametrize("preset, overrides", [
    ("bimorph_tip", {"n_modes": 1, "contact_step": 1.0, "frequency": 220.0}),
    ("mak_rod", {"rod_length": 1e-6})])  # (rod modes of 1e10 rad/s for a step of 3e-8 s)
def test_a_diverged_scene_records_no_time_history(preset, overrides):
    """A diverged point has no orbit to record: its scene's time history is empty, where
    the orbit's periods were recorded from the blown-up state and squaring its voltage
    overflowed (numpy's warning reached the command line's stderr)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", StabilityWarning)  # (contact_step = 1 s: said, and so)
        outputs, series = beam_scene(preset, **overrides)
    assert outputs["status"] == STATUS.diverged
    assert series.sizes["time"] == 0 and np.isnan(float(series["power"]))


def test_a_state_deep_in_a_stop_is_flagged_diverged_not_run_forever():
    """A state twenty thousand gaps into the stop (a Newton iterate of the beam's solver
    was 1 mm deep at 1.4 m/s), far deeper than the contact sub-step resolves: RK4 in contact
    overflows within the first period. The run is flagged diverged; before, the overflowed
    state's switch search sent the time to -2^48 s and the period never ended. A point at
    rest beside it in the same call runs as it does alone, bit for bit."""
    p = resolve_beam_parameters("bimorph_tip", gap=1e-6, lower_gap=1.5e-6, n_modes=3,
                                frequency=250.0)
    bs = system_of(p)
    pk = pack_beam(p, bs, *first_steps(p, bs))
    D = pk.dims[0]
    upper = bs.system.surfaces[0]
    deep = np.zeros(D)
    deep[0] = 2e-2 / upper[0]  # the tip 2 cm into the upper stop
    assert upper @ deep - p["gap"] > 1.9e-2
    starts = np.array([deep, np.zeros(D)])
    ends, ok = modal_map.map_states([pk, pk], starts, np.array([1, 1]))
    alone, ok_alone = modal_map.map_states([pk], starts[1:], np.array([1]))
    assert not ok[0] and ok[1] and ok_alone[0]
    assert np.array_equal(ends[1], alone[0])
    metrics, _, _ = modal_map.run([pk, pk], starts)
    status = metrics[:, modal_map.modal.HEAD.status]
    assert status[0] == STATUS.diverged and status[1] != STATUS.diverged


def test_a_measured_orbits_strobes_are_its_period_maps():
    """modal_map.measure over an orbit's p periods returns as strobes the orbit's states
    d = 1 ... p periods on, each the period map's (modal_map.map_states) from the start,
    repeated before them as the orbit's; its end state is the last of them."""
    p, sol = _solve(gap=2.5e-7, frequency=160.0, n_modes=2)
    bs = system_of(p)
    period = int(sol.values["orbit_period"][0])
    assert sol.values["status"][0] == 0 and period == 2
    steps = int(sol.values["steps_per_period"][0])
    pk = pack_beam(p, bs, steps, sol.values["contact_step"][0])
    y = sol.ends[0]
    _, ends, strobes = modal_map.measure([pk], [y], [period])
    samples = strobes.shape[1]
    for d in range(1, period + 1):
        (mapped,), ok = modal_map.map_states([pk], y[None], [d])
        assert ok[0]
        assert np.abs((strobes[0, samples - period + d - 1] - mapped) / bs.scale).max() <= 1e-12
    assert np.abs((strobes[0, -1] - ends[0]) / bs.scale).max() <= 1e-12
    assert np.array_equal(strobes[0, :-period], strobes[0, period:])


def test_a_mode_decayed_clear_of_the_stops_is_zero_not_subnormal():
    """Clear of the stops each eigen-coordinate decays as exp(lam t), the beam's first
    modes by about exp(-9) a period at 136 Hz, and a few tens of periods take them through
    the subnormal numbers, whose arithmetic costs a hundred times a normal one's. After
    every period of 120 from rest no component is subnormal: each is the exact flow's
    exp(lam t) z0 (to the rounding of a period's grid steps) where that is above the
    engine's TINY, and zero where it is far below."""
    p = resolve_beam_parameters("bimorph_tip", frequency=136.0, gap=1.0)
    bs = system_of(p)
    pk = pack_beam(p, bs, *first_steps(p, bs))
    D, S, K = pk.dims
    lam = pk.crow[:D]
    z0 = pk.to_modal(np.zeros(D)).astype(complex)
    z = z0[None].copy()
    ok = np.empty(1, dtype=bool)
    tiny = np.finfo(float).tiny
    T = 2 * np.pi / pk.rrow[modal_map.RealFields(*modal_map.real_fields(D, S, K)).omega]
    passed = np.zeros(D, dtype=bool)  # components whose exact flow went below TINY
    for n in range(1, 121):
        modal_map._take(modal_map.modal.MAP, pk.crow[None], pk.rrow[None], z, np.array([1]),
                         None, None, np.empty((1, 2, D, 0)), ok, 1, (D, S, K))
        assert ok[0]
        parts = np.concatenate([z[0].real, z[0].imag])
        assert ((parts == 0.0) | (np.abs(parts) >= tiny)).all(), f"subnormal at period {n}"
        exact = np.exp(lam * n * T) * z0
        kept = np.abs(exact) > 1e10 * modal_map.modal.kernel.TINY
        assert np.allclose(z[0][kept], exact[kept], rtol=1e-9, atol=0.0)
        assert (z[0][np.abs(exact) < 1e-10 * modal_map.modal.kernel.TINY] == 0.0).all()
        passed |= np.abs(exact) < tiny
    assert passed.sum() >= 2  # (the test would have seen subnormals without TINY)


def test_one_mode_at_the_tip_is_the_tip_mass_model():
    """The one-mode beam striking at its tip is the tip-mass model with the reduced
    parameters (m_eq, k_eq, theta_eq, mu_1): the same linear system in x = phi_1(L) eta_1
    to rounding, and the same orbit from the lane engine (another integrator: plain RK4
    on x) within both runs' accuracy. (Last in the file: the one test here that runs the
    tip-mass model, whose engine a cold suite compiles while the beam's tests run:
    conftest.BEAM_FIRST.)"""
    p, sol = _solve(n_modes=1)
    bs = system_of(p)
    tip = float(bs.modes.tip[0])
    eq = bm.reduction(bimorph(p))
    lumped = beam_model.tip_mass_system(eq.mass, eq.stiffness, 2 * p["damping_ratio"]
                                        * math.sqrt(eq.stiffness * eq.mass), eq.coupling,
                                        eq.capacitance, p["resistance"], p["gap"],
                                        eq.forcing_factor)
    T = np.diag([tip, tip, 1.0])  # (x, v, V) = T (eta, eta', V)
    Ti = np.linalg.inv(T)
    np.testing.assert_allclose(T @ bs.system.matrix @ Ti, lumped.matrix, rtol=1e-12,
                               atol=1e-12 * np.abs(lumped.matrix).max())
    np.testing.assert_allclose(T @ bs.system.forcing, lumped.forcing, rtol=1e-12)
    np.testing.assert_allclose(bs.system.surfaces @ Ti, lumped.surfaces, rtol=1e-12)
    np.testing.assert_allclose(T @ bs.system.inputs[0], lumped.inputs[0], rtol=1e-12)
    tip_mass = run_scene("paper", **bm.as_tip_mass_parameters(bimorph(p)))
    v = sol.values
    assert v["impacts_per_period"][0] == tip_mass.metrics["impacts_per_period"] == 1
    for name in ("power", "v_peak", "x_max", "x_min", "approach_velocity"):
        assert v[name][0] == pytest.approx(tip_mass.metrics[name], rel=2e-7), name
    # the Floquet multipliers: the beam's from forward differences at its reported step
    # (about 1e-6), the lane engine's from central ones
    mu = v["floquet_multipliers_real"][0] + 1j * v["floquet_multipliers_imag"][0]
    ref = (np.array(tip_mass.metrics["floquet_multipliers_real"])
           + 1j * np.array(tip_mass.metrics["floquet_multipliers_imag"]))
    assert np.abs(mu - ref).max() <= 2e-6
    assert v["spectral_radius"][0] == abs(mu[0])
