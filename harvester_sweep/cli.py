"""The ``harvester-sweep`` command line."""

from __future__ import annotations

import argparse
import contextlib
import json
import re
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from .parameters import (
    DEFAULT_PRESET,
    PARAMETERS,
    PRESETS,
    ParameterError,
    StabilityWarning,
    parse_assignment,
    resolve_parameters,
)

EXIT_USER_ERROR = 2
EXIT_DIVERGED = 3
EXIT_INTERRUPTED = 130  # the shell's code for a run stopped by Ctrl-C (128 + SIGINT)


class _OneLineParser(argparse.ArgumentParser):
    """argparse's parser whose usage errors are one line, as every bad input's is (exit 2),
    naming the command's --help rather than printing its usage; a negative number in
    exponent form (``-1e-6``, a preloaded gap) is a value, as ``-0.5`` is, not an option."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # (argparse's own pattern, which takes -1 and -0.5 for values, with an exponent)
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _parser() -> argparse.ArgumentParser:
    parser = _OneLineParser(
        prog="harvester-sweep",
        description="Steady states of a piezoelectric cantilever harvester striking a Hertz bump "
        "stop (SI units throughout).",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    scene = sub.add_parser(
        "scene", help="run one parameter point to steady state",
        description="Run one parameter point (a preset with --set overrides, SI units) from "
        "rest to its steady state, the periodic orbit it settles on, and print its metrics "
        "(power, voltages, x_max, contact force, Floquet multipliers, error estimate) as a "
        "table or JSON; optionally write the orbit to netCDF and draw the paper's Fig. 3.")
    scene.add_argument("--preset", default=DEFAULT_PRESET, choices=sorted(PRESETS),
                       help=f"starting parameter set (default: {DEFAULT_PRESET}, the paper's "
                       "Table 1)")
    scene.add_argument("--set", dest="assignments", action="append", default=[],
                       metavar="NAME=VALUE",
                       help="override a parameter in SI units, e.g. --set gap=2e-6 (repeatable; "
                       "see 'harvester-sweep parameters')")
    scene.add_argument("--json", action="store_true",
                       help="print the metrics as one JSON object on stdout")
    scene.add_argument("--plot", metavar="FIG.png",
                       help="draw displacement, voltage, power and contact force (paper Fig. 3)")
    scene.add_argument("--output", metavar="FILE.nc",
                       help="write the last orbit periods and the metrics to netCDF")

    listing = sub.add_parser(
        "parameters", help="list the parameters, their units, ranges and presets",
        description="Print every parameter with its SI unit, allowed range and meaning, then "
        "each preset's value of every parameter (the names --set, sweep files and output "
        "files use).")
    listing.add_argument("--model", default="tip_mass", choices=("tip_mass", "beam"),
                         help="the tip-mass model (default; 'scene', 'run', 'continue', "
                         "'basins') or the beam ('beam-scene', 'beam-sweep')")

    beam_scene = sub.add_parser(
        "beam-scene", help="run one point of the beam model to steady state",
        description="Run one point of the beam model (a bimorph in n_modes bending modes "
        "striking a rigid or rod stop; a preset with --set overrides, SI units) to its "
        "periodic orbit and print its outputs as a table or JSON; optionally write the "
        "orbit's time history to netCDF.")
    _beam_common(beam_scene)
    beam_scene.add_argument("--periods", type=int, default=2, metavar="N",
                            help="forcing periods of the orbit to record with --output "
                            "(default: 2)")
    beam_scene.add_argument("--json", action="store_true",
                            help="print the outputs as one JSON object on stdout")
    beam_scene.add_argument("--output", "--out", dest="output", metavar="FILE.nc",
                            help="write the orbit's time history to netCDF")

    beam_sweep = sub.add_parser(
        "beam-sweep", help="steady states of the beam model over a grid, into netCDF",
        description="Solve the beam model at every point of a grid (a sweep file with "
        "model = \"beam\", or one --axis per swept parameter) and write the CF dataset. "
        "With directions (--direction), each line along frequency is swept in that "
        "direction, every point starting from the previous one's orbit (the stop's "
        "hysteresis). Finished chunks are kept in OUT.nc.partial/ for --resume.")
    beam_sweep.add_argument("sweep_file", nargs="?", metavar="SWEEP.toml",
                            help="a sweep file with model = \"beam\" (see "
                            "examples/beam_frequency_response.toml); or give --axis")
    _beam_common(beam_sweep)
    beam_sweep.add_argument("--axis", dest="axes", action="append", default=[],
                            metavar="NAME=SPEC",
                            help="a grid axis: NAME=START:STOP:COUNT (evenly spaced, ends "
                            "included) or NAME=V1,V2,... (repeatable), e.g. "
                            "--axis frequency=120:170:26")
    beam_sweep.add_argument("--direction", choices=("up", "down", "both"),
                            help="sweep each frequency line up, down or both ways (needs a "
                            "frequency axis; default: every point from its linear steady "
                            "state)")
    beam_sweep.add_argument("--output", "--out", dest="output", required=True,
                            metavar="OUT.nc", help="netCDF file to write")
    beam_sweep.add_argument("--resume", action="store_true",
                            help="finish an interrupted run from the chunks in "
                            "OUT.nc.partial/")
    beam_sweep.add_argument("--quiet", action="store_true",
                            help="no estimate and no progress lines")
    beam_sweep.add_argument("--yes", action="store_true",
                            help="start the sweep even when it is estimated to take more "
                            "than an hour")
    beam_where = beam_sweep.add_mutually_exclusive_group()
    beam_where.add_argument("--workers", type=int, metavar="N",
                            help="solve the grid in chunks on a local dask cluster of N "
                            "worker processes")
    beam_where.add_argument("--scheduler", metavar="ADDRESS",
                            help="solve the grid in chunks on a running dask.distributed "
                            "scheduler, e.g. tcp://127.0.0.1:8786")

    beam_branch = sub.add_parser(
        "beam-continue", help="a branch of the beam model's orbits through folds, into "
        "netCDF",
        description="Follow the branch of periodic orbits of a beam point in one parameter "
        "from START towards STOP through folds (pseudo-arclength), locating folds, period "
        "doublings, Neimark-Sacker points and grazings, and write the CF dataset.")
    _beam_common(beam_branch)
    beam_branch.add_argument("parameter", help="the parameter followed, e.g. frequency")
    beam_branch.add_argument("start", type=float, help="its first value (SI units)")
    beam_branch.add_argument("stop", type=float, help="the value the branch heads for")
    beam_branch.add_argument("--step", type=float, default=0.01,
                             help="arclength step in units of the range (default 0.01)")
    beam_branch.add_argument("--max-points", type=int, default=400, dest="max_points",
                             help="points at most (default 400)")
    beam_branch.add_argument("--period-doubling", choices=("mark", "switch"), default="mark",
                             dest="period_doubling",
                             help="at a period doubling: mark it (default), or also follow "
                             "the branch of doubled orbits (up to 8 forcing periods)")
    beam_branch.add_argument("--output", "--out", dest="output", required=True,
                             metavar="OUT.nc", help="netCDF file to write")

    beam_basin = sub.add_parser(
        "beam-basins", help="basins of attraction of one beam point, into netCDF",
        description="Run a beam point from SAMPLES starts around its linear steady state "
        "(in the first mode's plane), group the orbits reached, measure each attractor and "
        "write the CF dataset.")
    _beam_common(beam_basin)
    beam_basin.add_argument("--samples", type=int, default=64, help="starts (default 64)")
    beam_basin.add_argument("--seed", type=int, default=0, help="the starts' seed (default 0)")
    beam_basin.add_argument("--box", type=float, default=2.0,
                            help="half-width of the box of starts in units of the first "
                            "mode's linear amplitude and rate (default 2)")
    beam_basin.add_argument("--output", "--out", dest="output", required=True,
                            metavar="OUT.nc", help="netCDF file to write")

    run = sub.add_parser("run", help="run a sweep file (TOML) into a netCDF dataset",
                         description="Run every point of a sweep file to steady state and write "
                         "the frequency-response / bifurcation dataset (see "
                         "examples/paper_frequency_response.toml).")
    run.add_argument("sweep_file", metavar="SWEEP.toml", help="the sweep file")
    run.add_argument("--output", required=True, metavar="OUT.nc", help="netCDF file to write")
    run.add_argument("--resume", action="store_true",
                     help="finish an interrupted run from the chunks in OUT.nc.partial/")
    run.add_argument("--quiet", action="store_true",
                     help="no estimate, no progress bar and no summary (warnings, such "
                     "as points that did not settle, are still said)")
    run.add_argument("--yes", action="store_true",
                     help="start the sweep even when it is estimated to take more than an hour")
    where = run.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N",
                       help="run the chunks on a local dask cluster of N worker processes")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="run the chunks on a running dask.distributed scheduler, "
                       "e.g. tcp://127.0.0.1:8786")

    branch = sub.add_parser(
        "continue", help="follow a branch of periodic orbits in one parameter (TOML)",
        description="Follow the branch of periodic orbits reached from rest at the start value "
        "through folds to the stop value, with its stability and located bifurcations (see "
        "examples/paper_s_curve.toml); the bifurcations are listed on stdout.")
    branch.add_argument("spec_file", metavar="SPEC.toml", help="the continuation file")
    branch.add_argument("--output", required=True, metavar="BRANCH.nc",
                        help="netCDF file to write")
    branch.add_argument("--plot", metavar="FIG.png", help="draw the branch")

    basins = sub.add_parser(
        "basins", help="which coexisting orbit the device lands on, over a grid (TOML)",
        description="Solve many starts (a box around rest, or the states a base shock leaves) "
        "at every grid point to their attractors and write each attractor's basin fraction "
        "(see examples/paper_basins.toml); a summary goes to stdout.")
    basins.add_argument("spec_file", metavar="SPEC.toml", help="the basin file")
    basins.add_argument("--output", required=True, metavar="BASINS.nc",
                        help="netCDF file to write")
    basins.add_argument("--plot", metavar="FIG.png",
                        help="draw the impact basin fraction over the grid")
    basins.add_argument("--quiet", action="store_true", help="no estimate and no progress bar")
    basins.add_argument("--yes", action="store_true",
                        help="start the map even when it is estimated to take more than an hour")

    plot = sub.add_parser("plot", help="draw a sweep, scene, branch or basins netCDF file")
    plot.add_argument("dataset", metavar="OUT.nc",
                      help="a file written by 'run', 'scene', 'continue' or 'basins'")
    plot.add_argument("--output", required=True, metavar="FIG.png",
                      help="figure to write (.png, .pdf or .svg)")
    plot.add_argument("--over", metavar="SWEEP.nc", action="append", default=[],
                      help="with a branch: a sweep along the same parameter to draw under it "
                      "(its up and down directions; repeatable)")
    plot.add_argument("--log", metavar="AXIS", action="append", default=[],
                      help="draw this grid axis or continued parameter on a log axis "
                      "(default: where it is spaced log or spans two decades; repeatable)")
    plot.add_argument("--linear", metavar="AXIS", action="append", default=[],
                      help="draw this grid axis or continued parameter on a linear axis")
    return parser


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    shown = _Warnings()
    try:
        with warnings.catch_warnings():
            warnings.showwarning = shown
            return _main(args)
    finally:
        shown.close()


class _Warnings:
    """Warnings as one line each on stderr, without the source line a script's user cannot
    act on. A StabilityWarning is shown once: an explicit step beyond the contact's bound
    gives one for every parameter set it is checked on, each naming its own step (hundreds
    in a sweep); how many more there were is said at the end."""

    def __init__(self):
        self.stability = 0

    def __call__(self, message, category, filename, lineno, file=None, line=None) -> None:
        if issubclass(category, StabilityWarning):
            self.stability += 1
            if self.stability > 1:
                return
        print(f"harvester-sweep: warning: {message}", file=sys.stderr)

    def close(self) -> None:
        if self.stability > 1:
            print(f"harvester-sweep: warning: and {self.stability - 1} more parameter sets "
                  "with the step beyond the estimated stability bound", file=sys.stderr)


def _main(args) -> int:
    _WRITTEN.clear()
    try:
        if args.command == "parameters":
            return _print_parameters(args.model)
        if args.command == "beam-scene":
            return _beam_scene(args)
        if args.command == "beam-sweep":
            return _beam_sweep(args)
        if args.command in ("beam-continue", "beam-basins"):
            return _beam_branch_or_basins(args)
        if args.command == "plot":
            return _plot(args)
        if args.command == "run":
            return _run(args)
        if args.command == "continue":
            return _continue(args)
        if args.command == "basins":
            return _basins(args)
        return _scene(args)
    except ParameterError as error:
        print(f"harvester-sweep: error: {error}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:  # ('run' says what it keeps for --resume itself)
        done = (f"after writing {', '.join(_WRITTEN)}" if _WRITTEN
                else "before any file was written")
        print(f"harvester-sweep: interrupted {done}", file=sys.stderr)
        return EXIT_INTERRUPTED


#: The files the command has written so far (said when Ctrl-C stops it).
_WRITTEN = []


def _announce_compilation() -> None:
    from .orbits import solver_ready

    if not solver_ready():
        print("harvester-sweep: compiling the RK4 kernel and the orbit solver into numba's "
              "on-disk cache (first run only, a few minutes)", file=sys.stderr, flush=True)


def _scene(args) -> int:
    from .scene import check_scene, run_scene

    overrides = dict(parse_assignment(text) for text in args.assignments)
    for path, suffixes in ((args.plot, _FIGURES), (args.output, (".nc",))):
        if path is not None:
            _check_output(path, suffixes)
    # (checked once, before anything else: bad input or a too stiff point is one line; the
    # scene takes the checked values as they are)
    spec = check_scene(args.preset, **overrides)
    _announce_compilation()
    result = run_scene(spec)
    metrics = result.metrics
    if args.json:
        print(json.dumps(metrics))
    else:
        print(_table(result, args.preset))
    if metrics["status"] == "diverged":
        print(
            f"harvester-sweep: the integration diverged after {metrics['periods_run']} periods: "
            f"steps_per_period = {metrics['steps_per_period']} is too coarse for this contact; "
            "no metrics are reported. Raise steps_per_period.",
            file=sys.stderr,
        )
        return EXIT_DIVERGED
    if metrics["status"] == "not settled":
        from ._engine import MAX_ORBIT_PERIOD
        from .timescales import slowest_decay

        rate, what = slowest_decay(result.parameters)
        print(f"harvester-sweep: warning: no steady state within max_periods = "
              f"{result.parameters['max_periods']} (slowest transient without the stop: {what}, "
              f"{rate * 1 / result.parameters['frequency']:.3g} e-folds per period); the motion "
              "may be chaotic or need more periods: the metrics are over the last "
              f"{min(metrics['periods_run'], MAX_ORBIT_PERIOD)} periods",
              file=sys.stderr)
    if args.output:
        with _writing(args.output):
            result.to_netcdf(args.output)
    if args.plot:
        with _writing(args.plot):
            result.plot(args.plot)
    return 0


@contextlib.contextmanager
def _writing(path: str):
    """Turn a file that cannot be written (no folder, no permission, a full disk) into one
    line, exit 2."""
    from .chunk_store import write_failure

    try:
        yield
    except OSError as error:
        raise ParameterError(f"cannot write {path}: {write_failure(path, error)}") from None
    _WRITTEN.append(path)


_FIGURES = (".png", ".pdf", ".svg")


def _check_output(path: str, suffixes: tuple) -> None:
    """Refuse, before any work, a file name that cannot be written as asked."""
    if not path.lower().endswith(suffixes):
        raise ParameterError(f"{path!r}: the file name must end in {' or '.join(suffixes)}")
    if Path(path).is_dir():
        raise ParameterError(f"{path} is a folder: give a file name")
    folder = Path(path).parent
    if not folder.is_dir():
        raise ParameterError(f"{path}: the folder {folder} does not exist")
    try:  # (a folder that takes no file, found now rather than after the work)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as error:
        raise ParameterError(f"{path}: cannot write in the folder {folder} "
                             f"({error.strerror or error})") from None


def _run(args) -> int:
    from .sweep import run_sweep
    from .sweep_file import load_sweep

    _check_output(args.output, (".nc",))
    # bad input: one line, before anything else (a beam file runs as beam-sweep runs it)
    spec = load_sweep(args.sweep_file, model=None)
    if spec.model == "beam":
        return _run_beam_spec(spec, args)
    _note_derived_stiffness(spec.preset, spec.fixed, spec.grid)
    if not args.quiet:
        _announce_compilation()
    try:  # (the checked spec, not the file: run_sweep takes it as it is)
        ds = run_sweep(spec, args.output, resume=args.resume,
                       progress=not args.quiet, workers=args.workers, scheduler=args.scheduler,
                       yes=args.yes)
    except KeyboardInterrupt:
        print(f"harvester-sweep: interrupted; the finished chunks are kept in "
              f"{args.output}.partial/: run the same command with --resume to finish",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    from .outputs import STATUSES

    counts = {s.name: int((ds["status"] == s.code).sum()) for s in STATUSES}
    for s in reversed(STATUSES[1:]):  # the worst first
        if counts[s.name]:
            print(f"harvester-sweep: warning: {counts[s.name]} of {ds['status'].size} points "
                  f"{s.name} (status = {s.code}): {s.meaning}{_work_share(ds, s.code)}; "
                  f"{_ADVICE[s.name]}", file=sys.stderr)
    if not args.quiet:
        print(f"harvester-sweep: {ds['status'].size} points ({counts['settled']} settled) in "
              f"{ds.attrs['run_time']:.3g} s of integration: {args.output}", file=sys.stderr)
    return 0


def _work_share(ds, code: int) -> str:
    """'; they took N % of the sweep's RK4 steps' for the points of status ``code``, where
    that is a tenth or more: a point that does not settle runs its whole max_periods, so
    a few of them can take most of a sweep's time."""
    steps = ds["rk4_steps"].values.astype(float)
    total = steps.sum()
    share = steps[ds["status"].values == code].sum() / total if total > 0 else 0.0
    return f"; they took {100 * share:.0f} % of the sweep's RK4 steps" if share >= 0.1 else ""


_ADVICE = {  # what to do about the points of each status but settled
    "not settled": "raise max_periods to settle them, or lower it to spend less on them, or "
                   "look for chaos in a bifurcation diagram",
    "diverged": "raise steps_per_period",
    "too stiff": "'harvester-sweep scene' with their parameters says what needs which step",
}


def _continue(args) -> int:
    from .branch_file import load_continuation
    from .continuation import NoOrbitError, continue_branch

    _check_outputs(args)
    spec = load_continuation(args.spec_file)  # bad input: one line, before anything else
    _note_derived_stiffness(spec.preset, spec.fixed, [spec.parameter])
    with _locked(args):
        _announce_compilation()
        try:
            ds = continue_branch(spec)
        except NoOrbitError as error:
            print(f"harvester-sweep: error: {error}", file=sys.stderr)
            return EXIT_DIVERGED
        print(_bifurcation_table(ds))
        return _write(ds, args, "plot_branch")


@contextlib.contextmanager
def _locked(args):
    """The output's lock held, as 'run' holds it: a second run on the same output is
    refused, and a folder that cannot be written is found before the work, not after."""
    from .chunk_store import lock_output

    lock = lock_output(args.output)
    try:
        if args.plot is not None:
            _check_writable(Path(args.plot).parent)
        yield
    finally:
        lock.release()


def _check_writable(folder: Path) -> None:
    import tempfile

    try:
        with tempfile.NamedTemporaryFile(dir=folder):
            pass
    except OSError as error:
        raise ParameterError(f"cannot write in the folder {folder} ({error.strerror}): give a "
                             "--plot where you can write") from None


def _check_outputs(args) -> None:
    """The netCDF file and optional figure a command writes, checked before any work."""
    _check_output(args.output, (".nc",))
    if args.plot is not None:
        _check_output(args.plot, _FIGURES)


def _write(ds, args, plotter: str) -> int:
    """Write ``ds`` to args.output, and draw it to args.plot by plots.<plotter> if asked."""
    from . import plots
    from .datasets import write_netcdf

    with _writing(args.output):
        write_netcdf(ds, args.output)
    if args.plot:
        with _writing(args.plot):
            getattr(plots, plotter)(ds, args.plot)
    return 0


def _basins(args) -> int:
    from .basin_file import load_basins
    from .basins import basin_map

    _check_outputs(args)
    spec = load_basins(args.spec_file)  # bad input: one line, before anything else
    _note_derived_stiffness(spec.preset, spec.fixed, spec.axes)
    with _locked(args):
        _announce_compilation()
        start = time.perf_counter()
        ds = basin_map(spec, progress=not args.quiet, yes=args.yes)
        print(_basin_summary(ds, time.perf_counter() - start))
        return _write(ds, args, "plot_basins")


def _basin_summary(ds, seconds: float) -> str:
    """What a basin run found: per attractor at one point, the range of the map else."""
    axes = ds.attrs["grid_axes"].split()
    points = int(np.prod([ds.sizes[a] for a in axes]))
    lines = [f"{points} point(s) x {ds.attrs['samples']} starts ({ds.attrs['starts']}) in "
             f"{seconds:.3g} s"]
    impact = ds["impact_basin_fraction"].values
    if axes and np.isnan(impact).all():
        lines.append("  impact_basin_fraction: unknown: no start reached an orbit")
    elif axes:
        lines.append(f"  impact_basin_fraction: {np.nanmin(impact):.3g} to "
                     f"{np.nanmax(impact):.3g}; up to {ds.sizes['attractor']} attractors at "
                     "a point")
    else:
        lines.append(f"  {'attractor':>9} {'basin_fraction':>16} {'orbit_period':>12} "
                     f"{'impacts_per_period':>18} {'power [W]':>10} {'x_max [' + _UM + ']':>10}")
        if ds.sizes["attractor"] == 0:
            lines.append(f"  {'none':>9}")
        for k in range(ds.sizes["attractor"]):
            a = ds.isel(attractor=k)
            lines.append(f"  {k + 1:>9} {float(a.basin_fraction):>8.3f} +- "
                         f"{float(a.basin_fraction_error):<5.3f} {int(a.orbit_period):>12} "
                         f"{float(a.impacts_per_period):>18.3g} {float(a.power):>10.4g} "
                         f"{float(a.x_max) / 1e-6:>10.4g}")
    lost = float(np.nanmax(ds["fraction_not_settled"].values + ds["fraction_diverged"].values))
    if lost > 0:
        lines.append(f"  up to {lost:.0%} of a point's starts reached no orbit (not settled "
                     "or diverged)")
    return "\n".join(lines)


def _bifurcation_table(ds) -> str:
    """The bifurcations of a branch dataset, one line each: a located one at its value, one
    whose location failed as the interval that holds it (its bracket), not as a value it
    does not have."""
    from .plots import bifurcation_points

    name = ds.attrs["continued_parameter"]
    unit = ds[name].attrs["units"]
    scale, shown = (1e-6, _UM) if unit == "m" else (1.0, unit)
    lines = [f"branch of {name} from {ds.attrs['start'] / scale:g} to "
             f"{ds.attrs['stop'] / scale:g} {shown}: "
             f"{ds.sizes['point']} points in {ds.attrs['run_time']:.3g} s, followed at "
             f"{ds.attrs['steps_per_period']} steps per period; {ds.attrs['ends']}",
             ""]
    rows = []
    for b in bifurcation_points(ds):
        i = b["index"]
        value = (f"{b['value'] / scale:.10g}" if b["located"] else
                 f"{b['low'] / scale:.6g} to {b['high'] / scale:.6g}")
        rows.append((b["kind"] + (" (lower)" if b["stop"] == "lower" else ""), value, i,
                     "" if b["located"] else "  not located: somewhere in the interval"))
    value_w = max([len(f"{name} [{shown}]")] + [len(row[1]) for row in rows])
    lines.append(f"  {'bifurcation':<16} {'branch':>6} {name + ' [' + shown + ']':>{value_w}} "
                 f"{'bracket':>9} {'2x steps':>9} {'steps':>7} {'x_max [' + _UM + ']':>11} "
                 f"{'power [W]':>10}")
    for kind, value, i, note in rows:
        lines.append(f"  {kind:<16} {int(ds['branch'][i]):>6} {value:>{value_w}} "
                     f"{float(ds[name + '_precision'][i]) / scale:>9.2g} "
                     f"{float(ds[name + '_shift'][i]) / scale:>+9.2g} "
                     f"{int(ds['steps_per_period'][i]):>7} "
                     f"{float(ds['x_max'][i]) / 1e-6:>11.5g} {float(ds['power'][i]):>10.4g}"
                     + note)
    if not rows:
        lines.append("  none located")
    lines.append(f"  (bracket: width of the interval in {name} that holds it; 2x steps: the "
                 "larger change of its location when located again at 3/2 and at twice")
    lines.append("  its steps per period, its discretization error, nan where its location "
                 "failed; steps: the steps per period it is located at)")
    return "\n".join(lines)


def _open(path: str):
    import xarray as xr

    try:
        return xr.open_dataset(path)
    except (OSError, ValueError) as error:
        raise ParameterError(f"{path}: cannot read it as netCDF ({_unreadable(path, error)})"
                             ) from None


#: The first bytes of a netCDF file: classic (CDF-1, -2, -5) or netCDF-4 (HDF5).
_NETCDF_STARTS = (b"CDF\x01", b"CDF\x02", b"CDF\x05", b"\x89HDF\r\n\x1a\n")


def _unreadable(path: str, error: Exception) -> str:
    """Why ``path`` could not be opened, short: xarray's own reason for a file no engine
    takes is a paragraph on engines, of no use to one who gave a text file."""
    file = Path(path)
    if not file.exists():
        return "no such file"
    if file.is_dir():
        return "it is a folder"
    try:
        with open(file, "rb") as opened:
            head = opened.read(512)
    except OSError as failure:
        return failure.strerror or str(failure)
    if not head:
        return "it is empty"
    if not head.startswith(_NETCDF_STARTS):
        try:
            text = b"\x00" not in head and bool(head.decode("utf-8"))
        except UnicodeDecodeError:
            text = False
        return ("it holds text, not netCDF" if text
                else "not a netCDF file: it does not start as one does")
    if isinstance(error, OSError) and error.strerror:
        return error.strerror  # (the netCDF library's: "NetCDF: HDF error")
    return str(error).splitlines()[0]


def _plot(args) -> int:
    from .plots import check_over, dataset_kind, plot_basins, plot_branch, plot_scene, plot_sweep

    _check_output(args.output, _FIGURES)
    both = sorted(set(args.log) & set(args.linear))
    if both:
        raise ParameterError(f"--log and --linear both name {', '.join(both)}")
    scales = {**{name: "log" for name in args.log}, **{name: "linear" for name in args.linear}}
    ds = _open(args.dataset)
    sweeps = [_open(path) for path in args.over]
    for path, opened in [(args.dataset, ds)] + list(zip(args.over, sweeps)):
        _check_written_here(path, opened)
    if sweeps and "point" not in ds.dims:
        raise ParameterError("--over: draws sweeps under a branch (a file written by "
                             f"'continue'); {args.dataset} is {dataset_kind(ds)}")
    if ds.attrs.get("model") == "beam":
        from .plots import (
            plot_beam_basins,
            plot_beam_branch,
            plot_beam_scene,
            plot_beam_sweep,
        )

        if sweeps or scales:
            raise ParameterError("--over, --log, --linear: not for a beam file")
        with ds, _writing(args.output):
            draw = (plot_beam_scene if "time" in ds.dims else plot_beam_branch
                    if "point" in ds.dims else plot_beam_basins if "attractor" in ds.dims
                    else plot_beam_sweep)
            draw(ds, args.output)
        return 0
    with ds, _writing(args.output), _complete(args.dataset):
        if "point" in ds.dims:
            for path, sweep in zip(args.over, sweeps):
                try:
                    check_over(ds, sweep)
                except ParameterError as error:
                    raise ParameterError(f"--over {path}: {error}") from None
            plot_branch(ds, args.output, sweeps, scales=scales)
        elif "attractor" in ds.dims:
            plot_basins(ds, args.output, scales=scales)
        elif "time" in ds.dims:
            if scales:
                raise ParameterError("--log, --linear: a scene is drawn against time alone")
            plot_scene(ds, args.output)
        else:
            plot_sweep(ds, args.output, scales=scales)
    for sweep in sweeps:
        sweep.close()
    return 0


def _check_written_here(path: str, ds) -> None:
    """Refuse a netCDF file this tool did not write: every file it writes has a title
    "harvester_sweep ..." (datasets.py), and the plots read its variables and attributes
    by name."""
    if ds.attrs.get("model") == "beam":
        return  # (drawn by plots.plot_beam_scene, plot_beam_sweep)
    title = ds.attrs.get("title")
    if not (isinstance(title, str) and title.startswith("harvester_sweep ")):
        raise ParameterError(f"{path}: not a file written by harvester-sweep (its title "
                             "attribute is not 'harvester_sweep ...'): plot draws the files "
                             "of 'run', 'scene', 'continue' and 'basins'")


@contextlib.contextmanager
def _complete(path: str):
    """A file of this tool that lacks a variable or attribute its plot reads (changed
    since it was written): one line naming it, exit 2."""
    try:
        yield
    except KeyError as error:
        what = str(error.args[0]) if error.args else ""
        what = what.split(". ")[0] if what.startswith("No variable") else \
            f"no variable, dimension or attribute {what!r}"
        raise ParameterError(f"{path}: {what}, which harvester-sweep writes and the plot "
                             "needs (was the file changed since?)") from None


#: The display unit of every length in the tables, as on the figures (JSON and netCDF keep m).
_UM = "\u00b5m"


def _note_derived_stiffness(preset, fixed: dict, varied) -> None:
    """Say on stderr where stop_mass sets the contact stiffness (a run's file keeps it as
    hertz_stiffness): to what, or that each point derives its own."""
    from .plots import derived_stiffness

    if fixed.get("stop_mass") is None and "stop_mass" not in varied:
        return
    if set(varied) & {"mass", "tip_material", "stop_mass", "stop_material"}:
        print("harvester-sweep: note: hertz_stiffness is derived at each point from "
              "stop_mass, the tip's mass and the materials (Goldsmith)", file=sys.stderr)
        return
    with warnings.catch_warnings():  # (the run itself warns of its step, once)
        warnings.simplefilter("ignore")
        text = derived_stiffness(resolve_parameters(preset, **fixed))
    if text:
        print(f"harvester-sweep: note: {text}", file=sys.stderr)


def _table(result, preset: str) -> str:
    from .outputs import OUTPUTS, SCENE_OUTPUTS
    from .plots import derived_stiffness, parameters_text

    p, m = result.parameters, result.metrics
    lines = [f"scene '{preset}': {parameters_text(p, stiffness=False)}, "
             f"coupling = {p['coupling']:.3g} N/V"]
    lines += [f"  note: {note}" for note in result.notes]
    derived = derived_stiffness(p)
    if derived:  # (stop_mass changes the contact stiffness: say so, and to what)
        lines.append(f"  note: {derived}")
    lines.append("")
    rows = []
    for name in SCENE_OUTPUTS:
        if name == "status":
            continue
        output = OUTPUTS[name]
        value, unit, long_name = m[name], output.units, output.long_name
        scale = 1e-6 if unit == "m" else 1.0
        unit = _UM if unit == "m" else "" if unit == "1" else unit
        if value is None:
            text = "none"
        elif isinstance(value, bool):
            text = "yes" if value else "no"
        elif isinstance(value, int):
            text = str(value)
        elif isinstance(value, list):
            text = " ".join("none" if v is None else f"{v:.4g}" for v in value)
        else:
            text = f"{value / scale:.6g}"
        rows.append((name, text, unit, long_name))
    rows.append(("status", m["status"], "", ""))
    # columns as wide as their longest entries (the multipliers' lists and long names)
    name_w, value_w, unit_w = (max(len(row[k]) for row in rows) for k in range(3))
    lines.append(f"  {'metric':<{name_w}} {'value':>{value_w}}  unit")
    lines += [f"  {name:<{name_w}} {text:>{value_w}}  {unit:<{unit_w}} {long_name}".rstrip()
              for name, text, unit, long_name in rows]
    return "\n".join(lines)


def _beam_common(parser) -> None:
    """The options every beam command takes: its preset and --set overrides (checked by
    beam_parameters, not by argparse: importing it for the choices would slow every
    command)."""
    parser.add_argument("--preset", default=None, metavar="NAME",
                        help="starting parameter set: bimorph_tip (default) or mak_rod (see "
                        "'harvester-sweep parameters --model beam')")
    parser.add_argument("--set", dest="assignments", action="append", default=[],
                        metavar="NAME=VALUE",
                        help="override a beam parameter in SI units, e.g. --set n_modes=3 "
                        "(repeatable)")


def _beam_assignment(text: str) -> tuple[str, object]:
    """``NAME=VALUE`` of a beam parameter, typed and refused as parse_assignment does for
    the tip-mass model (which parses the parameters the two models share)."""
    name, sep, raw = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise ParameterError(f"--set {text!r}: expected NAME=VALUE, e.g. --set n_modes=3")
    spec = _beam_spec(name)
    if PARAMETERS.get(name) is spec:
        return parse_assignment(text)
    raw = raw.strip()
    if spec.kind in ("choice", "bool", "list"):
        return name, raw
    if spec.optional and raw.lower() in ("", "none"):
        return name, None
    return name, _beam_number(spec, raw)


def _beam_spec(name: str):
    from .beam_parameters import BEAM_PARAMETERS

    if name not in BEAM_PARAMETERS:
        raise ParameterError(f"unknown beam parameter {name!r}: known parameters are "
                             + ", ".join(BEAM_PARAMETERS))
    return BEAM_PARAMETERS[name]


def _beam_number(spec, raw: str):
    """The number ``raw`` of parameter ``spec``, or one line naming it, its unit and
    range."""
    try:
        number = float(raw)
    except ValueError:
        unit = f" [{'-' if spec.unit == '1' else spec.unit}]"
        raise ParameterError(f"{spec.name}{unit} = {raw.strip()!r} is not a number: must be "
                             f"{spec.range_text()}") from None
    return int(number) if spec.kind == "int" and number.is_integer() else number


def _beam_axis(text: str) -> tuple[str, np.ndarray]:
    """``NAME=START:STOP:COUNT`` (evenly spaced, both ends included) or
    ``NAME=V1,V2,...`` from --axis, each value checked against the parameter's range."""
    name, sep, raw = text.partition("=")
    name, raw = name.strip(), raw.strip()
    if not sep or not name or not raw:
        raise ParameterError(f"--axis {text!r}: expected NAME=START:STOP:COUNT or "
                             "NAME=V1,V2,..., e.g. --axis frequency=120:170:26")
    spec = _beam_spec(name)
    if spec.kind in ("choice", "bool"):
        raise ParameterError(f"--axis {name}: a sweep axis takes numbers, and {name} is "
                             f"{spec.range_text()}: give it with --set")
    if ":" in raw:
        parts = raw.split(":")
        if len(parts) != 3:
            raise ParameterError(f"--axis {text!r}: expected NAME=START:STOP:COUNT, e.g. "
                                 "--axis frequency=120:170:26")
        start, stop = (_beam_number(spec, part) for part in parts[:2])
        try:
            count = int(parts[2])
        except ValueError:
            count = 0
        if count < 1:
            raise ParameterError(f"--axis {name}: COUNT = {parts[2].strip()!r}: must be a whole "
                                 "number of points, at least 1")
        values = list(np.linspace(start, stop, count))
    else:
        values = [_beam_number(spec, part) for part in raw.split(",")]
    values = [spec.check(v) for v in values]  # (one line: name, unit, range)
    return name, np.array(values)


def _announce_beam_compilation() -> None:
    """Say so where the beam's modal engine (cached apart from the tip-mass model's) is
    not in numba's on-disk cache: its first run compiles it."""
    try:
        from ._engine import cache
        from ._engine.modal import kernel

        warm = cache.is_warm(kernel.take_points)
    except (ImportError, AttributeError):  # (the engine's layout changed: say nothing)
        return
    if not warm:
        print("harvester-sweep: compiling the beam's modal engine into numba's on-disk "
              "cache (first run only, a few minutes)", file=sys.stderr, flush=True)


#: The beam's outputs shown as whole numbers.
_BEAM_COUNTS = ("orbit_period", "periods_run", "steps_per_period")


def _beam_scene(args) -> int:
    from .beam_parameters import DEFAULT_BEAM_PRESET, resolve_beam_parameters
    from .beam_runs import beam_scene
    from .outputs import STATUSES

    if args.output is not None:
        _check_output(args.output, (".nc",))
    if not 1 <= args.periods <= 1000:
        raise ParameterError(f"--periods = {args.periods}: must be an integer in [1, 1000]")
    overrides = dict(_beam_assignment(text) for text in args.assignments)
    p = resolve_beam_parameters(args.preset, **overrides)
    preset = args.preset or DEFAULT_BEAM_PRESET
    _announce_beam_compilation()
    outputs, series = beam_scene(preset, periods=args.periods, **overrides)
    rows = _beam_rows(outputs, p)
    status = {s.code: s.name for s in STATUSES}.get(int(outputs["status"]), "unknown")
    if args.json:
        record = {name: value for name, value, _, _ in rows}
        record["status"] = status
        print(json.dumps(record))
    else:
        print(_beam_table(rows, p, preset, status))
    if status == "diverged":
        print(f"harvester-sweep: the integration diverged after {int(outputs['periods_run'])} "
              "periods: no outputs are reported. Raise steps_per_period or lower "
              "contact_step.", file=sys.stderr)
        return EXIT_DIVERGED
    if status == "not settled":
        print(f"harvester-sweep: warning: no steady state within max_periods = "
              f"{p['max_periods']}: the outputs are over the last periods run", file=sys.stderr)
    if args.output:
        with _writing(args.output):
            from .datasets import write_netcdf

            write_netcdf(series, args.output)
    return 0


def _beam_rows(outputs: dict, p: dict) -> list:
    """(name, value for JSON, unit, long_name) of each output of a beam point; one row per
    mode of ``modal_amplitude``; ``stop_face_max`` left out with a rigid stop; NaN as
    None."""
    from .beam_parameters import moving_stop
    from .outputs import OUTPUTS

    def plain(name, value):
        value = float(value)
        if not np.isfinite(value):
            return None
        return int(value) if name in _BEAM_COUNTS else value

    rows = []
    for name, value in outputs.items():
        if name == "status" or (name == "stop_face_max" and not moving_stop(p)):
            continue
        output = OUTPUTS.get(name)
        unit, long_name = (output.units, output.long_name) if output else ("", "")
        if name == "modal_amplitude":
            rows.append((name, [plain(name, v) for v in np.ravel(value)], unit, long_name))
        else:
            rows.append((name, plain(name, value), unit, long_name))
    return rows


def _beam_table(rows: list, p: dict, preset: str, status: str) -> str:
    """A beam point's outputs as a table, lengths in micrometres as in the other tables."""
    from .beam_parameters import BEAM_PRESET_NOTES, contact_position

    stop = ("a stop on a spring" if p["stop_support_stiffness"] is not None
            else "a rigid stop" if p["rod_modes"] == 0
            else f"a rod stop in {p['rod_modes']} modes")
    lines = [f"beam scene '{preset}': {p['n_modes']} bending modes striking {stop} at "
             f"{contact_position(p) / p['length']:.3g} L, gap = {p['gap'] / 1e-6:g} {_UM}, "
             f"frequency = {p['frequency']:g} Hz, amplitude = {p['amplitude']:g} m/s^2, "
             f"resistance = {p['resistance']:g} ohm"]
    lines += [f"  note: {note}" for note in BEAM_PRESET_NOTES.get(preset, [])]
    lines.append("")

    def text(value, scale):
        if value is None:
            return "nan"
        return str(value) if isinstance(value, int) else f"{value / scale:.6g}"

    shown = []
    for name, value, unit, long_name in rows:
        scale = 1e-6 if unit == "m" else 1.0
        unit = _UM if unit == "m" else "" if unit == "1" else unit
        if name == "modal_amplitude":
            shown += [(f"{name}[{r}]", text(v, scale), unit, f"{long_name} (mode {r})")
                      for r, v in enumerate(value, 1)]
        else:
            shown.append((name, text(value, scale), unit, long_name))
    shown.append(("status", status, "", ""))
    name_w, value_w, unit_w = (max(len(row[k]) for row in shown) for k in range(3))
    lines.append(f"  {'output':<{name_w}} {'value':>{value_w}}  unit")
    lines += [f"  {name:<{name_w}} {value:>{value_w}}  {unit:<{unit_w}} {long_name}".rstrip()
              for name, value, unit, long_name in shown]
    return "\n".join(lines)


def _beam_branch_or_basins(args) -> int:
    """beam-continue and beam-basins: the API's checks (one line, exit 2), then the run
    and its CF netCDF file."""
    from .beam_basins import beam_basins
    from .beam_continuation import check_branch, continue_beam_branch
    from .beam_parameters import DEFAULT_BEAM_PRESET, resolve_beam_parameters
    from .datasets import write_netcdf

    _check_output(args.output, (".nc",))
    overrides = dict(_beam_assignment(text) for text in args.assignments)
    resolve_beam_parameters(args.preset, **overrides)
    if args.command == "beam-continue":
        check_branch(args.parameter, args.start, args.stop, args.step, args.max_points)
    preset = args.preset or DEFAULT_BEAM_PRESET
    _announce_beam_compilation()
    if args.command == "beam-continue":
        from .continuation import NoOrbitError

        try:
            ds = continue_beam_branch(args.parameter, args.start, args.stop, preset,
                                      step=args.step, max_points=args.max_points,
                                      period_doubling=args.period_doubling, **overrides)
        except NoOrbitError as error:  # (as continue's: no result, not bad input)
            print(f"harvester-sweep: error: {error}", file=sys.stderr)
            return EXIT_DIVERGED
        found = int((ds["bifurcation"] > 0).sum())
        branches = int(ds["branch"].max()) + 1
        what = (f"{ds.sizes['point']} branch points ({branches} branch"
                f"{'es' if branches > 1 else ''}), {found} bifurcation(s) located")
    else:
        ds = beam_basins(preset, samples=args.samples, seed=args.seed, box=args.box,
                         **overrides)
        what = f"{ds.sizes['attractor']} attractor(s) from {args.samples} starts"
    with _writing(args.output):
        write_netcdf(ds, args.output)
    print(f"harvester-sweep: {what}: {args.output}", file=sys.stderr)
    return 0


def _beam_sweep(args) -> int:
    from .sweep_file import load_sweep

    _check_output(args.output, (".nc",))
    # (checked once, before anything else: bad input is one line, exit 2)
    spec = load_sweep(_beam_sweep_source(args), model="beam")
    return _run_beam_spec(spec, args)


def _run_beam_spec(spec, args) -> int:
    """A checked beam sweep run as ``args`` (of beam-sweep or run) say: its chunks kept in
    OUT.nc.partial/ as they finish, a summary of its statuses on stderr."""
    from .beam_cluster import run_beam_file
    from .cluster import check_cluster
    from .outputs import STATUSES

    check_cluster(args.workers, args.scheduler)
    _announce_beam_compilation()
    start = time.perf_counter()
    try:
        ds = run_beam_file(spec, args.output, resume=args.resume,
                           progress=_beam_progress(args.quiet), workers=args.workers,
                           scheduler=args.scheduler, announce=not args.quiet,
                           yes=args.yes)
    except KeyboardInterrupt:
        print(f"harvester-sweep: interrupted; the finished chunks are kept in "
              f"{args.output}.partial/: run the same command with --resume to finish",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    seconds = time.perf_counter() - start
    counts = {s.name: int((ds["status"] == s.code).sum()) for s in STATUSES}
    for s in reversed(STATUSES[1:]):  # the worst first
        if counts[s.name]:
            print(f"harvester-sweep: warning: {counts[s.name]} of {ds['status'].size} points "
                  f"{s.name} (status = {s.code}): {s.meaning}", file=sys.stderr)
    if not args.quiet:
        print(f"harvester-sweep: {ds['status'].size} points ({counts['settled']} settled) in "
              f"{seconds:.3g} s: {args.output}", file=sys.stderr)
    return 0


def _beam_sweep_source(args):
    """What beam-sweep runs: its sweep file, or the sweep file (a dict) of its --axis,
    --direction, --preset and --set (each value checked against its range here)."""
    from .beam_cluster import beam_source

    given = [option for option, value in (("--axis", args.axes), ("--set", args.assignments),
                                          ("--preset", args.preset),
                                          ("--direction", args.direction)) if value]
    if args.sweep_file is not None:
        if given:
            raise ParameterError(f"{given[0]}: the sweep file {args.sweep_file} gives the "
                                 "grid, its parameters and directions; give them there or "
                                 "on the command line, not both")
        return args.sweep_file
    if not args.axes:
        raise ParameterError("beam-sweep: give a sweep file (SWEEP.toml, with model = "
                             "\"beam\") or at least one --axis NAME=START:STOP:COUNT")
    overrides = dict(_beam_assignment(text) for text in args.assignments)
    axes = {}
    for text in args.axes:
        name, values = _beam_axis(text)
        if name in axes:
            raise ParameterError(f"--axis {name}: given twice")
        if name in overrides:
            raise ParameterError(f"{name}: both on an --axis and in --set")
        axes[name] = values
    directions = {None: None, "up": ("up",), "down": ("down",),
                  "both": ("up", "down")}[args.direction]
    if directions and "frequency" not in axes:
        raise ParameterError("--direction: a sweep up or down needs a frequency axis "
                             "(--axis frequency=START:STOP:COUNT)")
    return beam_source(axes, args.preset, directions, **overrides)


def _beam_progress(quiet: bool):
    """A beam sweep's progress hook: one line on stderr per frequency step of a chunk's
    swept lines (each step of its every line at once), per chunk of points, or per chunk
    on dask, with the time the rest will take at the rate so far; None when quiet."""
    if quiet:
        return None
    from .run_estimate import duration

    start = time.perf_counter()
    begun = [start]

    def report(done: int, total: int, what: str) -> None:
        now = time.perf_counter()
        left = "" if done >= total else \
            f"; about {duration((now - start) * (total - done) / done)} left"
        print(f"harvester-sweep: {done}/{total}: {what} in {now - begun[0]:.2g} s{left}",
              file=sys.stderr, flush=True)
        begun[0] = now

    return report


def _print_parameters(model: str = "tip_mass") -> int:
    """Two tables, their columns as wide as their longest entries: the parameters (unit,
    range, meaning) of ``model`` ("tip_mass" or "beam"), then every preset's value of
    each, none left out."""
    registry, presets = PARAMETERS, PRESETS
    if model == "beam":
        from .beam_parameters import BEAM_PARAMETER_PRESETS, BEAM_PARAMETERS

        registry, presets = BEAM_PARAMETERS, BEAM_PARAMETER_PRESETS
    specs = list(registry.values())
    rows = [("name", "unit", "allowed", "description")] + [
        (s.name, "-" if s.unit == "1" else s.unit, s.range_text(), s.description) for s in specs]
    print(_columns(rows))
    print()

    def shown(value) -> str:
        if value is None:
            return "unset"
        if isinstance(value, bool):
            return str(value).lower()
        return f"{value:g}" if isinstance(value, float) else str(value)

    rows = [("preset values", "unit", *presets)] + [
        (s.name, "-" if s.unit == "1" else s.unit,
         *(shown(values.get(s.name)) for values in presets.values())) for s in specs]
    print(_columns(rows))
    return 0


def _columns(rows: list) -> str:
    """Rows of text as aligned columns (the last one left ragged)."""
    widths = [max(len(row[k]) for row in rows) for k in range(len(rows[0]) - 1)]
    return "\n".join(" ".join(f"{cell:<{w}}" for cell, w in zip(row, widths)) + " " + row[-1]
                     for row in rows)


if __name__ == "__main__":
    sys.exit(main())
