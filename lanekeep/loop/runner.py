"""Running episodes: one to its end (`run_episode`, judged by its criteria, with plots and a
recording if asked), or many in worker processes (`run_bench`, longest first, interruptible
with every partial report kept). `lanekeep run`, `bench`, `perf` and `sweep` call these.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path

from lanekeep.core.interrupts import (
    end_children,
    stop_children,
    stop_signals_held,
    stop_signals_interrupt,
)
from lanekeep.core.workers import (
    episode_running,
    init_worker,
    spawn_context,
    worker_pool,
    worker_threads,
)
from lanekeep.loop.checks import check_scenario
from lanekeep.loop.overrides import PluginOverrides
from lanekeep.report.json_io import report_from_dict
from lanekeep.scoring import criteria as criteria_mod
from lanekeep.scoring.metrics import EpisodeReport


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
    criteria (lanekeep/scoring/criteria.py), in place of the file's. `progress`: progress on
    stderr (a bar on a terminal, else a line every few seconds: lanekeep/core/progress.py);
    `on_step(done, total)` is called after every step. `plugins`: the command line's
    detectors and controller (lanekeep/cli/plugins.py), before `front_detectors`.
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
    full_length = seconds is None or seconds >= scenario.duration_s
    scenario = dataclasses.replace(scenario, criteria=criteria_mod.for_run(
        scenario.criteria, criteria, full_length))  # off_road_distance_m ends the episode
    check_scenario(scenario, seconds)  # before the recording file is opened
    recorder = None
    if record_path:
        from lanekeep.report.record import RerunRecorder

        recorder = RerunRecorder(Path(record_path), scenario, every=record_every,
                                 jpeg_quality=jpeg_quality)
    from lanekeep.core.progress import step_bar

    with detector_weights(weights), Episode(scenario, recorder=recorder) as episode:
        trace = EpisodeTrace(list(episode.driver.front))
        total = episode.total_steps if seconds is None else int(round(seconds / episode.dt_s))
        bar = step_bar(total, scenario.name, enabled=None if progress else False,
                       step_s=episode.dt_s)

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


def _bench_one(job: BenchJob, seconds: float | None, plots: str | None,
               record_dir: str | None, weights: str | None = None,
               criteria: dict | None = None, index: int = 0) -> dict | None:
    label = job.episode_label
    record = str(Path(record_dir) / f"{label}.rrd") if record_dir else None
    plots_dir = str(Path(plots) / label) if plots else None

    def on_step(done: int, total: int) -> None:  # the parent's progress bar
        if _STEPS is not None:
            _STEPS.put((index, done))

    with stop_signals_interrupt(), episode_running():  # lanekeep/core/interrupts.py, workers.py
        if _STOP is not None and _STOP.is_set():  # queued before the bench was stopped
            return None
        return run_episode(job.scenario, job.seed, seconds, plots_dir, record, mode=job.mode,
                           front_detectors=job.front_detectors, weights=weights,
                           criteria=criteria, on_step=on_step, plugins=job.plugins).to_dict()


_STOP = None  # in a bench worker: the parent's "stop" event (multiprocessing.Event)


_STEPS = None  # in a bench worker: the parent's queue of (job index, steps done)


def _init_worker(threads: int, stop, steps=None, running=None) -> None:
    """Runs first in every bench worker (lanekeep/core/workers.py), and keeps the parent's
    `stop` event (no episode starts once it is set), `steps` queue (its episodes' progress)
    and count of running episodes (an episode alone at the end runs on both cores)."""
    global _STOP, _STEPS
    _STOP, _STEPS = stop, steps
    init_worker(threads, running)


@dataclasses.dataclass(frozen=True)
class BenchJob:
    """One bench episode: a scenario (name or file), a seed, the estimation mode and the front
    models (None: the scenario's own)."""

    scenario: str
    seed: int | None = None
    mode: str | None = None
    front_detectors: tuple[str, ...] | None = None
    plugins: PluginOverrides | None = None  # --front-detectors, --controller, ... (all jobs)
    seed_in_label: bool = False  # a bench over several seeds: one file name per seed

    @property
    def label(self) -> str:
        """Its key in reports: the scenario, "@model" for a model-only loop."""
        name = Path(self.scenario).stem if self.scenario.endswith(".toml") else self.scenario
        if self.front_detectors is None:
            return name
        return f"{name}@{'+'.join(self.front_detectors)}"

    @property
    def episode_label(self) -> str:
        """Its own name (recordings, plots, JUnit cases): the label, ".seedN" added in a bench
        over several seeds."""
        return f"{self.label}.seed{self.seed}" if self.seed_in_label else self.label


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
    context = spawn_context()
    stop, steps, running = context.Event(), context.Queue(), context.Value("i", 0)
    pool = worker_pool(workers, _init_worker, (worker_threads(workers), stop, steps, running))
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
                reports[i] = report_from_dict(future.result())
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
            reports[futures[future]] = report_from_dict(future.result())
    pool.shutdown(wait=False, cancel_futures=True)
    end_children(STOP_GRACE_S)
