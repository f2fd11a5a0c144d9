"""The `lanekeep` command line: thin argument parsing over library calls; main() returns a code.

Exit codes: 0 success, 1 a failure while running, 2 bad input (arguments, files, scenarios),
130 stopped by Ctrl-C or SIGTERM (both are handled alike: the results so far are kept, see
lanekeep/core/interrupts.py).
An error is one line on stderr, "lanekeep: error: ...", naming the file and key or the option;
`lanekeep --debug ...` lets the exception through instead (with its traceback).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path

import lanekeep  # sets MUJOCO_GL before mujoco is imported; --version
from lanekeep.cli.outputs import error_line
from lanekeep.core.config_io import ConfigError
from lanekeep.core.interrupts import stop_signals_interrupt
from lanekeep.sensing.gl_backend import require_mujoco

EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130


def _cmd_scenarios(args: argparse.Namespace) -> int:
    from lanekeep.scenario.schema import load_scenario, shipped_scenarios

    names = shipped_scenarios()
    if args.json:
        from lanekeep.report.json_io import dumps

        sys.stdout.write(dumps([_scenario_summary(load_scenario(name)) for name in names]))
        return EXIT_OK
    width = max(len(n) for n in names)
    for name in names:
        print(f"{name:<{width}}  {load_scenario(name).description}")
    return EXIT_OK


def _scenario_summary(scenario) -> dict:
    """`scenarios --json`: what picks a scenario for a run (keys in docs/reports.md)."""
    return {"name": scenario.name, "description": scenario.description,
            "path": scenario.source, "seed": scenario.seed, "duration_s": scenario.duration_s,
            "target_speed_mps": scenario.target_speed_mps,
            "road_length_m": scenario.road.length_m, "n_lanes": scenario.road.n_lanes,
            "time_of_day": scenario.conditions.time_of_day,
            "camera": f"{scenario.camera.width}x{scenario.camera.height}",
            "front_detectors": list(scenario.estimation.front_detectors),
            "mode": scenario.estimation.mode}


def _cmd_render(args: argparse.Namespace) -> int:
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.sensing.snapshot import render_snapshot

    scenario = load_scenario(args.scenario)
    written = render_snapshot(scenario, Path(args.out), at_s=args.at, offset_m=args.offset,
                              heading_deg=args.heading, effects=not args.no_effects)
    for path in written:
        print(path)
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="lanekeep", description="Headless closed-loop lane-keeping testbed on MuJoCo."
    )
    parser.add_argument("--debug", action="store_true",
                        help="on an error, raise the exception (with its traceback) instead of "
                             "printing one line")
    parser.add_argument("--version", action="version",
                        version=f"%(prog)s {lanekeep.__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("scenarios", help="list the shipped scenarios")
    p.add_argument("--json", action="store_true",
                   help="a JSON array on stdout: each scenario's name, description, file, "
                        "seed, duration, speed, road length, lanes, light, camera size, "
                        "front detectors and estimation mode")
    p.set_defaults(func=_cmd_scenarios)

    p = sub.add_parser("render", help="render front/rear RGB and segmentation PNGs of a scenario")
    p.add_argument("scenario", help="shipped scenario name or path to a .toml file")
    p.add_argument("--at", type=float, default=None, help="arc length s (m); default: start")
    p.add_argument("--offset", type=float, default=0.0, help="lateral offset from lane centre (m)")
    p.add_argument("--heading", type=float, default=0.0, help="heading error (deg, + = left)")
    p.add_argument("--out", default="out/render", help="output folder")
    p.add_argument("--no-effects", action="store_true",
                   help="the bare render, without the scenario's image effects (fog, rain, "
                        "snow, wet reflections, motion blur) and camera model (exposure, "
                        "noise, vignetting)")
    p.set_defaults(func=_cmd_render)

    for module in _optional_command_modules():
        module.register(sub)
    return parser


def _optional_command_modules() -> list:
    """Subcommands that live in their own modules (detect, calibrate, run, bench, perf, eval,
    view, sweep, compare, falsify)."""
    import importlib

    modules = []
    for name in ("lanekeep.cli.detect", "lanekeep.cli.episode", "lanekeep.cli.perf",
                 "lanekeep.cli.eval", "lanekeep.cli.view", "lanekeep.cli.sweep",
                 "lanekeep.cli.compare", "lanekeep.cli.falsify"):
        try:
            modules.append(importlib.import_module(name))
        except ModuleNotFoundError as err:
            if err.name != name:
                raise
    return modules


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with stop_signals_interrupt():
            require_mujoco()  # a GL backend this machine lacks: one line, not a traceback
            return int(args.func(args))
    except KeyboardInterrupt:
        if args.debug:
            raise
        print("lanekeep: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        # The reader went away (`lanekeep scenarios | head`): stop quietly, as Unix tools do;
        # stdout goes to /dev/null so that flushing it at exit raises nothing more.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except (ConfigError, FileNotFoundError, RuntimeError) as err:
        if args.debug:
            raise
        error_line(None, err)  # one line, whatever the message holds
        return EXIT_FAILURE if isinstance(err, RuntimeError) else EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
