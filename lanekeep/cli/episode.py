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
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path

from lanekeep.cli.plugins import PluginOverrides, check_plugins
from lanekeep.cli.plugins import add_options as add_plugin_options
from lanekeep.core.config_io import ConfigError
from lanekeep.core.interrupts import (
    end_children,
    ignore_stop_signals,
    stop_children,
    stop_signals_held,
    stop_signals_interrupt,
)
from lanekeep.report.json_io import report_document, report_from_dict, write_json
from lanekeep.scenario.schema import ESTIMATION_MODES, Scenario
from lanekeep.scoring import criteria as criteria_mod
from lanekeep.scoring.metrics import EpisodeReport


def check_scenario(scenario: Scenario, seconds: float | None = None) -> None:
    """Everything about a scenario that building its episode would reject, checked in 30-160 ms
    so that a bad scenario fails before anything runs or any file is written (`lanekeep
    bench` checks every scenario before a worker starts): the world's cross-field checks
    (lanekeep.world.build.check_scenario), the detector and controller names (imported), and that
    `seconds` makes at least one control step.

    Raises:
      ScenarioError: naming the scenario's file and key.
      ConfigError: `seconds` makes no control step (key "--seconds").
    """
    from lanekeep.world.build import check_scenario as check_world

    check_plugins(scenario)  # detector and controller names, import paths, entry points
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
                weights: str | None = None, criteria: dict | None = None,
                on_step=None, plugins: PluginOverrides | None = None) -> EpisodeReport:
    """Run one scenario to the end and return its report, judged by its criteria (optionally
    plots and a recording).

    `mode` ("default" | "paper") and `front_detectors` (e.g. ("hough",) for a model-only
    loop) override the scenario file's; None keeps them. `weights` is the file of every
    learned detector in the episode (None: their shipped one). `criteria`: the command line's
    criteria (lanekeep/scoring/criteria.py), in place of the file's. `progress`: a step bar on stderr
    (a terminal only); `on_step(done, total)` is called after every step. `plugins`: the
    command line's detectors and controller (lanekeep/cli/plugins.py), before `front_detectors`.
    """
    import lanekeep  # noqa: F401 - EGL before mujoco
    from lanekeep.detectors.registry import detector_weights
    from lanekeep.loop.episode import Episode
    from lanekeep.loop.paper_mode import with_mode
    from lanekeep.report.plots import EpisodeTrace, plot_title, write_plots
    from lanekeep.scenario.schema import load_scenario

    scenario = with_mode(load_scenario(scenario_name), mode)
    if seed is not None:
        scenario = dataclasses.replace(scenario, seed=seed)
    if plugins is not None:
        scenario = plugins.apply(scenario)
    if front_detectors is not None:
        scenario = dataclasses.replace(scenario, estimation=dataclasses.replace(
            scenario.estimation, front_detectors=tuple(front_detectors)))
    scenario = dataclasses.replace(scenario, criteria=criteria_mod.with_overrides(
        scenario.criteria, criteria))  # off_road_distance_m ends the episode itself
    check_scenario(scenario, seconds)  # before the recording file is opened
    recorder = None
    if record_path:
        from lanekeep.report.record import RerunRecorder

        recorder = RerunRecorder(Path(record_path), scenario, every=record_every,
                                 jpeg_quality=jpeg_quality)
    from lanekeep.core.progress import step_bar

    with detector_weights(weights), Episode(scenario, recorder=recorder) as episode:
        trace = EpisodeTrace(list(episode.front), episode.world.road,
                             scenario.road.ego_lane)
        total = episode.total_steps if seconds is None else int(round(seconds / episode.dt_s))
        bar = step_bar(total, scenario.name, enabled=None if progress else False)

        def each_step(result, total: int) -> None:
            trace.add(result)
            bar.update(1)
            if on_step is not None:
                on_step(result.index + 1, total)

        with bar:
            report = episode.run(seconds, on_step=each_step)
        report = criteria_mod.judge(report, scenario.criteria)
        if not report.completed:
            print(f"stopped ({report.stop_reason}): writing the partial report",
                  file=sys.stderr)
        if plots_dir:
            for written in write_plots(trace, episode.world.road, Path(plots_dir),
                                       plot_title(scenario)):
                print(f"wrote {written}", file=sys.stderr)
    if record_path:  # finalised when the episode closed
        print(f"wrote {record_path} (open it with `lanekeep view {record_path}`)",
              file=sys.stderr)
    return report


def _cmd_run(args: argparse.Namespace) -> int:
    from lanekeep.scenario.schema import load_scenario

    check_options(args)
    overrides = criteria_mod.overrides_from_args(args)
    plugins = PluginOverrides.from_args(args)
    scenario = plugins.apply(load_scenario(args.scenario))
    code = weights_error("run", args, [scenario])
    if code is not None:
        return code
    report = run_episode(args.scenario, args.seed, args.seconds, args.plots, args.record,
                         args.record_every, args.jpeg_quality, progress=sys.stderr.isatty(),
                         mode=args.mode, weights=args.weights, criteria=overrides,
                         plugins=plugins)
    print(f"scenario {report.scenario} (seed {report.seed}): {report.duration_s:.1f} s simulated "
          f"in {report.wall_s:.1f} s")
    print(report.table())
    if args.json:
        write_json(args.json, report_document(report, scenario))
    if report.status == "interrupted":
        return 130
    return 0 if report.passed else 1  # a stopped episode fails its "status" criterion


def _bench_one(job: BenchJob, seconds: float | None, plots: str | None,
               record_dir: str | None, weights: str | None = None,
               criteria: dict | None = None, index: int = 0) -> dict | None:
    label = job.label
    record = str(Path(record_dir) / f"{label}.rrd") if record_dir else None
    plots_dir = str(Path(plots) / label) if plots else None

    def on_step(done: int, total: int) -> None:  # the parent's progress bar
        if _STEPS is not None:
            _STEPS.put((index, done))

    with stop_signals_interrupt():  # only while an episode runs (lanekeep/core/interrupts.py)
        if _STOP is not None and _STOP.is_set():  # queued before the bench was stopped
            return None
        return run_episode(job.scenario, job.seed, seconds, plots_dir, record, mode=job.mode,
                           front_detectors=job.front_detectors, weights=weights,
                           criteria=criteria, on_step=on_step, plugins=job.plugins).to_dict()


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
_STEPS = None  # in a bench worker: the parent's queue of (job index, steps done)


def _init_worker(threads: int, stop, steps=None) -> None:
    """Runs first in every bench worker: thread counts before EGL or OpenCV start; an idle
    worker ignores Ctrl-C and SIGTERM (one dying would break the pool for all) and starts no
    episode once the parent has set `stop`; `steps` carries its episodes' progress."""
    global _STOP, _STEPS
    _STOP, _STEPS = stop, steps
    ignore_stop_signals()
    os.environ["LP_NUM_THREADS"] = str(threads)  # Mesa llvmpipe, read when EGL starts
    os.environ["OMP_NUM_THREADS"] = str(threads)  # torch (LaneNet), read at its import
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
    plugins: PluginOverrides | None = None  # --front-detectors, --controller, ... (all jobs)

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
    steps = job_steps(jobs, seconds)
    return sorted(range(len(jobs)), key=lambda i: steps[i], reverse=True)


def job_steps(jobs: list[BenchJob], seconds: float | None) -> list[int]:
    """Control steps each job will make if it runs to its end (as Episode.run counts them)."""
    from lanekeep.scenario.schema import load_scenario

    out = []
    for job in jobs:
        scenario = load_scenario(job.scenario)
        simulated = scenario.duration_s if seconds is None else seconds
        out.append(int(round(simulated / scenario.control_period_s)))
    return out


STOP_GRACE_S = 60.0  # how long stopped workers get to return their partial reports


class BenchInterrupted(KeyboardInterrupt):
    """A bench stopped by Ctrl-C or SIGTERM, with what it had: `reports` in the jobs' order
    (finished, partial with `completed = False`, or None for an episode that never ran)."""

    def __init__(self, reports: list[EpisodeReport | None], wall_s: float) -> None:
        super().__init__("interrupted")
        self.reports, self.wall_s = reports, wall_s


def run_bench(jobs: list[BenchJob], workers: int, seconds: float | None = None,
              plots: str | None = None, record_dir: str | None = None,
              on_done=None, weights: str | None = None, criteria: dict | None = None,
              on_steps=None) -> tuple[list[EpisodeReport], float]:
    """Episodes in `workers` processes, longest first: (reports in the jobs' order, wall s).

    `weights`: the file of every learned detector (None: their shipped one). `criteria`: the
    command line's criteria (lanekeep/scoring/criteria.py); each report comes back judged.

    `on_done(done, total)` is called as each episode finishes, `on_steps(done, total)` with
    the control steps of all episodes as the workers report them (an episode that ends early,
    off the road, takes its remaining steps off the total). On KeyboardInterrupt (Ctrl-C,
    or SIGTERM under `lanekeep.cli.main.main`) the waiting episodes are cancelled, the running ones
    are told to stop and return their partial reports (recordings finalised), any worker still
    alive after STOP_GRACE_S is killed, and BenchInterrupted carries the reports.
    """
    start = time.perf_counter()
    reports: list[EpisodeReport | None] = [None] * len(jobs)
    context = multiprocessing.get_context("spawn")
    stop, steps = context.Event(), context.Queue()
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_init_worker,
                               initargs=(worker_threads(workers), stop, steps))
    futures = {}
    expected = job_steps(jobs, seconds)
    progress = _StepProgress(expected, steps, on_steps)
    try:
        futures = {pool.submit(_bench_one, jobs[i], seconds, plots, record_dir, weights,
                               criteria, i): i
                   for i in longest_first(jobs, seconds)}
        pending, done = set(futures), 0
        while pending:
            finished, pending = wait(pending, timeout=0.25, return_when=FIRST_COMPLETED)
            progress.drain()
            for future in finished:
                i = futures[future]
                reports[i] = _report_from_dict(future.result())
                progress.finished(i, reports[i].steps)
                done += 1
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


class _StepProgress:
    """The bench's step count from the workers' (job, steps done) messages, for `on_steps`."""

    def __init__(self, expected: list[int], queue, on_steps) -> None:
        self.expected, self.queue, self.on_steps = list(expected), queue, on_steps
        self.done = [0] * len(expected)

    def drain(self) -> None:
        import queue

        changed = False
        while True:
            try:
                i, n = self.queue.get_nowait()
            except queue.Empty:
                break
            self.done[i], changed = max(self.done[i], n), True
        if changed:
            self._report()

    def finished(self, i: int, steps: int) -> None:
        self.drain()
        self.done[i] = self.expected[i] = steps
        self._report()

    def _report(self) -> None:
        if self.on_steps is not None:
            self.on_steps(sum(self.done), sum(self.expected))


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
    from lanekeep.loop.paper_mode import with_mode
    from lanekeep.scenario.schema import load_scenario, shipped_scenarios

    check_options(args)
    overrides = criteria_mod.overrides_from_args(args)
    plugins = PluginOverrides.from_args(args)
    names = args.scenarios or shipped_scenarios()
    # as each episode will run them: the mode first (its own front models), then the command
    # line's detectors; fail fast on a bad name
    scenarios = {name: plugins.apply(with_mode(load_scenario(name), args.mode))
                 for name in names}
    for scenario in scenarios.values():  # and on a bad scenario, before any worker starts
        if args.seed is not None:  # (shadow casters stand where the seed puts them)
            scenario = dataclasses.replace(scenario, seed=args.seed)
        check_scenario(scenario, args.seconds)
    code = weights_error("bench", args, list(scenarios.values()))
    if code is not None:
        return code
    if args.record_dir:
        Path(args.record_dir).mkdir(parents=True, exist_ok=True)
    jobs = [BenchJob(name, args.seed, args.mode, plugins=plugins) for name in names]
    if args.single_model:
        jobs += [BenchJob(name, args.seed, args.mode, (model,), plugins) for name in names
                 for model in scenarios[name].estimation.front_detectors]
    from lanekeep.core.progress import set_progress, step_bar
    from lanekeep.report.junit import write_junit

    bar = step_bar(sum(job_steps(jobs, args.seconds)), f"bench ({len(jobs)} episodes)")
    try:
        with bar:
            done_reports, wall = run_bench(
                jobs, args.workers, args.seconds, args.plots, args.record_dir,
                weights=args.weights, criteria=overrides,
                on_steps=lambda done, total: set_progress(bar, done, total))
    except BenchInterrupted as stop:
        return _bench_interrupted(args, jobs, scenarios, stop)
    reports = {job.label: report for job, report in zip(jobs, done_reports, strict=True)}
    if args.json:  # first: a failing table must not lose the episodes
        write_json(args.json, {job.label: report_document(reports[job.label],
                                                          scenarios[job.scenario])
                               for job in jobs})
    if args.junit:
        write_junit(args.junit, reports, wall)
    main_labels = [job.label for job in jobs[: len(names)]]
    for label in main_labels:
        r = reports[label]
        print(f"\n== {label} (seed {r.seed}, {r.duration_s:.0f} s, wall {r.wall_s:.0f} s) ==")
        print(r.table())
    print("\n" + summary_table([reports[label] for label in main_labels]))
    print("\n" + drift_table([reports[label] for label in main_labels]))
    if args.single_model:
        print("\n" + single_model_table(jobs, reports))
    print(f"\nbench wall time: {wall:.1f} s for {len(jobs)} episodes "
          f"with {args.workers} workers")
    lines, code = bench_verdict(reports, main_labels)
    print("\n".join(lines))
    return code


def bench_verdict(reports: dict[str, EpisodeReport], main_labels: list[str]
                  ) -> tuple[list[str], int]:
    """The bench's closing lines and exit code. The code judges the scenarios as configured
    (`main_labels`); `--single-model` loops are a diagnostic (one detector driving alone),
    judged by the same criteria and reported, but not counted."""
    failed = [label for label, r in reports.items() if not r.passed]
    lines = [f"FAILED {label}: {criteria_mod.failure_message(reports[label])}"
             for label in failed]
    main_failed = [label for label in failed if label in main_labels]
    lines.append(f"criteria: {len(main_labels) - len(main_failed)} of {len(main_labels)} "
                 "scenarios passed")
    extra = len(reports) - len(main_labels)
    if extra:
        lines.append(f"model-only loops: {extra - (len(failed) - len(main_failed))} of {extra} "
                     "passed (not counted in the exit code)")
    return lines, (1 if main_failed else 0)


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
        if args.junit:
            from lanekeep.report.junit import write_junit

            write_junit(args.junit, {job.label: kept.get(job.label, (job, None))[1]
                                     for job in jobs}, stop.wall_s)
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


def _verdict(r: EpisodeReport) -> str:
    """The summary's last column: "pass", "FAIL" or the status of an episode that stopped."""
    if r.status != "completed":
        return r.status.upper().replace("_", " ")
    return ("pass" if r.passed else "FAIL") if r.criteria else "-"


def summary_table(reports: list[EpisodeReport]) -> str:
    """One line per scenario: fused vs the best front model's own track (like for like: both
    Kalman estimates at the same look-ahead) and its best raw detection; reference; safety;
    the criteria's verdict. Columns are as wide as their longest name: nothing is cut."""
    rows = []
    for r in reports:
        tracks = [k for k in r.sources if k.endswith(":track")]
        raws = [k[: -len(":track")] for k in tracks]
        rows.append((r, _best(r.sources, tracks), _best(r.sources, raws)))
    names = [n for _, (t, _), (w, _) in rows for n in (t.split(":")[0], w)] or [""]
    name_w = max(len(n) for n in names)
    scen_w = max([28, *(len(r.scenario) + 2 for r in reports)])
    best_w = name_w + 11  # "%8.1f (name)"
    header = (f"{'scenario':<{scen_w}}{'fused':>8}{'best track':>{best_w}}{'best raw':>{best_w}}"
              f"{'reference':>11}{'car RMS':>9}{'depart':>8}{'switch':>8}  result")
    lines = [header, "-" * len(header)]
    for r, (track_name, track), (raw_name, raw) in rows:
        lines.append(
            f"{r.scenario:<{scen_w}}{r.sources['fused'].rmse_cm:>8.1f}"
            f"{track:>8.1f} ({track_name.split(':')[0]:>{name_w}})"
            f"{raw:>8.1f} ({raw_name:>{name_w}})"
            f"{r.sources['reference'].rmse_cm:>11.1f}{r.car_rms_cm:>9.1f}"
            f"{r.lane_departures:>8d}{r.mmae_switches:>8d}  {_verdict(r)}"
        )
    lines.append("(offset RMSE in cm; track = a model's own Kalman track at the fused output's "
                 "look-ahead; raw = its detections, on the steps it had one; fused = the MMAE "
                 "output)")
    return "\n".join(lines)


def _finite_mean(values: list[float]) -> float:
    finite = [v for v in values if math.isfinite(v)]
    return sum(finite) / len(finite) if finite else math.nan


def drift_table(reports: list[EpisodeReport]) -> str:
    """Paper 000's tracking claim, per scenario: frame-to-frame drift (metrics.SourceReport)
    of each front model's raw detections and of its own Kalman track, and of the fused
    output; the change is the tracks' mean against the raw detections' mean."""
    rows = []
    for r in reports:
        tracks = [k for k in r.sources if k.endswith(":track")]
        raw = [r.sources[k[: -len(":track")]].drift_cm for k in tracks]
        track = [r.sources[k].drift_cm for k in tracks]
        rows.append((r.scenario, _finite_mean(raw), _finite_mean(track),
                     r.sources["fused"].drift_cm))
    scen_w = max([28, *(len(n) + 2 for n, *_ in rows)])
    header = f"{'scenario':<{scen_w}}{'raw':>8}{'tracks':>8}{'change':>9}{'fused':>8}"
    lines = ["frame-to-frame drift (cm; mean over the front models)", header, "-" * len(header)]
    for name, raw, track, fused in rows:
        change = f"{100.0 * (track - raw) / raw:+.0f}%" if raw > 0 else "-"
        lines.append(f"{name:<{scen_w}}{raw:>8.2f}{track:>8.2f}{change:>9}{fused:>8.2f}")
    raws = [raw for _, raw, _, _ in rows if math.isfinite(raw)]
    tracks = [track for _, _, track, _ in rows if math.isfinite(track)]
    if raws and tracks:
        mean_raw, mean_track = _finite_mean(raws), _finite_mean(tracks)
        lines.append(f"{'mean':<{scen_w}}{mean_raw:>8.2f}{mean_track:>8.2f}"
                     f"{100.0 * (mean_track - mean_raw) / mean_raw:>+8.0f}%")
    lines.append("(drift: RMS over consecutive steps of the offset's change minus the true "
                 "change; paper 000 reports -12% for its Kalman filter)")
    return "\n".join(lines)


def single_model_table(jobs: list[BenchJob], reports: dict[str, EpisodeReport]) -> str:
    """The closed loop driven by the MMAE beside the same loop driven by each front model
    alone (the paper's "model-only system"): the car's own lateral error and departures."""
    def loop(job: BenchJob) -> str:
        return "+".join(job.front_detectors) + " only" if job.front_detectors else "MMAE"

    scen_w = max([28, *(len(j.label) + 2 for j in jobs if j.front_detectors is None)])
    loop_w = max([22, *(len(loop(j)) + 2 for j in jobs)])
    header = (f"{'scenario':<{scen_w}}{'loop':>{loop_w}}{'car RMS':>9}{'car max':>9}"
              f"{'depart':>8}  result")
    lines = ["closed loop: MMAE vs each front model alone", header, "-" * len(header)]
    for main in (j for j in jobs if j.front_detectors is None):
        alone = [j for j in jobs if j.scenario == main.scenario and j.front_detectors]
        for job in [main, *alone]:
            r = reports[job.label]
            lines.append(f"{main.label if job is main else '':<{scen_w}}{loop(job):>{loop_w}}"
                         f"{r.car_rms_cm:>9.1f}{r.car_max_cm:>9.1f}{r.lane_departures:>8d}"
                         f"  {_verdict(r)}")
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
                        "lanekeep/loop/paper_mode.py); default: the scenario file's")
    add_weights_option(p)
    criteria_mod.add_options(p)
    add_plugin_options(p)
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
    p.add_argument("--junit", metavar="FILE", default=None,
                   help="write JUnit XML for CI: one test case per episode (and per "
                        "single-model run), a <failure> naming each criterion not met")
    add_weights_option(p)
    criteria_mod.add_options(p)
    add_plugin_options(p)
    p.set_defaults(func=_cmd_bench)


def add_weights_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--weights", metavar="FILE", default=None,
                   help="weights of the learned detector (lanenet) wherever a scenario uses it "
                        "(default: the shipped detectors/weights/lanenet.pt); loaded before "
                        "anything runs, a bad file is one error line and exit 2")
