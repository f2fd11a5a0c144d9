"""`lanekeep perf` reports what its help promises; the bench runner orders and reproduces.

No timing is asserted here: speed targets are benchmarks (`lanekeep perf`), not tests.
"""

import json

from lanekeep.cli.main import main
from lanekeep.core.workers import worker_threads
from lanekeep.loop.perf import format_results
from lanekeep.loop.runner import BenchJob, longest_first, run_bench, run_episode

STAGES = {"render_front", "render_rear", "effects_front", "effects_rear", "detect_hough",
          "detect_sliding_window", "detect_lanenet", "detect_reference", "track", "mmae",
          "control", "physics", "traffic", "sensors", "score", "record"}


def test_perf_json_holds_every_documented_figure(tmp_path, capsys):
    out = tmp_path / "perf.json"
    code = main(["perf", "--seconds", "0.2", "--bench-episodes", "2", "--bench-seconds", "0.2",
                 "--json", str(out)])
    assert code == 0
    r = json.loads(out.read_text())
    assert r["cameras"] == {"front": "1280x720", "rear": "1280x720"}
    assert set(r["stage_ms"]) == STAGES
    assert all(ms >= 0.0 for ms in r["stage_ms"].values())
    # The stages partition the step: their sum is the step less the loop's own bookkeeping.
    assert 0.8 * r["step_ms"] <= sum(r["stage_ms"].values()) <= r["step_ms"]
    assert r["real_time_factor"] == 100.0 / r["step_ms"]
    assert r["real_time_factor_recording"] == 100.0 / r["step_ms_recording"]
    assert r["physics_steps_per_s"] > 0
    bench = r["bench"]
    assert bench["episodes"] == 2
    for workers in ("workers_1", "workers_2"):
        assert set(bench[workers]) == {"wall_s", "episodes_per_s", "simulated_s_per_s"}
    assert bench["speedup"] == (bench["workers_2"]["episodes_per_s"]
                                / bench["workers_1"]["episodes_per_s"])
    printed = capsys.readouterr().out
    assert "real-time factor" in printed and str(out) in printed
    assert format_results(r).splitlines()[0] in printed


def test_perf_rejects_a_non_positive_duration(capsys):
    assert main(["perf", "--seconds", "0"]) == 2
    assert "--seconds" in capsys.readouterr().err


def test_bench_starts_the_longest_episodes_first():
    # 20 s, 30 s and 25 s long: started as 30, 25, 20.
    jobs = [BenchJob("clear_straight"), BenchJob("clear_curve"), BenchJob("case1_building_shadows")]
    assert longest_first(jobs, None) == [1, 2, 0]
    # A cap on the episode length makes every job equally long: the given order stays.
    assert longest_first(jobs, 0.5) == [0, 1, 2]


def test_worker_threads_share_the_machine():
    import os

    cpus = os.cpu_count() or 1
    assert worker_threads(1) == cpus
    assert worker_threads(cpus) == 1
    assert worker_threads(4 * cpus) == 1


def test_bench_workers_reproduce_the_in_process_episode():
    """Worker processes (one llvmpipe and OpenCV thread each) give the metrics of the same
    episode run here: thread counts change speed, never results."""
    jobs = [BenchJob("clear_straight", 3), BenchJob("night", 5)]
    reports, _ = run_bench(jobs, workers=2, seconds=0.5)
    for job, report in zip(jobs, reports, strict=True):
        here = run_episode(job.scenario, job.seed, 0.5)
        assert report.scenario == here.scenario and report.seed == job.seed
        a, b = report.to_dict(), here.to_dict()
        a.pop("wall_s"), b.pop("wall_s")
        assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)  # NaN == NaN


def test_stage_clock_splits_the_time_between_laps(monkeypatch):
    import lanekeep.core.timing as timing

    ticks = iter([0.0, 1.0, 1.25, 2.0, 10.0, 10.5])
    monkeypatch.setattr(timing.time, "perf_counter", lambda: next(ticks))
    clock = timing.StageClock()  # 0.0
    clock.start()  # 1.0
    clock.lap("render")  # 1.25
    clock.lap("detect")  # 2.0
    clock.start()  # 10.0
    clock.lap("render")  # 10.5
    assert clock.mean_ms() == {"render": 375.0, "detect": 375.0}


def test_an_episode_alone_in_a_bench_gets_the_cores_the_finished_ones_left(monkeypatch):
    """A bench worker's share of the cores follows the episodes running now: with as many
    running as cores each has one thread; the last one left has them all."""
    import multiprocessing
    import os

    from lanekeep.core import workers

    cpus = os.cpu_count() or 1
    running = multiprocessing.get_context("spawn").Value("i", 0)
    monkeypatch.setattr(workers, "_RUNNING", running)
    running.value = cpus - 1  # the others
    with workers.episode_running():
        assert running.value == cpus
        assert workers.threads_now() == 1
        running.value = 0  # they finished
        assert workers.threads_now() == cpus
        running.value = 1
    assert running.value == 0
