"""`lanekeep run`, `lanekeep bench` and `lanekeep perf`: closed-loop episodes from the CLI.

`--weights FILE` gives every learned detector (LaneNet) of the episodes that file; it is loaded
once before anything runs or is written (as is the shipped file when a scenario uses LaneNet
without --weights), and a bad one is one line "lanekeep CMD: error: FILE: why", exit 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed, wait
from pathlib import Path

from lanekeep.config_io import ConfigError
from lanekeep.interrupts import (
    end_children,
    ignore_stop_signals,
    stop_children,
    stop_signals_held,
    stop_signals_interrupt,
)
from lanekeep.metrics import EpisodeReport
from lanekeep.report_json import report_document, report_from_dict, write_json
from lanekeep.scenario import ESTIMATION_MODES, Scenario, ScenarioError


def check_scenario(scenario: Scenario, seconds: float | None = None) -> None:
    """Everything about a scenario that building its episode would reject, checked in 30-160 ms
    so that a bad scenario fails before anything runs or any file is written (`lanekeep
    bench` checks every scenario before a worker starts): the world's cross-field checks
    (lanekeep.world.check_scenario), the detector names, and that `seconds` makes at least
    one control step.

    Raises:
      ScenarioError: naming the scenario's file and key.
      ConfigError: `seconds` makes no control step (key "--seconds").
    """
    from lanekeep.detectors.registry import known_detectors
    from lanekeep.world import check_scenario as check_world

    source = scenario.source or scenario.name
    est = scenario.estimation
    names = [(f"estimation.front_detectors[{i}]", name)
             for i, name in enumerate(est.front_detectors)]
    for key, name in [*names, ("estimation.reference_detector", est.reference_detector)]:
        if name not in known_detectors():
            raise ScenarioError(source, key, f"unknown detector {name!r} (known: "
                                             f"{', '.join(known_detectors())})")
    check_world(scenario)
    if seconds is not None and round(seconds / scenario.control_period_s) < 1:
        raise ConfigError("", "--seconds", f"{seconds:g} s is less than one control step "
                                           f"({scenario.control_period_s:g} s)")


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


def check_weights_option(scenarios: list[Scenario], weights: str | None) -> list[str]:
    """Load the weights file each learned detector of `scenarios` would use (`weights`, else
    its shipped one); a `weights` file is checked even if no scenario uses such a detector.
    Unknown detector names are left to `check_scenario`. Returns the files checked.

    Raises:
      ValueError: the first bad file's error, "FILE: why" (detectors.lanenet.WeightsError).
    """
    from lanekeep.detectors.registry import check_detectors_weights, known_detectors

    names = [name for sc in scenarios
             for name in (*sc.estimation.front_detectors, sc.estimation.reference_detector)
             if name in known_detectors()]
    return check_detectors_weights(names, None, weights)


def weights_error(command: str, args: argparse.Namespace, scenarios: list[Scenario]
                   ) -> int | None:
    """Exit code 2 after one error line if the weights are bad, else None."""
    try:
        check_weights_option(scenarios, args.weights)
    except ValueError as err:
        if getattr(args, "debug", False):
            raise
        print(f"lanekeep {command}: error: {' '.join(str(err).split())}", file=sys.stderr)
        return 2
    return None


def run_episode(scenario_name: str, seed: int | None = None, seconds: float | None = None,
                plots_dir: str | None = None, record_path: str | None = None,
                record_every: int = 1, jpeg_quality: int = 75,
                progress: bool = False, mode: str | None = None,
                front_detectors: tuple[str, ...] | None = None,
                weights: str | None = None) -> EpisodeReport:
    """Run one scenario to the end and return its report (optionally plots and a recording).

    `mode` ("default" | "paper") and `front_detectors` (e.g. ("hough",) for a model-only
    loop) override the scenario file's; None keeps them. `weights` is the file of every
    learned detector in the episode (None: their shipped one).
    """
    import lanekeep  # noqa: F401 - EGL before mujoco
    from lanekeep.detectors.registry import detector_weights
    from lanekeep.episode import Episode
    from lanekeep.paper_mode import with_mode
    from lanekeep.plots import EpisodeTrace, write_plots
    from lanekeep.scenario import load_scenario

    scenario = with_mode(load_scenario(scenario_name), mode)
    if seed is not None:
        scenario = dataclasses.replace(scenario, seed=seed)
    if front_detectors is not None:
        scenario = dataclasses.replace(scenario, estimation=dataclasses.replace(
            scenario.estimation, front_detectors=tuple(front_detectors)))
    check_scenario(scenario, seconds)  # before the recording file is opened
    recorder = None
    if record_path:
        from lanekeep.record import RerunRecorder

        recorder = RerunRecorder(Path(record_path), scenario, every=record_every,
                                 jpeg_quality=jpeg_quality)
    with detector_weights(weights), Episode(scenario, recorder=recorder) as episode:
        trace = EpisodeTrace(list(episode.front))

        def on_step(result, total: int) -> None:
            trace.add(result)
            if progress:
                _progress(result.index + 1, total, scenario.name)

        report = episode.run(seconds, on_step=on_step)
        if progress:
            print(file=sys.stderr)
        if not report.completed:
            print(f"stopped ({report.stop_reason}): writing the partial report",
                  file=sys.stderr)
        if plots_dir:
            write_plots(trace, episode.world.road, Path(plots_dir), scenario.name)
    return report


def _progress(done: int, total: int, label: str) -> None:
    width = 30
    filled = int(width * done / max(total, 1))
    print(f"\r{label:<28} [{'#' * filled}{'.' * (width - filled)}] {done}/{total}",
          end="", file=sys.stderr, flush=True)


def _cmd_run(args: argparse.Namespace) -> int:
    from lanekeep.scenario import load_scenario

    check_options(args)
    scenario = load_scenario(args.scenario)
    code = weights_error("run", args, [scenario])
    if code is not None:
        return code
    report = run_episode(args.scenario, args.seed, args.seconds, args.plots, args.record,
                         args.record_every, args.jpeg_quality, progress=sys.stderr.isatty(),
                         mode=args.mode, weights=args.weights)
    print(f"scenario {report.scenario} (seed {report.seed}): {report.duration_s:.1f} s simulated "
          f"in {report.wall_s:.1f} s")
    print(report.table())
    if args.json:
        write_json(args.json, report_document(report, scenario))
    if report.completed:
        return 0
    return 130 if report.stop_reason == "interrupted" else 1


def _bench_one(job: BenchJob, seconds: float | None, plots: str | None,
               record_dir: str | None, weights: str | None = None) -> dict | None:
    label = job.label
    record = str(Path(record_dir) / f"{label}.rrd") if record_dir else None
    plots_dir = str(Path(plots) / label) if plots else None
    with stop_signals_interrupt():  # only while an episode runs (lanekeep/interrupts.py)
        if _STOP is not None and _STOP.is_set():  # queued before the bench was stopped
            return None
        return run_episode(job.scenario, job.seed, seconds, plots_dir, record, mode=job.mode,
                           front_detectors=job.front_detectors, weights=weights).to_dict()


def _report_from_dict(d: dict) -> EpisodeReport:
    """A worker's `to_dict()` (or a report read back from JSON: null floats, metadata keys)."""
    return report_from_dict(d)


def worker_threads(workers: int) -> int:
    """Threads each bench worker may use so that the workers together fill the machine once.

    Mesa's llvmpipe rasterises with one thread per core and OpenCV parallelises per call; with
    two workers on two cores both would run two threads each and fight over the cores.
    """
    return max(1, (os.cpu_count() or 1) // max(workers, 1))


_STOP = None  # in a bench worker: the parent's "stop" event (multiprocessing.Event)


def _init_worker(threads: int, stop) -> None:
    """Runs first in every bench worker: thread counts before EGL or OpenCV start; an idle
    worker ignores Ctrl-C and SIGTERM (one dying would break the pool for all) and starts no
    episode once the parent has set `stop`."""
    global _STOP
    _STOP = stop
    ignore_stop_signals()
    os.environ["LP_NUM_THREADS"] = str(threads)  # Mesa llvmpipe, read when EGL starts
    import cv2

    cv2.setNumThreads(threads)


@dataclasses.dataclass(frozen=True)
class BenchJob:
    """One bench episode: a scenario (name or file), a seed, the estimation mode and the front
    models (None: the scenario's own)."""

    scenario: str
    seed: int | None = None
    mode: str | None = None
    front_detectors: tuple[str, ...] | None = None

    @property
    def label(self) -> str:
        """Its key in reports: the scenario, "@model" for a model-only loop."""
        name = Path(self.scenario).stem if self.scenario.endswith(".toml") else self.scenario
        if self.front_detectors is None:
            return name
        return f"{name}@{'+'.join(self.front_detectors)}"


def longest_first(jobs: list[BenchJob], seconds: float | None) -> list[int]:
    """Indices of `jobs` in the order to start them: the longest episodes first, so that no
    worker starts a long one while the others are idle at the end (ties keep the order)."""
    from lanekeep.scenario import load_scenario

    def simulated_s(i: int) -> float:
        duration = load_scenario(jobs[i].scenario).duration_s
        return duration if seconds is None else min(duration, seconds)

    return sorted(range(len(jobs)), key=simulated_s, reverse=True)


STOP_GRACE_S = 60.0  # how long stopped workers get to return their partial reports


class BenchInterrupted(KeyboardInterrupt):
    """A bench stopped by Ctrl-C or SIGTERM, with what it had: `reports` in the jobs' order
    (finished, partial with `completed = False`, or None for an episode that never ran)."""

    def __init__(self, reports: list[EpisodeReport | None], wall_s: float) -> None:
        super().__init__("interrupted")
        self.reports, self.wall_s = reports, wall_s


def run_bench(jobs: list[BenchJob], workers: int, seconds: float | None = None,
              plots: str | None = None, record_dir: str | None = None,
              on_done=None, weights: str | None = None) -> tuple[list[EpisodeReport], float]:
    """Episodes in `workers` processes, longest first: (reports in the jobs' order, wall s).

    `weights`: the file of every learned detector (None: their shipped one).

    `on_done(done, total)` is called as each episode finishes. On KeyboardInterrupt (Ctrl-C,
    or SIGTERM under `lanekeep.cli.main`) the waiting episodes are cancelled, the running ones
    are told to stop and return their partial reports (recordings finalised), any worker still
    alive after STOP_GRACE_S is killed, and BenchInterrupted carries the reports.
    """
    start = time.perf_counter()
    reports: list[EpisodeReport | None] = [None] * len(jobs)
    context = multiprocessing.get_context("spawn")
    stop = context.Event()
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_init_worker,
                               initargs=(worker_threads(workers), stop))
    futures = {}
    try:
        futures = {pool.submit(_bench_one, jobs[i], seconds, plots, record_dir, weights): i
                   for i in longest_first(jobs, seconds)}
        for done, future in enumerate(as_completed(futures), start=1):
            reports[futures[future]] = _report_from_dict(future.result())
            if on_done is not None:
                on_done(done, len(jobs))
    except KeyboardInterrupt:
        with stop_signals_held():
            stop.set()
            _collect_partial(pool, futures, reports)
        raise BenchInterrupted(reports, time.perf_counter() - start) from None
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        end_children(STOP_GRACE_S)
        raise
    pool.shutdown(wait=True)
    return reports, time.perf_counter() - start


def _collect_partial(pool: ProcessPoolExecutor, futures: dict, reports: list) -> None:
    """After an interrupt: cancel the waiting episodes, stop the running ones, keep every
    report that comes back within STOP_GRACE_S, and leave no worker behind."""
    for future in futures:
        future.cancel()
    stop_children()  # a terminal's Ctrl-C reached them already; SIGTERM did not
    running = [f for f in futures if not f.cancelled()]
    wait(running, timeout=STOP_GRACE_S)
    for future in running:
        if future.done() and future.exception() is None and future.result() is not None:
            reports[futures[future]] = _report_from_dict(future.result())
    pool.shutdown(wait=False, cancel_futures=True)
    end_children(STOP_GRACE_S)


def _cmd_bench(args: argparse.Namespace) -> int:
    from lanekeep.paper_mode import with_mode
    from lanekeep.scenario import load_scenario, shipped_scenarios

    check_options(args)
    names = args.scenarios or shipped_scenarios()
    scenarios = {name: load_scenario(name) for name in names}  # fail fast on a bad name
    for scenario in scenarios.values():  # and on a bad scenario, before any worker starts
        if args.seed is not None:  # (shadow casters stand where the seed puts them)
            scenario = dataclasses.replace(scenario, seed=args.seed)
        check_scenario(with_mode(scenario, args.mode), args.seconds)
    code = weights_error("bench", args, list(scenarios.values()))
    if code is not None:
        return code
    if args.record_dir:
        Path(args.record_dir).mkdir(parents=True, exist_ok=True)
    jobs = [BenchJob(name, args.seed, args.mode) for name in names]
    if args.single_model:
        jobs += [BenchJob(name, args.seed, args.mode, (model,)) for name in names
                 for model in scenarios[name].estimation.front_detectors]
    try:
        done_reports, wall = run_bench(
            jobs, args.workers, args.seconds, args.plots, args.record_dir,
            on_done=lambda done, total: _progress(done, total, "bench"), weights=args.weights)
    except BenchInterrupted as stop:
        return _bench_interrupted(args, jobs, scenarios, stop)
    reports = {job.label: report for job, report in zip(jobs, done_reports, strict=True)}
    if args.json:  # first: a failing table must not lose the episodes
        write_json(args.json, {job.label: report_document(reports[job.label],
                                                          scenarios[job.scenario])
                               for job in jobs})
    main_labels = [job.label for job in jobs[: len(names)]]
    print(file=sys.stderr)
    for label in main_labels:
        r = reports[label]
        print(f"\n== {label} (seed {r.seed}, {r.duration_s:.0f} s, wall {r.wall_s:.0f} s) ==")
        print(r.table())
    print("\n" + summary_table([reports[label] for label in main_labels]))
    if args.single_model:
        print("\n" + single_model_table(jobs, reports))
    print(f"\nbench wall time: {wall:.1f} s for {len(jobs)} episodes "
          f"with {args.workers} workers")
    return 0


def _bench_interrupted(args: argparse.Namespace, jobs: list[BenchJob],
                       scenarios: dict[str, Scenario], stop: BenchInterrupted) -> int:
    """Keep what an interrupted bench has: the JSON of every episode that returned a report
    (partial ones say `completed: false`), a table each, and which episodes never ran."""
    with stop_signals_held():
        kept = {job.label: (job, r) for job, r in zip(jobs, stop.reports, strict=True)
                if r is not None}
        if args.json:
            write_json(args.json, {label: report_document(r, scenarios[job.scenario])
                                   for label, (job, r) in kept.items()})
        print(file=sys.stderr)
        for label, (_, r) in kept.items():
            state = "complete" if r.completed else f"stopped: {r.stop_reason}"
            print(f"\n== {label} (seed {r.seed}, {r.duration_s:.0f} s, {state}) ==")
            print(r.table())
        partial = [label for label, (_, r) in kept.items() if not r.completed]
        not_run = [job.label for job in jobs if job.label not in kept]
        print(f"bench interrupted after {stop.wall_s:.1f} s: {len(kept) - len(partial)} "
              f"episodes complete, {len(partial)} stopped part-way"
              f"{' (' + ', '.join(partial) + ')' if partial else ''}, {len(not_run)} not run"
              f"{' (' + ', '.join(not_run) + ')' if not_run else ''}", file=sys.stderr)
    return 130


def _best(sources: dict, names: list[str]) -> tuple[str, float]:
    """The source with the lowest offset RMSE among `names` (NaN counts as worst)."""
    rmse = {n: sources[n].rmse_cm for n in names}
    name = min(rmse, key=lambda n: math.inf if math.isnan(rmse[n]) else rmse[n])
    return name, rmse[name]


def summary_table(reports: list[EpisodeReport]) -> str:
    """One line per scenario: fused vs the best front model's own track (like for like: both
    Kalman estimates at the same look-ahead) and its best raw detection; reference; safety."""
    header = (f"{'scenario':<28}{'fused':>8}{'best track':>20}{'best raw':>20}"
              f"{'reference':>11}{'car RMS':>9}{'depart':>8}{'switch':>8}")
    lines = [header, "-" * len(header)]
    for r in reports:
        tracks = [k for k in r.sources if k.endswith(":track")]
        raws = [k[: -len(":track")] for k in tracks]
        track_name, track = _best(r.sources, tracks)
        raw_name, raw = _best(r.sources, raws)
        lines.append(
            f"{r.scenario:<28}{r.sources['fused'].rmse_cm:>8.1f}"
            f"{track:>8.1f} ({track_name.split(':')[0][:9]:>9})"
            f"{raw:>8.1f} ({raw_name[:9]:>9})"
            f"{r.sources['reference'].rmse_cm:>11.1f}{r.car_rms_cm:>9.1f}"
            f"{r.lane_departures:>8d}{r.mmae_switches:>8d}"
        )
    lines.append("(offset RMSE in cm; track = a model's own Kalman track at the fused output's "
                 "look-ahead; raw = its detections, on the steps it had one; fused = the MMAE "
                 "output)")
    return "\n".join(lines)


def single_model_table(jobs: list[BenchJob], reports: dict[str, EpisodeReport]) -> str:
    """The closed loop driven by the MMAE beside the same loop driven by each front model
    alone (the paper's "model-only system"): the car's own lateral error and departures."""
    header = f"{'scenario':<28}{'loop':>22}{'car RMS':>9}{'car max':>9}{'depart':>8}"
    lines = ["closed loop: MMAE vs each front model alone", header, "-" * len(header)]
    for main in (j for j in jobs if j.front_detectors is None):
        alone = [j for j in jobs if j.scenario == main.scenario and j.front_detectors]
        for job in [main, *alone]:
            r = reports[job.label]
            loop = "MMAE" if job is main else "+".join(job.front_detectors) + " only"
            lines.append(f"{main.label if job is main else '':<28}{loop:>22}"
                         f"{r.car_rms_cm:>9.1f}{r.car_max_cm:>9.1f}{r.lane_departures:>8d}")
    lines.append("(car = its true lateral offset from the lane centre, cm)")
    return "\n".join(lines)


def register(sub) -> None:
    p = sub.add_parser("run", help="run one closed-loop episode and print its table")
    p.add_argument("scenario", help="shipped scenario name or path to a .toml file")
    p.add_argument("--seed", type=int, default=None, help="override the scenario's seed")
    p.add_argument("--seconds", type=float, default=None, help="stop after S simulated seconds")
    p.add_argument("--json", default=None, help="write the report as JSON")
    p.add_argument("--plots", default=None, help="folder for PNG plots")
    p.add_argument("--record", default=None, help="write a rerun recording (.rrd)")
    p.add_argument("--record-every", type=int, default=1, help="record every N-th step")
    p.add_argument("--jpeg-quality", type=int, default=75, help="JPEG quality of recorded images")
    p.add_argument("--mode", choices=ESTIMATION_MODES, default=None,
                   help="estimation mode: 'default' (ours) or 'paper' (paper 001's own loop, "
                        "lanekeep/paper_mode.py); default: the scenario file's")
    add_weights_option(p)
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("bench", help="run many scenarios in parallel; paper-style tables")
    p.add_argument("scenarios", nargs="*", help="scenario names (default: all shipped)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--seconds", type=float, default=None)
    p.add_argument("--json", default=None)
    p.add_argument("--plots", default=None, help="folder; one subfolder of PNGs per scenario")
    p.add_argument("--record-dir", default=None, help="write one .rrd per scenario here")
    p.add_argument("--mode", choices=ESTIMATION_MODES, default=None,
                   help="estimation mode for every episode ('default' or 'paper'); "
                        "default: each scenario file's")
    p.add_argument("--single-model", action="store_true",
                   help="also drive each scenario closed loop with each front model alone "
                        "and print the car's lateral RMS / max and departures beside the "
                        "MMAE loop's; in --json these episodes are keyed 'SCENARIO@MODEL'")
    add_weights_option(p)
    p.set_defaults(func=_cmd_bench)


def add_weights_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--weights", metavar="FILE", default=None,
                   help="weights of the learned detector (lanenet) wherever a scenario uses it "
                        "(default: the shipped detectors/weights/lanenet.pt); loaded before "
                        "anything runs, a bad file is one error line and exit 2")
