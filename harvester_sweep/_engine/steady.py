"""Steady state: the orbit period from the stroboscopic samples y(nT), and the metrics
reduced from the per-period accumulators (layouts.ACC) of the last orbit.

The forcing phase is measured from the start of a forcing period, so the state at a
period boundary is a stroboscopic sample y(nT) and can be continued at another frequency.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import JIT, njit
from .layouts import ACC, METRIC, PARAM, STATE

MAX_ORBIT_PERIOD = 16  # longest orbit period p looked for, in forcing periods
GAP_HISTORY = 4 * MAX_ORBIT_PERIOD  # periods of e_p(n) kept to estimate the decay rate


@njit(**JIT)
def orbit_period(ring, acc, gaps, n, ring_len, tol, v_per_x, e_per_x):
    """Orbit period p once the transient left in y(nT) is below ``tol``, else 0.

    The gap e_p(n) = |y(nT) - y((n-p)T)| (largest over x, v, V, each relative to its
    amplitude over the last p periods) shrinks geometrically, by rho = e_p(n) / e_p(n-p)
    per p periods, so the transient still left is about e_p(n) / (1 - rho). Testing that
    estimate, not e_p(n) alone, keeps slow transients (rho near 1, light damping) and
    transients that alternate in sign (a multiplier near -1 mimics p = 2) from passing
    for a steady state; rho is the largest of the last three ratios because beating
    modes make single ratios jump. Once settled at p, the smallest divisor of p that
    also repeats is the orbit period.

    A period p is tested at the multiples of p only (n = p, 2p, ...; the ratios compare
    those, and a divisor of p is tested whenever p is): the 16 candidates cost about 3.4
    tests a period rather than 16, and a p-periodic orbit is found at most p - 1 periods
    later than it would be at every period.
    """
    row = n % GAP_HISTORY
    found = 0
    xs, vs, es = 0.0, 0.0, 0.0  # amplitudes over the last `period` periods, grown with it
    for period in range(1, min(n, MAX_ORBIT_PERIOD) + 1):
        slot = (n - period) % MAX_ORBIT_PERIOD
        xs = max(xs, abs(acc[slot, ACC.x_max]), abs(acc[slot, ACC.x_min]))
        vs, es = max(vs, acc[slot, ACC.v_max]), max(es, acc[slot, ACC.v_peak])
        if n % period != 0:  # (a period p is tested every p periods: see above)
            continue
        e = gap(ring, n, period, ring_len, xs, max(vs, v_per_x * xs), max(es, e_per_x * xs))
        gaps[row, period] = e
        if found == 0 and e <= tol:  # (else neither test below can pass)
            rho = 0.0
            for k in range(3):
                later = gaps[(n - k * period) % GAP_HISTORY, period]
                earlier = gaps[(n - (k + 1) * period) % GAP_HISTORY, period]
                rho = max(rho, later / earlier if 0.0 < earlier < np.inf else np.inf)
            # (or at the rounding floor, where ratios are noise)
            if e <= 1e-5 * tol or (rho < 1.0 and e <= tol * (1.0 - rho)):
                found = period
    if found > 1:
        for d in range(1, found):
            if found % d == 0 and gaps[row, d] <= 8.0 * tol:
                return d
    return found


@njit(inline="always", **JIT)
def gap(ring, n, period, ring_len, xs, vs, es):
    """max over (x, v, V) of |y(nT) - y((n-period)T)| / its amplitude (xs, vs, es) over the
    last ``period`` periods.

    The caller floors the velocity and voltage amplitudes at what the displacement
    amplitude implies (v ~ w x, V ~ theta x / C_p), so that a component at rest (pure
    rounding noise) does not hold the test back.
    """
    a, b = ring[n % ring_len], ring[(n - period) % ring_len]
    e = 0.0
    if xs > 0.0:
        e = max(e, abs(a[STATE.x] - b[STATE.x]) / xs)
    if vs > 0.0:
        e = max(e, abs(a[STATE.v] - b[STATE.v]) / vs)
    if es > 0.0:
        e = max(e, abs(a[STATE.voltage] - b[STATE.voltage]) / es)
    return e


@njit(**JIT)
def reduce(acc, n, periods, p, metrics):
    """Metrics over the last ``periods`` forcing periods from the per-period accumulators."""
    q, n_imp, sum_vimp, n_low, fc_low = 0.0, 0.0, 0.0, 0.0, 0.0
    xmax, xmin, vpk, fcmax = -np.inf, np.inf, 0.0, 0.0
    smax, peak_min, peak_max, miss, vimp_min = 0.0, np.inf, -np.inf, np.inf, np.inf
    for i in range(periods):
        slot = (n - 1 - i) % MAX_ORBIT_PERIOD
        q += acc[slot, ACC.q]
        xmax, xmin = max(xmax, acc[slot, ACC.x_max]), min(xmin, acc[slot, ACC.x_min])
        vpk, fcmax = max(vpk, acc[slot, ACC.v_peak]), max(fcmax, acc[slot, ACC.fc_max])
        n_imp += acc[slot, ACC.impacts]
        sum_vimp += acc[slot, ACC.sum_vimp]
        n_low += acc[slot, ACC.impacts_lower]
        fc_low = max(fc_low, acc[slot, ACC.fc_max_lower])
        smax = max(smax, acc[slot, ACC.stop_x_max])
        peak_min = min(peak_min, acc[slot, ACC.fc_peak_min])
        peak_max = max(peak_max, acc[slot, ACC.fc_peak_max])
        miss = min(miss, acc[slot, ACC.near_miss])
        vimp_min = min(vimp_min, acc[slot, ACC.vimp_min])
    mean_v2 = q / (max(periods, 1) * p[PARAM.period])
    metrics[METRIC.power] = mean_v2 / p[PARAM.resistance]
    metrics[METRIC.v_rms] = math.sqrt(mean_v2)
    metrics[METRIC.v_peak] = vpk
    metrics[METRIC.power_peak] = vpk * vpk / p[PARAM.resistance]
    metrics[METRIC.x_max], metrics[METRIC.x_min] = xmax, xmin
    metrics[METRIC.contact_force_max] = fcmax
    metrics[METRIC.impacts_per_period] = n_imp / max(periods, 1)
    metrics[METRIC.approach_velocity] = sum_vimp / n_imp if n_imp > 0 else np.nan
    metrics[METRIC.impacts_per_period_lower] = n_low / max(periods, 1)
    metrics[METRIC.contact_force_max_lower] = fc_low
    metrics[METRIC.stop_displacement_max] = smax
    # (no located peak: no impact, or contacts too short for three force samples)
    metrics[METRIC.contact_force_spread] = peak_max - peak_min if peak_max >= peak_min \
        else (0.0 if n_imp == 0 else np.nan)
    # (no swing's top short of a rigid stop; no first touch)
    metrics[METRIC.near_miss] = miss if miss < np.inf else np.nan
    metrics[METRIC.approach_velocity_min] = vimp_min if vimp_min < np.inf else np.nan
