"""What a user would otherwise pick: baselines for the speed benchmark, on the same equations.

    python -m benchmarks.alternatives     # paper scene, 94 periods from rest, prints a table

- ``lsoda``: SciPy ``solve_ivp(method="LSODA")`` with the switched right-hand side written as a
  user would write it, one ``if`` on the contact and no event restarts;
- ``diffrax_ensemble``: a JAX/diffrax ``vmap`` ensemble (Tsit5, PID step-size control, float64),
  the contact switch a ``jnp.where`` in the right-hand side, as a GPU/XLA user would write it.

Both integrate (x [m], v [m/s], V [V]) of MODEL.md from rest over a whole number of forcing
periods and return the state at every period boundary (the last is the final state), so
that each can be compared with ``tests/helpers.py`` and the steady state's own periodic
orbit.
The absolute tolerance is ``rtol`` times (1e-6 m, 1e-2 m/s, 1e-5 V), the scales of the paper
scene (gap 1 um, velocities of mm/s to cm/s, tens of microvolts), the same scales the error is
measured in.

jax, diffrax and pytest-benchmark are optional: ``pip install ".[bench]"``.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy.integrate import solve_ivp

from tests.helpers import Reference, lankarani_nikravesh_damping

ATOL_SCALE = np.array([1e-6, 1e-2, 1e-5])  # x [m], v [m/s], V [V]: atol = rtol * ATOL_SCALE
INSTALL_HINT = 'jax and diffrax are needed for this baseline: pip install ".[bench]"'


def coefficients(p: dict) -> dict:
    """Coefficients of the equations from a resolved parameter dict (SI units).

    Returns m [kg], k [N/m], c [N s/m], w [rad/s], theta [N/V], Cp [F], R [Ohm], A [m/s^2],
    g [m], kh [N/m^1.5] and ch [s/m]; ch is Lankarani-Nikravesh 3 (1 - e^2) / (4 v_imp) when
    ``p["contact_damping"]`` is None, as in ``tests/helpers.py``.
    """
    wn = 2 * math.pi * p["natural_frequency"]
    m = p["mass"]
    ch = p.get("contact_damping")
    if ch is None:
        ch = lankarani_nikravesh_damping(p["restitution"], p["impact_velocity"])
    return {"m": m, "k": m * wn**2, "c": 2 * p["damping_ratio"] * m * wn,
            "w": 2 * math.pi * p["frequency"], "theta": p["coupling"],
            "Cp": p["capacitance"], "R": p["resistance"], "A": p["amplitude"],
            "g": p["gap"], "kh": p["hertz_stiffness"], "ch": ch}


#: The tolerances each alternative runs at, from rest, to find the one that reaches the
#: engine's error soonest (matched_time) [-].
RTOLS = {"lsoda": (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11),
         "diffrax": (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)}

# The alternatives run from rest until the transient has decayed by this factor (from the
# orbit's spectral radius): long enough for each to come within the engine's error of the
# orbit at its tighter tolerances.
TRANSIENT_DECAY = 1e-12


def paper_reference(accuracy: float) -> tuple[dict, np.ndarray, int]:
    """The paper scene at ``accuracy`` [-]: its parameters; the state (x [m], v [m/s], V [V])
    of its exact periodic orbit at forcing phase 0 (DOP853 at rtol 1e-12 from the engine's
    orbit, until the difference has decayed below 1e-16); the periods the alternatives
    integrate from rest (TRANSIENT_DECAY)."""
    import harvester_sweep as hs

    scene = hs.run_scene("paper", accuracy=accuracy)
    p, rho = scene.parameters, scene.metrics["spectral_radius"]
    settle = math.ceil(math.log(1e-16) / math.log(rho))
    exact = Reference(p).integrate(scene.state[:3], 0.0, settle / p["frequency"])[0][:3]
    return p, exact, math.ceil(math.log(TRANSIENT_DECAY) / math.log(rho))


def state_error(state, exact):
    """max over (x, v, V) of |state - exact| / ATOL_SCALE [-], over the last axis of
    ``state`` (a float for one state)."""
    errors = np.max(np.abs(np.asarray(state)[..., :3] - exact) / ATOL_SCALE, axis=-1)
    return errors if errors.ndim else float(errors)


def matched_time(runs, exact, target: float) -> tuple[float, str]:
    """Time [s] a transient integration takes to come, and stay, within ``target`` of the
    orbit ``exact``, from (rtol, time [s], states at every period boundary) runs.

    Each run's time is scaled to the first period boundary from which every later sample
    is within the target (an oracle's stopping rule: the alternative's best case); the
    shortest over the tolerances (each the best of its rounds) is returned, with how."""
    best = {}
    for rtol, seconds, states in runs:
        if rtol not in best or seconds < best[rtol][0]:
            best[rtol] = (seconds, states)
    found = []
    for rtol, (seconds, states) in best.items():
        above = np.flatnonzero(state_error(states, exact) > target)
        k = above[-1] + 1 if above.size else 0
        if k < len(states):
            found.append((seconds * k / (len(states) - 1), rtol, k))
    if not found:
        closest = min(state_error(states[-1], exact) for _, states in best.values())
        return math.inf, f"never within it (closest {closest:.1e})"
    seconds, rtol, k = min(found)
    return seconds, f"rtol {rtol:g}, from rest for {k} periods"


def lsoda(p: dict, periods: int, rtol: float) -> tuple[float, np.ndarray]:
    """SciPy LSODA from rest (x = v = V = 0 at t = 0) over ``periods`` forcing periods.

    Parameters
    ----------
    p : resolved parameters (``harvester_sweep.parameters.resolve_parameters``), SI units.
    periods : number of forcing periods 1/f [s] to integrate.
    rtol : relative tolerance [-]; atol = rtol * (1e-6 m, 1e-2 m/s, 1e-5 V).

    Returns
    -------
    seconds : wall time of the ``solve_ivp`` call only [s].
    states : (periods + 1, 3): (x [m], v [m/s], V [V]) at t = k / f, k = 0 .. periods.
    """
    q = coefficients(p)
    m, k, c, w, theta = q["m"], q["k"], q["c"], q["w"], q["theta"]
    Cp, R, mA, g, kh, ch = q["Cp"], q["R"], q["m"] * q["A"], q["g"], q["kh"], q["ch"]

    def rhs(t, y):  # the switched system as a user would write it: no event restarts
        x, v, V = y
        fc = max(kh * (x - g) ** 1.5 * (1 + ch * v), 0.0) if x > g else 0.0
        a = (mA * math.sin(w * t) - c * v - k * x - fc + theta * V) / m
        return [v, a, -(V / R + theta * v) / Cp]

    t1 = periods / p["frequency"]
    start = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, t1), np.zeros(3), method="LSODA", rtol=rtol,
                    atol=rtol * ATOL_SCALE, t_eval=np.arange(periods + 1) / p["frequency"])
    seconds = time.perf_counter() - start
    if not sol.success:
        raise RuntimeError(f"LSODA failed at rtol {rtol:g}: {sol.message}")
    return seconds, sol.y.T.copy()


def _jax():
    """Import jax (float64 switched on, process-wide) and diffrax, or raise ImportError."""
    try:
        import diffrax
        import jax
    except ImportError as error:
        raise ImportError(INSTALL_HINT) from error
    jax.config.update("jax_enable_x64", True)
    return jax, diffrax


_SOLVERS: dict = {}


def _ensemble_solver(max_steps: int):
    """The jitted, vmapped diffrax solve, built once per max_steps and reused (rtol is traced)."""
    if max_steps in _SOLVERS:
        return _SOLVERS[max_steps]
    jax, diffrax = _jax()
    jnp = jax.numpy

    def vector_field(t, y, args):
        w, q = args
        x, v, V = y[0], y[1], y[2]
        delta = jnp.maximum(x - q["g"], 0.0)  # keeps sqrt real in the branch jnp.where drops
        fc = jnp.where(x > q["g"],
                       jnp.maximum(q["kh"] * delta * jnp.sqrt(delta) * (1 + q["ch"] * v), 0.0),
                       0.0)
        a = (q["m"] * q["A"] * jnp.sin(w * t) - q["c"] * v - q["k"] * x - fc
             + q["theta"] * V) / q["m"]
        return jnp.stack([v, a, -(V / q["R"] + q["theta"] * v) / q["Cp"]])

    term = diffrax.ODETerm(vector_field)
    solver = diffrax.Tsit5()

    def one(w, q, ts, rtol, atol):
        sol = diffrax.diffeqsolve(
            term, solver, t0=0.0, t1=ts[-1], dt0=None, y0=jnp.zeros(3), args=(w, q),
            stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
            saveat=diffrax.SaveAt(ts=ts), max_steps=max_steps)
        return sol.ys, sol.stats["num_steps"]

    _SOLVERS[max_steps] = jax.jit(jax.vmap(one, in_axes=(0, None, None, None, None)))
    return _SOLVERS[max_steps]


def diffrax_ensemble(p: dict, periods: int, n_points: int, rtol: float, *, spread: float = 1e-9,
                     max_steps: int = 4_000_000, details: dict | None = None
                     ) -> tuple[float, np.ndarray]:
    """A JAX/diffrax ``vmap`` ensemble of ``n_points`` copies of one point, from rest.

    Tsit5 with ``PIDController(rtol, atol = rtol * (1e-6 m, 1e-2 m/s, 1e-5 V))``, float64,
    saved at every period boundary, over ``periods`` forcing periods of the nominal
    frequency. The lanes' forcing frequencies are spread by up to +-``spread`` (relative) so
    that XLA cannot fold them into one; lane ``n_points // 2`` has exactly the nominal
    frequency. The first call compiles (not timed into the result), the second is timed
    with ``block_until_ready``.

    Parameters
    ----------
    p : resolved parameters, SI units.
    periods : number of forcing periods 1/f [s] to integrate.
    n_points : ensemble size (lanes of the vmap).
    rtol : relative tolerance [-].
    spread : relative spread of the lanes' forcing frequencies [-].
    max_steps : diffrax step budget per lane; exceeding it raises.
    details : if a dict, filled with ``compile_seconds`` (wall time of the first call,
        compilation included, [s]), ``total_seconds`` (the timed call [s]) and ``steps``
        (accepted + rejected steps of the nominal lane).

    Returns
    -------
    seconds_per_point : wall time of the timed call divided by ``n_points`` [s].
    states : (n_points, periods + 1, 3): (x [m], v [m/s], V [V]) at t = k / f (nominal
        frequency), k = 0 .. periods.

    Raises
    ------
    ImportError : jax or diffrax missing (``pip install ".[bench]"``); callers may skip.
    """
    jax, _ = _jax()
    jnp = jax.numpy
    solve = _ensemble_solver(max_steps)
    q = {key: jnp.asarray(value, dtype=jnp.float64)
         for key, value in coefficients(p).items() if key != "w"}
    offsets = (np.arange(n_points) - n_points // 2) / max(n_points // 2, 1)
    w = jnp.asarray(coefficients(p)["w"] * (1 + spread * offsets), dtype=jnp.float64)
    args = (w, q, jnp.asarray(np.arange(periods + 1) / p["frequency"], dtype=jnp.float64),
            jnp.float64(rtol),
            jnp.asarray(rtol * ATOL_SCALE, dtype=jnp.float64))

    start = time.perf_counter()
    jax.block_until_ready(solve(*args))
    compile_seconds = time.perf_counter() - start
    start = time.perf_counter()
    ys, steps = jax.block_until_ready(solve(*args))
    total = time.perf_counter() - start
    if details is not None:
        details.update(compile_seconds=compile_seconds, total_seconds=total,
                       steps=int(steps[n_points // 2]))
    return total / n_points, np.asarray(ys)


def main(periods: int = 94, rtols=(1e-6, 1e-8, 1e-10), ensembles=(64, 16)) -> None:
    """Print per-point wall time [s] and final-state error of each baseline, paper scene."""
    from harvester_sweep.parameters import resolve_parameters

    p = resolve_parameters("paper")
    start = time.perf_counter()
    exact = Reference(p).integrate(np.zeros(3), 0.0, periods / p["frequency"])[0][:3]
    print(f"paper scene, {periods} periods from rest; reference (DOP853, rtol 1e-12, event "
          f"restarts) {time.perf_counter() - start:.1f} s")
    print("error = max |final - reference| / (1e-6 m, 1e-2 m/s, 1e-5 V)\n")

    def error(state) -> float:
        return float(np.max(np.abs(np.asarray(state) - exact) / ATOL_SCALE))

    print(f"| {'baseline':<20} | {'rtol':>6} | {'s/point':>9} | {'error':>8} | {'steps':>7} |")
    print(f"| {'-' * 20} | {'-' * 6}:| {'-' * 9}:| {'-' * 8}:| {'-' * 7}:|")
    compile_seconds = {}
    for rtol in rtols:
        seconds, states = lsoda(p, periods, rtol)
        print(f"| {'scipy LSODA':<20} | {rtol:>6.0e} | {seconds:>9.3g} | "
              f"{error(states[-1]):>8.1e} |"
              f" {'':>7} |")
        for n_points in ensembles:
            details = {}
            try:
                per_point, states = diffrax_ensemble(p, periods, n_points, rtol, details=details)
            except ImportError as missing:
                print(f"| diffrax skipped: {missing}")
                break
            print(f"| {f'diffrax Tsit5 x{n_points}':<20} | {rtol:>6.0e} | {per_point:>9.3g} |"
                  f" {error(states[n_points // 2, -1]):>8.1e} | {details['steps']:>7d} |")
            compile_seconds.setdefault(n_points, details["compile_seconds"])
    print("\nLSODA steps not counted; diffrax steps: accepted + rejected of the nominal lane.")
    for n_points, seconds in compile_seconds.items():
        print(f"diffrax x{n_points}: first call (jit compile + one untimed run) {seconds:.2f} s;"
              " later rtols reuse the compiled solve (rtol is traced)")


if __name__ == "__main__":
    main()
