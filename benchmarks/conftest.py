"""The speed benchmark's one table: every figure of test_speed.py, ratios taken in this run.

    python -m pytest benchmarks/test_speed.py              # about 2 minutes
    python -m pytest benchmarks/test_speed.py --million    # and the 1e6-point sweep (minutes)

The tests put their figures in ``FIGURES``; at the end of the session the table is printed
and written to ``benchmarks/results/speed.md`` (when every benchmark ran).
"""

from __future__ import annotations

import os
import platform
import time
from pathlib import Path

import pytest

from benchmarks.cases import COLD_START_ROUNDS, SWEEP_ROUNDS

ROOT = Path(__file__).resolve().parents[1]

FIGURES: dict = {}
RESULT = ROOT / "benchmarks" / "results" / "speed.md"
FLOPS_PER_STEP = 100  # one RK4 step of this system, counted by hand (4 stages + update)


def pytest_addoption(parser):
    parser.addoption("--million", action="store_true",
                     help="also run the one-million-point 4-D sweep (several minutes)")


def pytest_collection_modifyitems(items):
    """Run the diffrax cases after every measurement of the engine, and the 1e6-point
    sweep last: XLA's threads stay busy for a while after a diffrax run, and the engine's
    two-thread time measured next was 1.4-3x slower (0.20-0.41 ms per point against
    0.14-0.28 alone)."""
    items.sort(key=lambda item: 2 if "million" in item.name else "diffrax" in item.name)


@pytest.fixture(scope="session")
def figures() -> dict:
    return FIGURES


def cpu() -> dict:
    """CPU model, cores, clock [Hz], double-precision flops per cycle per core and peak."""
    text = Path("/proc/cpuinfo").read_text()
    lines = text.splitlines()
    model = next((line.split(":", 1)[1].strip() for line in lines
                  if line.startswith("model name")), platform.processor())
    mhz = max(float(line.split(":", 1)[1]) for line in lines if line.startswith("cpu MHz"))
    flags = next(line for line in lines if line.startswith("flags")).split()
    width = 8 if "avx512f" in flags else 4 if "avx" in flags else 2
    simd = "AVX-512" if width == 8 else "AVX2" if width == 4 else "SSE2"
    # The width the CPU executes, not the one it decodes: AMD Zen 1 and Zen+ (family 23,
    # models below 0x30) split a 256-bit AVX2 operation into two 128-bit ones, so their
    # vector gain is half (8 DP flops per cycle per core, not 16).
    field = {line.split(":", 1)[0].strip(): line.split(":", 1)[1].strip() for line in lines
             if ":" in line and line.split(":", 1)[0].strip() in ("vendor_id", "cpu family",
                                                                  "model")}
    if (field.get("vendor_id") == "AuthenticAMD" and field.get("cpu family") == "23"
            and int(field.get("model", "0")) < 0x30):
        width, simd = min(width, 2), simd + " on 128-bit units"
    per_cycle = width * 2 * (2 if "fma" in flags else 1)  # two FMA pipes, an FMA counts 2
    cores = len(os.sched_getaffinity(0))
    return {"model": model, "cores": cores, "clock": mhz * 1e6, "per_cycle": per_cycle,
            "simd": simd,
            "peak": cores * mhz * 1e6 * per_cycle}


def _table(f: dict) -> str:
    c = cpu()
    import numba

    def share(rate, cores=None):
        peak = c["peak"] / c["cores"] * (cores or c["cores"])
        return f"{100 * rate * FLOPS_PER_STEP / peak:.1f} % of peak"

    rows = [
        "# Speed of the sweep engine",
        "",
        f"- command: `python -m pytest benchmarks/test_speed.py"
        f"{' --million' if 'million_wall' in f else ''}`; {time.strftime('%Y-%m-%d %H:%M')}",
        f"- machine: {c['model']}, {c['cores']} cores at {c['clock'] / 1e9:.2f} GHz, {c['simd']}, "
        f"{c['per_cycle']} DP flops/cycle/core: peak {c['peak'] / 1e9:.0f} GFLOP/s; "
        f"numba {numba.__version__}, {numba.get_num_threads()} threads"
        f" ({numba.threading_layer() if hasattr(numba, 'threading_layer') else ''})",
        "- the steps/s share of peak counts ~100 flops per RK4 step, as a step's four stages"
        " take; the engine applies a contact-free step as its linear map, in ~50 with the commit",
        "",
        "| measure | value | |",
        "| --- | ---: | --- |",
    ]
    if "sweep_rate" in f:
        rows += [
            f"| 64 x 64 gap x frequency sweep of the paper scene, 1024 steps/period, end to end "
            f"(run_sweep to netCDF; each sweep best of {SWEEP_ROUNDS}) | {f['sweep_wall']:.2f} s | "
            f"{f['sweep_steps']:.3g} RK4 steps |",
            f"| ... RK4 steps per second | {f['sweep_rate'] / 1e6:.0f} M/s | "
            f"{share(f['sweep_rate'])} |",
        ]
    if "free_rate" in f:
        rows.append(f"| the same grid with the stop out of reach (gap 1 m), end to end | "
                    f"{f['free_wall']:.2f} s | {f['free_steps']:.3g} RK4 steps (each orbit "
                    f"solved directly) |")
    if "continued_rate" in f:
        rows.append(f"| 32 x 64 gap x frequency, swept up and down (each point from the state "
                    f"of the frequency before): steps per second | "
                    f"{f['continued_rate'] / 1e6:.0f} M/s | {share(f['continued_rate'])} |")
    if "loop_free" in f:
        rows.append(f"| the vector loop alone, one core, lane-steps per second: no lane in contact "
                    f"/ all in contact | {f['loop_free'] / 1e6:.0f} M/s / "
                    f"{f['loop_contact'] / 1e6:.0f} M/s | {share(f['loop_free'], 1)} of one core "
                    f"(no contact) |")
    n = f.get("ensemble")
    for accuracy, row in sorted(f.get("points", {}).items(), reverse=True):
        rows.append(f"| paper scene from rest to its periodic orbit (accuracy {accuracy:g}: "
                    f"{row['periods']} periods of motion, {row['rk4_steps']:,} RK4 steps at "
                    f"{row['steps']} a period, multipliers and error estimate included), "
                    f"ensemble of {n}: engine per point, {row['threads']} threads / 1 thread | "
                    f"{row['engine'] * 1e3:.3f} ms / {row['engine_1'] * 1e3:.3f} ms | "
                    f"distance from the exact orbit {row['error']:.1e} |")
        for key, name in (("lsoda", "SciPy LSODA, one point (1 core)"),
                          ("diffrax", f"JAX/diffrax Tsit5 vmap x{n} (XLA: 1 core busy)")):
            if key in row:
                rows.append(f"| ... {name}, from rest until within the same distance "
                            f"({row[key + '_how']}) | "
                            f"{row[key] * 1e3:.2f} ms | **{row[key] / row['engine']:.0f} x** "
                            f"the engine; {row[key] / row['engine_1']:.0f} x per core |")
            elif key == "diffrax" and "diffrax_skipped" in f:
                rows.append(f"| ... {name} | skipped | {f['diffrax_skipped']} |")
    if "cold_start" in f:
        rows.append(f"| one-point sweep in a new process, on-disk cache warm "
                    f"(`harvester-sweep run`, best of {COLD_START_ROUNDS}) | "
                    f"{f['cold_start']:.2f} s | |")
    if "million_wall" in f:
        # (the run and its machine in the row: a later run without --million carries it)
        when = f"{time.strftime('%Y-%m-%d %H:%M')} on {c['model']}, {c['simd']}"
        rows.append(f"| 1e6-point gap x frequency x resistance x restitution sweep "
                    f"(examples/million_points.toml, automatic step; run {when}"
                    f") | {f['million_wall'] / 60:.1f} min | peak memory "
                    f"{f['million_rss'] / 2**30:.2f} GiB; {f['million_settled']} settled |")
    else:  # (several minutes, so not every run: the last measured, with its run)
        old = RESULT.read_text().splitlines() if RESULT.exists() else []
        rows += [line for line in old if line.startswith("| 1e6-point")]
    return "\n".join(rows) + "\n"


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    if not FIGURES:
        return
    text = _table(FIGURES)
    terminalreporter.write_sep("=", "speed of the sweep engine")
    terminalreporter.write(text)
    points = FIGURES.get("points", {})
    complete = (all(k in FIGURES for k in ("sweep_rate", "free_rate", "continued_rate",
                                           "loop_free", "cold_start"))
                and len(points) == 2 and all("lsoda" in row for row in points.values()))
    if complete and exitstatus == 0:
        RESULT.write_text(text)
        terminalreporter.write(f"written: {RESULT.relative_to(ROOT)}\n")
