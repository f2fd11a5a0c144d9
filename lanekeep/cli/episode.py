"""`lanekeep run` and `lanekeep bench`: closed-loop episodes from the command line (the library
calls are in lanekeep/loop/runner.py, the tables in lanekeep/report/tables.py).

`--weights FILE` gives every learned detector (LaneNet) of the episodes that file; it is loaded
once before anything runs or is written (as is the shipped file when a scenario uses LaneNet
without --weights), and a bad one is one line "lanekeep CMD: error: FILE: why", exit 2.

`--size WxH` renders both cameras at that size (sugar for `--set camera.width=W --set
camera.height=H`: the detectors' camera models follow the render). Progress goes to stderr
(lanekeep/core/progress.py) unless `--quiet`; the tables fit 100 columns unless `--wide`;
outputs follow lanekeep/cli/outputs.py (`--json -` is stdout, folders are created).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import re
import sys
from pathlib import Path

from lanekeep.cli.outputs import (
    check_outputs,
    error_line,
    human_stream,
    write_json_output,
    write_junit_output,
)
from lanekeep.cli.plugins import add_options as add_plugin_options
from lanekeep.cli.plugins import overrides_from_args
from lanekeep.core.config_io import ConfigError
from lanekeep.core.interrupts import (
    stop_signals_held,
)
from lanekeep.loop import bench_plan as bp
from lanekeep.loop.checks import check_weights_option
from lanekeep.loop.overrides import PluginOverrides
from lanekeep.loop.runner import BenchInterrupted, BenchJob, job_steps, run_bench, run_episode
from lanekeep.report.json_io import report_document
from lanekeep.report.tables import (
    bench_verdict,
    drift_table,
    episode_table,
    interval_table,
    paired_table,
    safety_table,
    single_model_table,
    summary_table,
)
from lanekeep.scenario.estimation import ESTIMATION_MODES
from lanekeep.scenario.schema import Scenario
from lanekeep.scoring import criteria as criteria_mod
from lanekeep.tuning.scenarios import TUNING_SEEDS_START


def check_options(args: argparse.Namespace) -> None:
    """The numeric options of `run` and `bench` that the argument parser cannot check."""
    checks = [("--seconds", args.seconds,
               args.seconds is None or (math.isfinite(args.seconds) and args.seconds > 0),
               "must be a number > 0"),
              ("--seed", args.seed, args.seed is None or args.seed >= 0, "must be >= 0")]
    if hasattr(args, "workers"):
        checks.append(("--workers", args.workers, args.workers >= 1, "must be >= 1"))
    if hasattr(args, "record_every"):
        checks += [("--record-every", args.record_every, args.record_every >= 1, "must be >= 1"),
                   ("--jpeg-quality", args.jpeg_quality, 1 <= args.jpeg_quality <= 100,
                    "must be in 1..100")]
    for option, value, ok, rule in checks:
        if not ok:
            raise ConfigError("", option, f"{rule}, got {value}")


SIZE_PX = (64, 4096)  # the sides --size takes (64: as `lanekeep detect`'s smallest photo)


def parse_size(text: str) -> tuple[int, int]:
    """`--size WxH` as (width, height) in pixels; ConfigError naming the option otherwise."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    lo, hi = SIZE_PX
    if not match or not all(lo <= int(v) <= hi for v in match.groups()):
        raise ConfigError("", "--size", f"must be WIDTHxHEIGHT in pixels, each {lo}..{hi} "
                                        f"(e.g. 640x360), got {text!r}")
    return int(match[1]), int(match[2])


def with_size(plugins: PluginOverrides, args: argparse.Namespace) -> PluginOverrides:
    """The command line's scenario changes with `--size` first, as `--set camera.width=W
    --set camera.height=H` (an explicit `--set` of either key comes later and wins)."""
    if args.size is None:
        return plugins
    width, height = parse_size(args.size)
    return dataclasses.replace(plugins, settings=(("camera.width", width),
                                                  ("camera.height", height),
                                                  *plugins.settings))


def weights_error(command: str, args: argparse.Namespace, scenarios: list[Scenario]
                   ) -> int | None:
    """Exit code 2 after one error line if the weights are bad, else None."""
    try:
        check_weights_option(scenarios, args.weights)
    except ValueError as err:
        if getattr(args, "debug", False):
            raise
        return error_line(command, err)
    return None


def _cmd_run(args: argparse.Namespace) -> int:
    from lanekeep.scenario.schema import load_scenario

    check_options(args)
    overrides = criteria_mod.overrides_from_args(args)
    plugins = with_size(overrides_from_args(args), args)
    scenario = plugins.apply(load_scenario(args.scenario))
    code = weights_error("run", args, [scenario])
    if code is not None:
        return code
    check_outputs(args)
    report = run_episode(args.scenario, args.seed, args.seconds, args.plots, args.record,
                         args.record_every, args.jpeg_quality, progress=not args.quiet,
                         mode=args.mode, weights=args.weights, criteria=overrides,
                         plugins=plugins)
    out = human_stream(args)
    print(f"scenario {report.scenario} (seed {report.seed}): {report.duration_s:.1f} s simulated "
          f"in {report.wall_s:.1f} s", file=out)
    print(episode_table(report, args.wide), file=out)
    if args.json:
        write_json_output(args.json, report_document(report, scenario))
    if report.status == "interrupted":
        return 130
    return 0 if report.passed else 1  # a stopped episode fails its "status" criterion


def bench_seeds(args: argparse.Namespace, scenario: Scenario) -> list[int | None]:
    """The seeds `scenario` runs. `--seeds N` alone: the file's seed + 1 .. + N, N drawn drives;
    the nominal drive (the file's own seed) is left out because development and the tests have
    seen it, so it is no fresh sample (`run` or `bench` without `--seeds` drives it). `--seed S
    --seeds N`: S .. S + N - 1, as the user chose. Without `--seeds`: `--seed` alone (None:
    the file's own).

    Raises:
      ConfigError: the seeds cross from the scored ones (0-999) into the tuning tools' (1000+).
    """
    if args.seeds is None:
        return [args.seed]
    first = scenario.seed + 1 if args.seed is None else args.seed
    seeds = list(range(first, first + args.seeds))
    if seeds[0] < TUNING_SEEDS_START <= seeds[-1]:
        origin = (f"{scenario.name}'s seed {scenario.seed} + 1" if args.seed is None
                  else f"--seed {args.seed}")
        raise ConfigError("", "--seeds", f"{args.seeds} seeds from {origin} run seeds "
                                         f"{seeds[0]}-{seeds[-1]}, across the scored seeds "
                                         f"(0-{TUNING_SEEDS_START - 1}) and the tuning tools' "
                                         f"({TUNING_SEEDS_START} and up; docs/statistics.md"
                                         f"#seeds): run fewer seeds or start at --seed "
                                         f"{TUNING_SEEDS_START}")
    return seeds


def seeds_note(args: argparse.Namespace) -> str:
    """The bench's line on which seeds it scored ("" for one episode on a chosen seed): `--seeds`
    alone leaves out each file's nominal drive, and the reader must know it and how to run it."""
    if args.seeds is None or (args.seed is not None and args.seeds == 1):
        return ""
    if args.seed is not None:
        return f"over {args.seeds} seeds each, {args.seed} on"
    each = f"over {args.seeds} seeds each" if args.seeds > 1 else "on one seed each"
    return (f"{each}, from each file's seed + 1 on: the nominal drive (the file's own seed) is "
            f"not among the scored seeds; `lanekeep run SCENARIO` or `lanekeep bench` without "
            f"--seeds runs it")


def _cmd_bench(args: argparse.Namespace) -> int:
    from lanekeep.core.progress import set_progress, step_bar
    from lanekeep.scenario.schema import shipped_scenarios

    check_options(args)
    if args.seeds is not None and args.seeds < 1:
        raise ConfigError("", "--seeds", f"must be >= 1, got {args.seeds}")
    overrides = criteria_mod.overrides_from_args(args)
    plugins = with_size(overrides_from_args(args), args)
    margins = bench_margins(args)
    baseline, plan = read_baseline(args)
    names = args.scenarios or (list(plan) if plan else shipped_scenarios())
    scenarios = bp.bench_scenarios(names, args.mode, plugins)
    seeds = {name: list(plan[name]) if plan else bench_seeds(args, scenario)
             for name, scenario in scenarios.items()}
    if baseline is not None:
        bp.file_margins(scenarios)  # a file's bad margin fails now, not after the episodes
    bp.check_bench(scenarios, seeds, args.seconds)
    code = weights_error("bench", args, list(scenarios.values()))
    if code is not None:
        return code
    check_outputs(args)
    if args.record_dir:
        Path(args.record_dir).mkdir(parents=True, exist_ok=True)
    bench = bp.plan_jobs(names, scenarios, seeds, args.mode, plugins, args.single_model)
    jobs, many = bench.jobs, bench.many
    bar = step_bar(sum(job_steps(jobs, args.seconds)), f"bench ({len(jobs)} episodes)",
                   enabled=False if args.quiet else None,
                   step_s=bp.control_period_s(scenarios))
    try:
        with bar:
            done_reports, wall = run_bench(
                jobs, args.workers, args.seconds, args.plots, args.record_dir,
                weights=args.weights, criteria=overrides,
                on_steps=lambda done, total: set_progress(bar, done, total))
    except BenchInterrupted as stop:
        return _bench_interrupted(args, jobs, scenarios, stop)
    reports = {job.episode_label: r for job, r in zip(jobs, done_reports, strict=True)}
    documents = bp.bench_documents(jobs, done_reports, scenarios, plugins, args.weights,
                                   args.mode, args.single_model)
    if args.json:  # first: a failing table must not lose the episodes
        write_json_output(args.json, documents)
    if args.write_baseline:
        write_json_output(args.write_baseline, documents)
    if args.junit:
        write_junit_output(args.junit, reports, wall)
    out = human_stream(args)
    main_labels = bench.main_labels
    if not many:
        for label in main_labels:
            r = reports[label]
            print(f"\n== {label} (seed {r.seed}, {r.duration_s:.0f} s, wall {r.wall_s:.0f} s) ==",
                  file=out)
            print(episode_table(r, args.wide), file=out)
        print("\n" + summary_table([reports[label] for label in main_labels], args.wide),
              file=out)
        print("\n" + drift_table([reports[label] for label in main_labels]), file=out)
        if args.single_model:
            print("\n" + single_model_table(jobs, reports), file=out)
    main_docs = bp.main_documents(bench, documents)
    note = (f"on the baseline's seeds ({args.baseline})" if plan else seeds_note(args))
    print("\n" + note if note else "", file=out)
    print(interval_table(main_docs, args.wide), file=out)
    safety = safety_table(main_docs)  # "" without other vehicles or hard braking
    if safety:
        print("\n" + safety, file=out)
    if many or args.single_model:
        print("\n" + paired_table(main_docs), file=out)
    print(f"\nbench wall time: {wall:.1f} s for {len(jobs)} episodes "
          f"with {args.workers} workers", file=out)
    lines, code = bench_verdict(reports, main_labels,
                                "episodes (scenario x seed)" if many else "scenarios")
    print("\n".join(lines), file=out)
    if baseline is not None:
        code = max(code, _gate(baseline, documents, main_docs, scenarios, margins, out))
    return code


def _gate(baseline: dict, documents: dict, main_docs: list[dict],
          scenarios: dict[str, Scenario], margins: dict, out) -> int:
    """The regression gate against `baseline`, printed; 1 when a scenario got worse beyond
    its margin, 2 when the two cannot be paired."""
    from lanekeep.report.regression import gate_text

    try:
        gate = bp.regression(baseline, documents, main_docs, scenarios, margins)
    except bp.BaselineMismatch as err:
        print(f"regression gate: cannot compare with the baseline: {err}", file=out)
        return 2
    print("\n" + gate_text(gate), file=out)
    return 0 if gate.passed else 1


def read_baseline(args: argparse.Namespace) -> tuple[dict | None, dict[str, list[int]]]:
    """`--baseline F`: the baseline bench document and the scenarios and seeds it ran (those of
    the scenarios named, if any); one ConfigError line for a file that cannot be one, or with
    --seed / --seeds (the baseline's seeds are the ones paired)."""
    if not args.baseline:
        return None, {}
    from lanekeep.cli.compare import read_bench
    from lanekeep.report.regression import baseline_plan

    if args.seed is not None or args.seeds is not None:
        raise ConfigError("", "--baseline", "runs the baseline's own seeds: drop --seed and "
                                            "--seeds")
    try:
        baseline = read_bench(args.baseline)
        return baseline, baseline_plan(baseline, args.scenarios)
    except ValueError as err:  # CompareInputError, IncomparableRuns
        raise ConfigError("", "--baseline", " ".join(str(err).split())) from None


def bench_margins(args: argparse.Namespace) -> dict:
    """`--margin` values (compare's syntax) as margins; one ConfigError line for a bad one."""
    from lanekeep.report.compare import parse_margins

    try:
        return parse_margins(args.margin or [])
    except ValueError as err:
        raise ConfigError("", "--margin", str(err)) from None


def _bench_interrupted(args: argparse.Namespace, jobs: list[BenchJob],
                       scenarios: dict[str, Scenario], stop: BenchInterrupted) -> int:
    """Keep what an interrupted bench has: the JSON of every episode that returned a report
    (partial ones say `completed: false`), a table each, and which episodes never ran."""
    with stop_signals_held():
        kept = {job.episode_label: (job, r) for job, r in zip(jobs, stop.reports, strict=True)
                if r is not None}
        if args.json:
            write_json_output(args.json, {label: report_document(r, scenarios[job.scenario])
                                          for label, (job, r) in kept.items()})
        if args.junit:
            write_junit_output(args.junit, {job.episode_label: kept.get(job.episode_label,
                                                                         (job, None))[1]
                                            for job in jobs}, stop.wall_s)
        print(file=sys.stderr)
        out = human_stream(args)
        for label, (_, r) in kept.items():
            state = "complete" if r.completed else f"stopped: {r.stop_reason}"
            print(f"\n== {label} (seed {r.seed}, {r.duration_s:.0f} s, {state}) ==", file=out)
            print(episode_table(r, args.wide), file=out)
        partial = [label for label, (_, r) in kept.items() if not r.completed]
        not_run = [job.episode_label for job in jobs if job.episode_label not in kept]
        print(f"bench interrupted after {stop.wall_s:.1f} s: {len(kept) - len(partial)} "
              f"episodes complete, {len(partial)} stopped part-way"
              f"{' (' + ', '.join(partial) + ')' if partial else ''}, {len(not_run)} not run"
              f"{' (' + ', '.join(not_run) + ')' if not_run else ''}", file=sys.stderr)
    return 130


def register(sub) -> None:
    p = sub.add_parser("run", help="run one closed-loop episode and print its table")
    p.add_argument("scenario", help="shipped scenario name or path to a .toml file")
    p.add_argument("--seed", type=int, default=None, help="override the scenario's seed")
    p.add_argument("--seconds", type=float, default=None, help="stop after S simulated seconds")
    p.add_argument("--json", metavar="FILE", default=None,
                   help="write the report as JSON; '-': to stdout (the tables go to stderr)")
    p.add_argument("--plots", metavar="DIR", default=None, help="folder for PNG plots")
    p.add_argument("--record", metavar="FILE", default=None,
                   help="write a rerun recording (.rrd)")
    p.add_argument("--record-every", type=int, default=1, help="record every N-th step")
    p.add_argument("--jpeg-quality", type=int, default=75, help="JPEG quality of recorded images")
    p.add_argument("--mode", choices=ESTIMATION_MODES, default=None,
                   help="estimation mode: 'default' (ours) or 'paper' (paper 001's own loop, "
                        "lanekeep/loop/paper_mode.py); default: the scenario file's")
    add_display_options(p)
    add_weights_option(p)
    criteria_mod.add_options(p)
    add_plugin_options(p)
    p.set_defaults(func=_cmd_run)

    from lanekeep.report.seed_summary import KEYS_HELP

    p = sub.add_parser("bench", help="run many scenarios in parallel; paper-style tables",
                       epilog=KEYS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenarios", nargs="*", help="scenario names (default: all shipped)")
    p.add_argument("--workers", type=int, default=2,
                   help="episodes run at once, each in its own process (default: 2)")
    p.add_argument("--seed", type=int, default=None,
                   help="the seed of every episode (default: each file's); with --seeds, the "
                        "first seed (S .. S+N-1)")
    p.add_argument("--seeds", type=int, default=None, metavar="N",
                   help="run each scenario on N seeds, from --seed on or, without it, the "
                        "file's seed + 1 .. + N: N drawn drives (the start and traffic timing "
                        "within [start.jitter] besides the noise); the file's own seed, its "
                        "nominal drive, is not scored (`lanekeep run SCENARIO` or bench "
                        "without --seeds runs it). Every metric gets its mean, sd and 95%% "
                        "interval and the fused output a paired verdict against each model's "
                        "own track. Seeds 0-999 are the bench's (scored), 1000 and up the "
                        "tuning tools' (docs/statistics.md); a plan across both is refused")
    p.add_argument("--seconds", type=float, default=None,
                   help="stop every episode after S simulated seconds (default: each "
                        "scenario's duration)")
    p.add_argument("--json", metavar="FILE", default=None,
                   help="write one document per scenario over its seeds (keys below); '-': "
                        "to stdout (the tables go to stderr)")
    p.add_argument("--plots", metavar="DIR", default=None,
                   help="folder; one subfolder of PNGs per scenario")
    p.add_argument("--record-dir", metavar="DIR", default=None,
                   help="write one .rrd per scenario here")
    p.add_argument("--mode", choices=ESTIMATION_MODES, default=None,
                   help="estimation mode for every episode ('default' or 'paper'); "
                        "default: each scenario file's")
    p.add_argument("--single-model", action="store_true",
                   help="also drive each scenario closed loop with each front model alone "
                        "and print the car's lateral RMS / max and departures beside the "
                        "MMAE loop's; in --json these episodes are keyed 'SCENARIO@MODEL'")
    p.add_argument("--junit", metavar="FILE", default=None,
                   help="write JUnit XML for CI: one test case per episode (and per "
                        "single-model run), a <failure> naming each criterion not met")
    p.add_argument("--baseline", metavar="BASE.json", default=None,
                   help="the regression gate: run BASE's scenarios (or those named) on BASE's "
                        "seeds, pair each episode with BASE's and exit 1 when a scenario's "
                        "fused RMSE, car RMS, car max or departures got worse beyond its "
                        "margin (docs/statistics.md#the-regression-gate-against-a-baseline)")
    p.add_argument("--write-baseline", metavar="FILE", default=None,
                   help="write this bench as a baseline for --baseline (the --json document)")
    p.add_argument("--margin", action="append", default=[],
                   metavar="[LABEL:]METRIC=ABS[,REL%%]",
                   help="with --baseline: override a metric's margin, as `compare --margin`")
    add_display_options(p)
    add_weights_option(p)
    criteria_mod.add_options(p)
    add_plugin_options(p)
    p.set_defaults(func=_cmd_bench)


def add_display_options(p: argparse.ArgumentParser) -> None:
    """--size, --quiet and --wide, alike on `run` and `bench`."""
    p.add_argument("--size", metavar="WxH", default=None,
                   help="render both cameras at W x H pixels (e.g. 640x360; the detectors' "
                        "camera models follow); sugar for --set camera.width=W --set "
                        "camera.height=H; default: the scenario's (1280x720)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress on stderr (otherwise a bar on a terminal, a line every "
                        "few seconds elsewhere)")
    p.add_argument("--wide", action="store_true",
                   help="the full tables (about 190 columns) instead of the compact ones that "
                        "fit 100 columns")


def add_weights_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--weights", metavar="FILE", default=None,
                   help="weights for the learned detectors of the file's format (lanenet, "
                        "rowanchor) wherever a scenario uses them (default: their shipped "
                        "files); loaded before anything runs, a bad file is one error line "
                        "and exit 2")
