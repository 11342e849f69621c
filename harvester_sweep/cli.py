"""The ``harvester-sweep`` command line."""

from __future__ import annotations

import argparse
import json
import sys

from .parameters import PARAMETERS, PRESETS, ParameterError, parse_assignment

EXIT_USER_ERROR = 2
EXIT_DIVERGED = 3


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="harvester-sweep",
        description="Steady states of a piezoelectric cantilever harvester striking a Hertz bump "
        "stop (SI units throughout).",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    scene = sub.add_parser("scene", help="run one parameter point to steady state")
    scene.add_argument("--preset", default="paper", choices=sorted(PRESETS),
                       help="starting parameter set (default: paper, the paper's Table 1)")
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

    sub.add_parser("parameters", help="list the parameters, their units, ranges and presets")
    return parser


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "parameters":
            return _print_parameters()
        return _scene(args)
    except ParameterError as error:
        print(f"harvester-sweep: error: {error}", file=sys.stderr)
        return EXIT_USER_ERROR


def _scene(args) -> int:
    from .scene import run_scene

    overrides = dict(parse_assignment(text) for text in args.assignments)
    for path, suffixes in ((args.plot, (".png", ".pdf", ".svg")), (args.output, (".nc",))):
        if path is not None and not path.lower().endswith(suffixes):
            raise ParameterError(f"{path!r}: the file name must end in {' or '.join(suffixes)}")
    result = run_scene(args.preset, **overrides)
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
        print(f"harvester-sweep: warning: no steady state within max_periods = "
              f"{result.parameters['max_periods']}; the metrics are over the last periods run",
              file=sys.stderr)
    if args.output:
        result.to_netcdf(args.output)
    if args.plot:
        result.plot(args.plot)
    return 0


def _table(result, preset: str) -> str:
    from .datasets import METRICS

    p, m = result.parameters, result.metrics
    lines = [f"scene '{preset}': f = {p['frequency']:g} Hz, gap = {p['gap']:g} m, "
             f"R = {p['resistance']:g} Ohm, coupling = {p['coupling']:.3g} N/V"]
    lines += [f"  note: {note}" for note in result.notes]
    lines.append("")
    lines.append(f"  {'metric':<20} {'value':>14}  unit")
    for name, (unit, long_name) in METRICS.items():
        value = m[name]
        if value is None:
            text = "none"
        elif isinstance(value, bool):
            text = "yes" if value else "no"
        elif isinstance(value, int):
            text = str(value)
        else:
            text = f"{value:.6g}"
        lines.append(f"  {name:<20} {text:>14}  {'' if unit == '1' else unit:<5} {long_name}")
    lines.append(f"  {'status':<20} {m['status']:>14}")
    return "\n".join(lines)


def _print_parameters() -> int:
    print(f"{'name':<22} {'unit':<9} {'allowed':<34} description")
    for spec in PARAMETERS.values():
        unit = "-" if spec.unit == "1" else spec.unit
        print(f"{spec.name:<22} {unit:<9} {spec.range_text():<34} {spec.description}")
    print()
    for name, values in PRESETS.items():
        shown = ", ".join(f"{k}={v:g}" for k, v in values.items()
                          if isinstance(v, float) and k in ("coupling", "gap", "frequency"))
        print(f"preset {name}: {shown} ...")
    return 0


if __name__ == "__main__":
    sys.exit(main())
