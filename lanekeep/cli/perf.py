"""`lanekeep perf`: parse, measure (lanekeep/loop/perf.py), print, write JSON."""

from __future__ import annotations

import argparse

from lanekeep.core.config_io import ConfigError
from lanekeep.loop.perf import __doc__ as perf_doc
from lanekeep.loop.perf import format_results, measure


def register(sub) -> None:
    p = sub.add_parser("perf", help="speed of the closed loop: per-stage ms, real-time factor, "
                                    "recording cost, bench throughput (JSON keys: see --help)",
                       description=perf_doc,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scenario", default="clear_curve", help="scenario to time")
    p.add_argument("--seconds", type=float, default=10.0,
                   help="simulated seconds of each timed loop (default 10)")
    p.add_argument("--repeats", type=int, default=3,
                   help="timed loops with recording off and on, alternating; the fastest of "
                        "each counts (default 3)")
    p.add_argument("--bench-episodes", type=int, default=4,
                   help="episodes per bench-throughput run; 0 skips it (default 4)")
    p.add_argument("--bench-seconds", type=float, default=10.0,
                   help="simulated seconds of each bench episode (default 10)")
    p.add_argument("--lanenet-frames", type=int, default=30,
                   help="frames of the LaneNet inference timing; 0 skips it (default 30)")
    p.add_argument("--weights", metavar="FILE", default=None,
                   help="LaneNet weights for the inference timing and any loop that uses it "
                        "(default: the shipped file; if that is missing the timing says so)")
    p.add_argument("--json", default=None, help="also write the figures to this JSON file")
    p.set_defaults(func=_cmd_perf)


def _cmd_perf(args) -> int:
    for option, value, ok in (("--seconds", args.seconds, args.seconds > 0),
                              ("--bench-seconds", args.bench_seconds, args.bench_seconds > 0),
                              ("--repeats", args.repeats, args.repeats >= 1),
                              ("--bench-episodes", args.bench_episodes, args.bench_episodes >= 0),
                              ("--lanenet-frames", args.lanenet_frames, args.lanenet_frames >= 0)):
        if not ok:
            raise ConfigError("", option, f"out of range: {value}")
    from lanekeep.cli.episode import weights_error
    from lanekeep.loop.checks import check_scenario
    from lanekeep.scenario.schema import load_scenario

    scenario = load_scenario(args.scenario)
    check_scenario(scenario)  # a bad scenario: one line, before any loop
    code = weights_error("perf", args, [scenario])  # a given or needed file that is bad
    if code is not None:
        return code
    results = measure(args.scenario, args.seconds, args.repeats, args.bench_episodes,
                      args.bench_seconds, args.weights, args.lanenet_frames)
    print(format_results(results))
    if args.json:
        from lanekeep.report.json_io import with_metadata, write_json

        write_json(args.json, with_metadata(results, scenario))
        print(f"wrote {args.json}")
    return 0
