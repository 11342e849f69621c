"""Work-precision benchmark: error against run time, the RK4 engine against SciPy's solvers.

    python -m benchmarks.work_precision            # full run, writes benchmarks/results/
    python -m benchmarks.work_precision --quick    # smoke test, writes *_quick.md/.png

Task (fixed horizon): integrate from rest for K = 40 forcing periods and measure

- the mean power V^2/R over the last 16 periods [W],
- the peak |V| over the last 16 periods [V],
- the final state (x, v, V); its relative error is the largest over the components of
  |difference| / amplitude of that component over the last 16 periods.

Scenes: "no contact" (preset "paper", gap 1 m: the stop is out of reach), "paper" (the
preset as is) and "hard contact" (preset "paper", hertz_stiffness 9.03e10, restitution 0.5).
At 40 periods the paper scene strikes the stop once per period, a few periods short of its
steady state (the transient left is part of the task; all methods integrate the same one).

Methods:

- the engine, ``harvester_sweep.run_scene`` with ``settle_tolerance=1e-300`` (it never
  declares a steady state, so it runs exactly K periods and its metrics are over the last
  16), at 64 ... 16384 steps per period, with contact switches located inside the step
  (default) and with plain fixed steps; its own ``run_time`` (compilation excluded);
- ``scipy.integrate.solve_ivp`` with RK45, DOP853, LSODA and Radau at rtol 1e-3 ... 1e-11,
  on the equations written plainly (force max(k_h max(x-g,0)^1.5 (1 + c_h v), 0), no event
  handling for the contact), with a fourth state for int V^2 dt; atol = rtol times a typical
  amplitude per component (1e-6 m, 1e-2 m/s, the scene's peak voltage to 2 digits, and
  its square times one period for int V^2 dt). The peak voltage is found by solve_ivp's
  event location of dV/dt = 0 (a root search on the solver's own interpolant) over the last
  16 periods.

Reference: ``tests/helpers.py`` (SciPy DOP853 restarted exactly at every contact onset and
separation, quadratures in the state) at rtol 1e-13, checked against the same at rtol 1e-12;
its peak voltage comes from roots of dV/dt on each piece's dense output (brentq).

Timing: best of 3 runs (1 run when a run takes more than 5 s), compilation excluded; a SciPy
combination is stopped after CAP_S seconds and reported "skipped (too slow)", as are the
tighter tolerances of that method once one was stopped or predicted to exceed the cap.
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import scipy
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))  # this checkout's package, not an installed copy
import numba  # noqa: E402
from reference import Reference, lankarani_nikravesh_damping  # noqa: E402

import harvester_sweep  # noqa: E402
from harvester_sweep import resolve_parameters, run_scene  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
K = 40  # forcing periods from rest
WINDOW = 16  # the metrics are over the last WINDOW periods (the engine's MAX_ORBIT_PERIOD)
SCENES = {
    "no contact": dict(gap=1.0),
    "paper": dict(),
    "hard contact": dict(hertz_stiffness=9.03e10, restitution=0.5),
}
METHODS = ("RK45", "DOP853", "LSODA", "Radau")
CAP_S = 60.0  # wall-clock cap of one SciPy run
REPEAT_BELOW_S = 5.0  # best of 3 below this run time, else 1 run
GROWTH = 3.0  # assumed growth of run time per tighter rtol, to predict the cap
# The reference at rtol 3e-14 (just above the 100 eps below which solve_ivp refuses),
# checked against itself at rtol 1e-12 and 1e-13.
FULL = dict(
    steps=[64 * 2**i for i in range(9)],  # 64 ... 16384
    rtols=[1e-3, 1e-5, 1e-7, 1e-9, 1e-11],
    ref_rtol=3e-14,
    check_rtols=[1e-12, 1e-13],
)
QUICK = dict(steps=[64, 256, 1024, 4096], rtols=[1e-3, 1e-5, 1e-7], ref_rtol=1e-12,
             check_rtols=[1e-11])


class TooSlow(Exception):
    """Raised from inside the right-hand side once a run passes its wall-clock cap."""


# ---------------------------------------------------------------------------- reference

def _peak_abs_voltage(pieces, p):
    """max |V| over the dense pieces: roots of dV/dt = -(V/R + theta v)/C_p by brentq on
    each piece's dense output, plus the window's ends. Returns (peak, samples)."""
    R, theta, Cp = p["resistance"], p["coupling"], p["capacitance"]
    peak = 0.0
    amplitudes = np.zeros(3)
    for sol, _ in pieces:
        dense = sol.sol
        # each solver step split in 4, so that two extrema never share an interval
        t = np.unique(np.concatenate([np.linspace(a, b, 5) for a, b in zip(sol.t[:-1],
                                                                            sol.t[1:])]))
        y = dense(t)
        amplitudes = np.maximum(amplitudes, np.abs(y[:3]).max(axis=1))
        peak = max(peak, abs(y[2, 0]), abs(y[2, -1]))
        rate = -(y[2] / R + theta * y[1]) / Cp

        def dVdt(s):
            ys = dense(s)
            return -(ys[2] / R + theta * ys[1]) / Cp

        for i in np.nonzero(np.sign(rate[:-1]) * np.sign(rate[1:]) < 0)[0]:
            s = brentq(dVdt, t[i], t[i + 1], xtol=1e-18, rtol=4 * np.finfo(float).eps)
            peak = max(peak, abs(dense(s)[2]))
    return peak, amplitudes


def reference_solution(p, rtol, atol_scale):
    """The reference's metrics over the last WINDOW of K periods, from rest."""
    T = 1.0 / p["frequency"]
    start = time.perf_counter()
    ref = Reference(p, rtol=rtol, atol_scale=atol_scale)
    y, _ = ref.integrate(np.zeros(3), 0.0, (K - WINDOW) * T)
    impacts_before = len(ref.onset_velocities)
    end, pieces = ref.integrate(y[:3], (K - WINDOW) * T, K * T, dense=True)
    peak, amplitudes = _peak_abs_voltage(pieces, p)
    amplitudes[2] = max(amplitudes[2], peak)
    # is the no-tension clip max(..., 0) ever active inside a contact piece? (the reference
    # does not restart there, so that would cost it accuracy)
    clip = 0.0
    for sol, in_contact in pieces:
        if in_contact:
            v = sol.sol(np.linspace(sol.t[0], sol.t[-1], 2001))[1]
            clip = min(clip, float((1.0 + ref.ch * v).min()))
    return dict(
        power=end[3] / (WINDOW * T) / p["resistance"],
        peak=peak,
        state=end[:3].copy(),
        amplitudes=amplitudes,
        impacts=(len(ref.onset_velocities) - impacts_before) / WINDOW,
        pieces=len(pieces),
        clip_active=clip < 0.0,
        time=time.perf_counter() - start,
    )


def closed_form_linear(p, t0, t1):
    """Without the stop the model is linear: the exact solution from rest (particular
    solution by phasors, transient by the eigenvectors), in 40-digit mpmath. Returns the
    mean power and peak |V| over [t0, t1] and the state at t1, or None without mpmath."""
    try:
        import mpmath as mp
    except ImportError:
        return None
    mp.mp.dps = 40
    wn = 2 * mp.pi * p["natural_frequency"]
    w = 2 * mp.pi * p["frequency"]
    m, theta, R, Cp, A = (mp.mpf(p[k]) for k in ("mass", "coupling", "resistance",
                                                  "capacitance", "amplitude"))
    M = mp.matrix([[0, 1, 0], [-wn**2, -2 * mp.mpf(p["damping_ratio"]) * wn, theta / m],
                   [0, -theta / Cp, -1 / (R * Cp)]])
    Y = mp.lu_solve(1j * w * mp.eye(3) - M, mp.matrix([0, A, 0]))  # y_p = Im(Y e^{jwt})
    lam, U = mp.eig(M)
    coef = mp.lu_solve(U, -mp.matrix([mp.im(Y[i]) for i in range(3)]))  # y(0) = 0
    # component i of the state: Re(sum_k a[i][k] exp(mu[k] t))
    mu = [1j * w, -1j * w] + list(lam)
    a = [[Y[i] / 2j, -mp.conj(Y[i]) / 2j] + [coef[j] * U[i, j] for j in range(3)]
         for i in range(3)]

    def comp(i, t, derivative=0):
        return mp.re(sum(ak * mk**derivative * mp.exp(mk * t) for ak, mk in zip(a[i], mu)))

    t0, t1 = mp.mpf(t0), mp.mpf(t1)
    q = 0
    for ak, mk in zip(a[2], mu):
        for al, ml in zip(a[2], mu):
            s = mk + ml
            q += ak * al * ((t1 - t0) if s == 0 else (mp.exp(s * t1) - mp.exp(s * t0)) / s)
    n = WINDOW * 200
    ts = [t0 + (t1 - t0) * i / n for i in range(n + 1)]
    rate = [comp(2, t, 1) for t in ts]
    peak = max(abs(comp(2, t0)), abs(comp(2, t1)))
    for i in range(n):
        if rate[i] * rate[i + 1] < 0:
            root = mp.findroot(lambda t: comp(2, t, 1), (ts[i], ts[i + 1]), solver="anderson")
            peak = max(peak, abs(comp(2, root)))
    return (float(mp.re(q) / (t1 - t0) / R), float(peak),
            np.array([float(comp(i, t1)) for i in range(3)]))


def errors(power, peak, state, ref):
    """Relative errors (mean power, peak voltage, final state) against the reference."""
    return (
        abs(power / ref["power"] - 1.0),
        abs(peak / ref["peak"] - 1.0),
        float(np.max(np.abs(np.asarray(state) - ref["state"]) / ref["amplitudes"])),
    )


# ------------------------------------------------------------------------------- engine

def engine_run(scene, n, locate):
    """One engine run of exactly K periods; returns (metrics, final state, warnings)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run_scene("paper", steps_per_period=n, max_periods=K, settle_tolerance=1e-300,
                           locate_switches=locate, **scene)
    return result.metrics, result.state[:3].copy(), {type(w.message).__name__ for w in caught}


def engine_rows(scene, ref, steps, locate):
    rows = []
    for n in steps:
        m, state, caught = engine_run(scene, n, locate)
        times = [m["run_time"]]
        if m["status"] != "diverged" and times[0] < REPEAT_BELOW_S:
            times += [engine_run(scene, n, locate)[0]["run_time"] for _ in range(2)]
        row = dict(method="engine, located" if locate else "engine, plain steps",
                   setting=f"{n} steps/period", n=n, time=min(times), status=m["status"],
                   notes=", ".join(sorted(caught)))
        if m["status"] == "diverged":
            row["status"] = f"diverged after {m['periods_run']} periods"
        else:
            row["errors"] = errors(m["power"], m["v_peak"], state, ref)
        rows.append(row)
    for previous, row in zip(rows[:-1], rows[1:]):  # observed order between successive n
        if "errors" in previous and "errors" in row:
            ratio = math.log(row["n"] / previous["n"])
            row["order"] = tuple(math.log(a / b) / ratio if a > 0 and b > 0 else math.nan
                                 for a, b in zip(previous["errors"], row["errors"]))
    return rows


# -------------------------------------------------------------------------------- SciPy

def make_rhs(p, deadline):
    """The model as a user would write it for solve_ivp: no event handling at the stop."""
    m, g, kh = p["mass"], p["gap"], p["hertz_stiffness"]
    wn = 2 * math.pi * p["natural_frequency"]
    k, c = m * wn**2, 2 * p["damping_ratio"] * m * wn
    w = 2 * math.pi * p["frequency"]
    A, theta, R, Cp = p["amplitude"], p["coupling"], p["resistance"], p["capacitance"]
    ch = lankarani_nikravesh_damping(p["restitution"], p["impact_velocity"])
    clock = time.perf_counter

    def rhs(t, y):
        if clock() > deadline[0]:
            raise TooSlow
        x, v, V = y[0], y[1], y[2]
        delta = max(x - g, 0.0)
        fc = max(kh * delta**1.5 * (1.0 + ch * v), 0.0)
        a = (m * A * math.sin(w * t) - c * v - k * x - fc + theta * V) / m
        dV = -(V / R + theta * v) / Cp
        return [v, a, dV, V * V]

    def voltage_rate(t, y):  # dV/dt: zero at an extremum of V
        return -(y[2] / R + theta * y[1]) / Cp

    return rhs, voltage_rate


def scipy_run(p, method, rtol, v_scale, cap, atol_factor=1.0):
    """Returns (run time, power, peak, state, nfev, message) or raises TooSlow."""
    T = 1.0 / p["frequency"]
    deadline = [math.inf]
    rhs, voltage_rate = make_rhs(p, deadline)
    atol = atol_factor * rtol * np.array([1e-6, 1e-2, v_scale, v_scale**2 * T])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        start = time.perf_counter()
        deadline[0] = start + cap
        first = solve_ivp(rhs, (0.0, (K - WINDOW) * T), np.zeros(4), method=method, rtol=rtol,
                          atol=atol)
        if first.status < 0:
            return time.perf_counter() - start, None, None, None, first.nfev, first.message
        y0 = np.concatenate([first.y[:3, -1], [0.0]])
        last = solve_ivp(rhs, ((K - WINDOW) * T, K * T), y0, method=method, rtol=rtol,
                         atol=atol, events=voltage_rate)
        elapsed = time.perf_counter() - start
    nfev = first.nfev + last.nfev
    if last.status < 0:
        return elapsed, None, None, None, nfev, last.message
    # extrema of V located by the event search, plus the step points and the window's ends
    peak = max(np.abs(last.y_events[0][:, 2]).max(initial=0.0), np.abs(last.y[2]).max())
    power = last.y[3, -1] / (WINDOW * T) / p["resistance"]
    message = "; ".join(sorted({str(w.message).split("\n")[0][:60] for w in caught}))
    return elapsed, power, peak, last.y[:3, -1].copy(), nfev, message


def scipy_rows(p, ref, method, rtols):
    """The repeats for the timing run with atol scaled by 1 +- 1e-12: at loose tolerances
    the adaptive step sequence around the contact kink is erratic, and the spread of the
    power error over these three runs shows how much a single error figure can be trusted."""
    rows = []
    v_scale = float(f"{ref['peak']:.2g}")  # a typical amplitude, as a user would type it
    stopped = False
    previous_time = 0.0
    for rtol in rtols:
        row = dict(method=f"SciPy {method}", setting=f"rtol {rtol:.0e}", rtol=rtol)
        rows.append(row)
        if stopped or previous_time * GROWTH > CAP_S:
            row["status"] = "skipped (too slow)"
            stopped = True
            continue
        try:
            first = scipy_run(p, method, rtol, v_scale, CAP_S)
        except TooSlow:
            row["status"] = f"skipped (too slow: stopped at {CAP_S:g} s)"
            stopped = True
            continue
        elapsed, power, peak, state, nfev, message = first
        times = [elapsed]
        spread = []
        if power is not None and elapsed < REPEAT_BELOW_S:
            for factor in (1 + 1e-12, 1 - 1e-12):
                again = scipy_run(p, method, rtol, v_scale, CAP_S, factor)
                times.append(again[0])
                if again[1] is not None:
                    spread.append(abs(again[1] / ref["power"] - 1.0))
        previous_time = min(times)
        notes = f"nfev {nfev}"
        if power is None:
            row["status"] = f"failed: {message}"
        else:
            row["status"] = "ok"
            row["errors"] = errors(power, peak, state, ref)
            if spread:
                spread.append(row["errors"][0])
                notes += (f"; power err. with atol x(1+-1e-12): {min(spread):.1e} .. "
                          f"{max(spread):.1e}")
        row.update(time=min(times), notes=notes + (f"; {message}" if message else ""))
        print(f"    {method:6s} rtol {rtol:.0e}: {row['time']:8.3f} s  {row.get('errors')}",
              flush=True)
    return rows


def peak_measurement_check(p, ref):
    """DOP853 at rtol 1e-11 with dense output: the event-located peak against the peak
    found by the reference's own root search on the same dense output (so the peak
    measurement itself, not the solver, is compared)."""
    T = 1.0 / p["frequency"]
    rhs, voltage_rate = make_rhs(p, [math.inf])
    v_scale = float(f"{ref['peak']:.2g}")
    atol = 1e-11 * np.array([1e-6, 1e-2, v_scale, v_scale**2 * T])
    first = solve_ivp(rhs, (0.0, (K - WINDOW) * T), np.zeros(4), method="DOP853", rtol=1e-11,
                      atol=atol)
    y0 = np.concatenate([first.y[:3, -1], [0.0]])
    last = solve_ivp(rhs, ((K - WINDOW) * T, K * T), y0, method="DOP853", rtol=1e-11,
                     atol=atol, events=voltage_rate, dense_output=True)
    by_events = max(np.abs(last.y_events[0][:, 2]).max(), np.abs(last.y[2]).max())
    by_roots, _ = _peak_abs_voltage([(last, True)], p)
    return abs(by_events / by_roots - 1.0)


# ------------------------------------------------------------------------------ output

def machine_lines(command):
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass

    def git(*args):
        try:
            return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                                  check=False).stdout.rstrip()
        except OSError:
            return ""

    changed = sorted({line[3:] for line in git("status", "--porcelain", "--", "harvester_sweep",
                                                "tests/helpers.py").splitlines()})
    return [
        f"- command: `{command}`",
        f"- date: {datetime.datetime.now().isoformat(timespec='seconds')}",
        f"- machine: processor `{platform.processor() or '?'}`, machine `{platform.machine()}`, "
        f"CPU `{cpu}`, {os.cpu_count()} cores",
        f"- python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"numba {numba.__version__}, harvester_sweep {harvester_sweep.__version__}",
        f"- code: commit {git('rev-parse', '--short', 'HEAD') or '?'}"
        + (f", with uncommitted changes in: {', '.join(changed)}" if changed else ", clean"),
    ]


def _fmt(x):
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.2e}"


def scene_table(rows):
    lines = ["| method | setting | run time [s] | rel. err. mean power | rel. err. peak V "
             "| rel. err. final state | order (power) | order (state) | notes |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
    for row in rows:
        status = row.get("status", "ok")
        if "errors" in row:
            cells = ["-" if not math.isfinite(row["time"]) else
                     f"{row['time']:.4f}" if row["time"] < 1 else f"{row['time']:.2f}",
                     *(_fmt(e) for e in row["errors"])]
        else:
            cells = ["-", status, "", ""]
        order = row.get("order")
        cells += [f"{order[0]:.2f}", f"{order[2]:.2f}"] if order else ["", ""]
        lines.append(f"| {row['method']} | {row['setting']} | " + " | ".join(cells)
                     + f" | {row.get('notes', '')} |")
    return lines


def plot(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(5.2 * len(results), 4.8))
    styles = {
        "engine, located": dict(color="black", lw=2.2, marker="o", ms=5),
        "engine, plain steps": dict(color="0.45", lw=1.6, ls="--", marker="s", ms=4,
                                    mfc="white"),
        "SciPy RK45": dict(color="tab:blue", marker="^"),
        "SciPy DOP853": dict(color="tab:orange", marker="v"),
        "SciPy LSODA": dict(color="tab:green", marker="D", ms=4),
        "SciPy Radau": dict(color="tab:red", marker="P"),
    }
    floor = 1e-17
    for ax, (scene, data) in zip(np.atleast_1d(axes), results.items()):
        for method, style in styles.items():
            pts = [(r["time"], max(r["errors"][0], floor)) for r in data["rows"]
                   if r["method"] == method and "errors" in r]
            if pts:
                t, e = np.array(pts).T
                ax.plot(np.log10(t), np.log10(e), label=method, **style)
        for r in data["rows"]:  # step counts next to the located engine's points
            if r["method"] == "engine, located" and "errors" in r:
                ax.annotate(str(r["n"]), (math.log10(r["time"]),
                                          math.log10(max(r["errors"][0], floor))),
                            textcoords="offset points", xytext=(4, 3), fontsize=7)
        check = data["check_errors"][0]
        ax.axhline(math.log10(max(check, floor)), color="0.6", lw=0.8, ls=":")
        ax.text(0.99, math.log10(max(check, floor)), f"reference check ({data['check_label']})",
                transform=ax.get_yaxis_transform(), ha="right", va="bottom", fontsize=7,
                color="0.4")
        ax.set_title(f"{scene}")
        ax.set_xlabel("log10 run time [s]")
        ax.set_ylabel("log10 relative error in mean power")
        ax.grid(alpha=0.3)
    handles, labels = np.atleast_1d(axes)[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=9,
               frameon=False)
    fig.suptitle(f"Work-precision, {K} forcing periods from rest, mean power over the last "
                 f"{WINDOW} (engine: diverged runs omitted; numbers: steps per period)",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)


# -------------------------------------------------------------------------------- main

def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="fewer step counts and tolerances (a smoke test); writes "
                             "work_precision_quick.md/.png")
    args = parser.parse_args(argv)
    config = QUICK if args.quick else FULL
    command = "python -m benchmarks.work_precision" + (" --quick" if args.quick else "")
    wall = time.perf_counter()
    # One point runs on one thread anyway; a one-thread team keeps the engine's timing free
    # of thread wake-ups on a loaded machine (SciPy is single-threaded too).
    numba.set_num_threads(1)
    from harvester_sweep._engine.steady import MAX_ORBIT_PERIOD

    assert MAX_ORBIT_PERIOD == WINDOW, "the engine's metrics window changed"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run_scene("paper", steps_per_period=64, max_periods=1)  # compile / load the cache

    results = {}
    for scene, overrides in SCENES.items():
        print(f"{scene}:", flush=True)
        p = resolve_parameters("paper", **overrides)
        # Reference atol: x scaled by |gap| + 1e-6 m there; keep it ~2e-20 m with a far stop.
        atol_scale = 1e-14 * 2e-6 / (abs(p["gap"]) + 1e-6)
        ref = reference_solution(p, config["ref_rtol"], atol_scale)
        print(f"  reference rtol {config['ref_rtol']:.0e}: {ref['time']:.1f} s, "
              f"{ref['impacts']:g} impacts/period", flush=True)
        rows = []
        for rtol in config["check_rtols"]:
            check = reference_solution(p, rtol, atol_scale)
            rows.append(dict(method="reference check",
                             setting=f"rtol {rtol:.0e} vs {config['ref_rtol']:.0e}",
                             time=check["time"],
                             errors=errors(check["power"], check["peak"], check["state"], ref),
                             notes=f"reference (rtol {config['ref_rtol']:.0e}) run time "
                                   f"{ref['time']:.1f} s"))
            print(f"  check rtol {rtol:.0e}: differences {rows[-1]['errors']}", flush=True)
        check_errors, check_label = rows[-1]["errors"], rows[-1]["setting"]
        # the reference's own error in mean power: the tightest check, and the exact solution
        floor = max(r["errors"][0] for r in rows[len(config["check_rtols"]) - 1:])
        if p["gap"] > 0.1:  # no contact: the exact solution checks the reference itself
            exact = closed_form_linear(p, (K - WINDOW) / p["frequency"], K / p["frequency"])
            if exact is not None:
                rows.append(dict(method="reference vs exact", setting="closed form (mpmath)",
                                 time=math.nan, errors=errors(ref["power"], ref["peak"],
                                                              ref["state"],
                                                              dict(ref, power=exact[0],
                                                                   peak=exact[1],
                                                                   state=exact[2])),
                                 notes="linear model solved exactly from rest"))
                print(f"  reference vs closed form: {rows[-1]['errors']}", flush=True)
        for locate in (True, False):
            rows += engine_rows(overrides, ref, config["steps"], locate)
        print("  engine done", flush=True)
        for method in METHODS:
            rows += scipy_rows(p, ref, method, config["rtols"])
        for row in rows:  # errors within 3x of the reference's own error estimate
            if row["method"].startswith(("engine", "SciPy")) and "errors" in row \
                    and row["errors"][0] < 3 * floor:
                row["notes"] = "; ".join(filter(None, [row.get("notes"),
                                                       "power err. at reference floor"]))
        peak_check = peak_measurement_check(p, ref)
        results[scene] = dict(p=p, ref=ref, rows=rows, check_errors=check_errors,
                              check_label=check_label, peak_check=peak_check)

    lines = [f"# Work-precision: RK4 engine vs SciPy, {K} periods from rest", ""]
    lines += machine_lines(command)
    lines += [
        "",
        f"Errors are relative to the reference (tests/helpers.py, DOP853 restarted at every "
        f"contact onset and separation, rtol {config['ref_rtol']:.0e}): mean power V^2/R and "
        f"peak |V| over the last {WINDOW} of {K} forcing periods, final state (x, v, V) as "
        "max over components of |diff| / amplitude over the window. The 'reference check' "
        "rows compare the reference at looser rtol with it; the 'reference vs exact' row (no "
        "contact) compares it with the closed-form solution. Errors near those differences "
        "are at the reference's accuracy floor (flagged in the notes when the power error is "
        "below 3 times the larger of the tightest check and the exact comparison). "
        "Order: log(error ratio) / log(step ratio) between successive step counts n. Run "
        f"time: best of 3 (1 run above {REPEAT_BELOW_S:g} s), compilation excluded; engine "
        f"on one numba thread. SciPy runs are stopped at {CAP_S:g} s.",
        "",
    ]
    for scene, data in results.items():
        ref = data["ref"]
        lines += [
            f"## {scene}",
            "",
            f"Reference: mean power {ref['power']:.10e} W, peak |V| {ref['peak']:.10e} V, "
            f"final state x = {ref['state'][0]:.6e} m, v = {ref['state'][1]:.6e} m/s, "
            f"V = {ref['state'][2]:.6e} V; {ref['impacts']:g} impacts per period over the "
            f"window; amplitudes (x, v, V) = "
            + ", ".join(f"{a:.4e}" for a in ref["amplitudes"])
            + "; no-tension clip active in a contact piece: "
            + ("yes." if ref["clip_active"] else "no.")
            + f" Peak measurement check (DOP853 rtol 1e-11: event-located vs root search on its "
            f"dense output): {data['peak_check']:.1e}.",
            "",
            *scene_table(data["rows"]),
            "",
        ]
    total = time.perf_counter() - wall
    lines.append(f"Total wall time of the benchmark: {total:.0f} s.")
    text = "\n".join(lines) + "\n"
    suffix = "_quick" if args.quick else ""
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f"work_precision{suffix}.md").write_text(text)
    plot(results, RESULTS / f"work_precision{suffix}.png")
    print()
    print(text)


if __name__ == "__main__":
    main()
