"""`lanekeep perf`: how fast the closed loop runs on this machine (a benchmark, not a test).

It times the loop users run: a scenario's `Episode` (both cameras at the scenario's size, its
image effects, its detectors and estimators), stage by stage from the episode's own
`StageClock`, with recording off and then on; physics alone; and bench throughput with one
and two worker processes through the same code as `lanekeep bench`.

JSON keys (stable; times are wall-clock on this machine; strict JSON, null for no value):
  schema_version, lanekeep_version, scenario_sha256, seed   the file format, the package, the
                               scenario file's SHA-256 and seed (lanekeep/report/json_io.py)
  scenario, cpus               what was measured where
  cameras                      {"front": "1280x720", "rear": "1280x720"}
  front_detectors, reference_detector
  seconds                      simulated seconds of each timed loop (after one warm-up step)
  repeats                      timed loops each with recording off and on (alternating); the
                               figures below are each setting's fastest loop
  detect_threads               threads the step's detectors ran on: 2 where the process may
                               use two cores or more (lanekeep/driver/detection.py), else 1
  stage_ms                     mean ms per control step of each stage, recording off:
                               render_<camera>, effects_<camera>, detect_<detector>,
                               sensors (the vehicle signals and the radar), detect_reference,
                               track, mmae, control, physics (the car), traffic (the other
                               vehicles' model and poses, the lamps' pools), score, record;
                               with detect_threads 2 the detections' wall time is shared out
                               in proportion to each detector's own time
  step_ms                      mean ms per control step, recording off
  step_ms_recording            the same with a rerun recording written (every step)
  record_ms                    mean ms per step of the `record` stage with recording on (the
                               writer thread's JPEG encoding runs beside the loop, not in it)
  real_time_factor             simulated seconds per wall-clock second, recording off
  real_time_factor_recording   the same, recording on
  recording_cost_pct           100 * (1 - real_time_factor_recording / real_time_factor)
  physics_steps_per_s          MuJoCo steps per second of the scenario's model, nothing else
  bench                        null with --bench-episodes 0, else {episodes, seconds_each,
                               workers_1: {wall_s, episodes_per_s, simulated_s_per_s},
                               workers_2: {...}, speedup}: the perf scenario with seeds
                               0..episodes-1, each `seconds_each` long, via `lanekeep bench`'s
                               runner (process start and world build included)
  lanenet                      null with --lanenet-frames 0, else {weights, frame, frames,
                               ms_median, ms_p90, unavailable}: ms of LaneNet's `detect`
                               (resize, network, decoding) per 1280x720 frame, over `frames`
                               calls on the scenario's first front frame after 2 warm-up
                               calls; with a weights file that does not load, the ms are null
                               and `unavailable` says why (the issue's target: <= 15 ms)
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path


def _timed_loop(scenario, seconds: float, recorder=None) -> tuple[float, dict[str, float]]:
    """(mean ms per step, mean ms per stage) over `seconds` after one warm-up step."""
    from lanekeep.loop.episode import Episode

    with Episode(scenario, recorder=recorder) as episode:
        steps = max(1, int(round(seconds / episode.dt_s)))
        episode.step()  # warm-up: first renders compile llvmpipe's shaders
        episode.clock.reset()
        start = time.perf_counter()
        for _ in range(steps):
            episode.step()
        elapsed = time.perf_counter() - start
        return 1000.0 * elapsed / steps, episode.clock.mean_ms()


def _physics_steps_per_s(scenario, n: int = 2000) -> float:
    import mujoco

    from lanekeep.world.build import build

    world = build(scenario)
    world.car.apply(0.0, 0.3)
    start = time.perf_counter()
    for _ in range(n):
        mujoco.mj_step(world.model, world.data)
    return n / (time.perf_counter() - start)


def lanenet_inference(scenario, weights: str | None = None, frames: int = 30,
                      size: tuple[int, int] = (1280, 720)) -> dict:
    """LaneNet's ms per frame (see `lanenet` in the module docstring). The frame is the bare
    render of the scenario's start: the figure is the detector's cost, whatever the picture."""
    import numpy as np

    from lanekeep.detectors.registry import check_weights, make_detector
    from lanekeep.sensing.cameras import CameraRig, RenderSettings
    from lanekeep.world.build import build

    out: dict = {"weights": weights, "frame": f"{size[0]}x{size[1]}", "frames": frames,
                 "ms_median": None, "ms_p90": None, "unavailable": None}
    try:
        out["weights"] = check_weights("lanenet", None, weights)
    except ValueError as err:  # WeightsError: "FILE: why"
        out["unavailable"] = " ".join(str(err).split())
        return out
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, *size)) as rig:
        frame = rig.render_rgb(world.data, "front")
        camera = rig.cameras["front"]
    detector = make_detector("lanenet", camera, weights=out["weights"])
    for _ in range(2):  # warm-up: the first calls allocate torch's buffers
        detector.detect(frame)
    ms = []
    for _ in range(frames):
        start = time.perf_counter()
        detector.detect(frame)
        ms.append(1000.0 * (time.perf_counter() - start))
    out["ms_median"] = float(np.median(ms))
    out["ms_p90"] = float(np.percentile(ms, 90))
    return out


def _bench_throughput(scenario_name: str, episodes: int, seconds: float,
                      weights: str | None = None) -> dict:
    """Throughput of `lanekeep bench`'s runner with 1 and 2 workers: the scenario with seeds
    0..episodes-1 (process start-up and world builds included, as in a real bench)."""
    from lanekeep.loop.runner import BenchJob, run_bench

    jobs = [BenchJob(scenario_name, seed) for seed in range(episodes)]
    out: dict = {"episodes": episodes, "seconds_each": seconds}
    for workers in (1, 2):
        reports, wall = run_bench(jobs, workers, seconds=seconds, weights=weights)
        simulated = sum(r.duration_s for r in reports)
        out[f"workers_{workers}"] = {"wall_s": wall, "episodes_per_s": episodes / wall,
                                     "simulated_s_per_s": simulated / wall}
    out["speedup"] = out["workers_2"]["episodes_per_s"] / out["workers_1"]["episodes_per_s"]
    return out


def measure(scenario_name: str = "clear_curve", seconds: float = 10.0, repeats: int = 3,
            bench_episodes: int = 4, bench_seconds: float = 10.0, weights: str | None = None,
            lanenet_frames: int = 30) -> dict:
    """Every figure of the JSON described in the module docstring (`weights`: the file of
    every learned detector, None = the shipped one)."""
    import lanekeep
    from lanekeep.core.workers import process_threads
    from lanekeep.detectors.registry import detector_weights
    from lanekeep.report.record import RerunRecorder
    from lanekeep.scenario.schema import load_scenario

    scenario = load_scenario(scenario_name)
    seconds = min(seconds, scenario.duration_s - scenario.control_period_s)
    cam = scenario.camera
    results: dict = {
        "lanekeep_version": lanekeep.__version__,
        "scenario": scenario.name,
        "seed": scenario.seed,
        "cpus": os.cpu_count(),
        "cameras": {"front": f"{cam.width}x{cam.height}", "rear": f"{cam.width}x{cam.height}"},
        "front_detectors": list(scenario.estimation.front_detectors),
        "reference_detector": scenario.estimation.reference_detector,
        "seconds": seconds,
        "detect_threads": 2 if process_threads() >= 2 else 1,
    }
    # Off and on alternate, and each keeps its fastest repeat: a background process on a
    # shared machine slows one run by 10-20%, which would swamp a 10% recording cost.
    off, on = [], []
    for _ in range(repeats):
        with detector_weights(weights):
            off.append(_timed_loop(scenario, seconds))
            with tempfile.TemporaryDirectory() as tmp:
                on.append(_timed_loop(scenario, seconds,
                                      RerunRecorder(Path(tmp) / "perf.rrd", scenario)))
    step_ms, stages = min(off, key=lambda r: r[0])
    step_ms_rec, stages_rec = min(on, key=lambda r: r[0])
    results["repeats"] = repeats
    results["stage_ms"] = stages
    results["step_ms"] = step_ms
    results["step_ms_recording"] = step_ms_rec
    results["record_ms"] = stages_rec.get("record", float("nan"))
    dt_ms = 1000.0 * scenario.control_period_s
    results["real_time_factor"] = dt_ms / step_ms
    results["real_time_factor_recording"] = dt_ms / step_ms_rec
    results["recording_cost_pct"] = 100.0 * (1.0 - step_ms / step_ms_rec)
    results["physics_steps_per_s"] = _physics_steps_per_s(scenario)
    results["bench"] = (_bench_throughput(scenario_name, bench_episodes, bench_seconds, weights)
                        if bench_episodes > 0 else None)
    results["lanenet"] = (lanenet_inference(scenario, weights, lanenet_frames)
                          if lanenet_frames > 0 else None)
    return results






def format_results(r: dict) -> str:
    """The figures as a short human-readable report."""
    lines = [f"lanekeep {r['lanekeep_version']} perf: {r['scenario']} (seed {r['seed']}), "
             f"cameras {r['cameras']['front']} + {r['cameras']['rear']}, detectors "
             f"{', '.join(r['front_detectors'])} + {r['reference_detector']} (rear), "
             f"{r['cpus']} CPUs, {r['seconds']:.1f} s simulated per loop, fastest of "
             f"{r['repeats']}"]
    overlap = (" (detectors on two threads: their wall time shared out)"
               if r.get("detect_threads", 1) > 1 else "")
    lines.append(f"per control step, recording off{overlap}:")
    width = max(len(k) for k in r["stage_ms"])
    for stage, ms in r["stage_ms"].items():
        lines.append(f"  {stage:<{width}}  {ms:7.1f} ms")
    lines.append(f"  {'total':<{width}}  {r['step_ms']:7.1f} ms")
    lines.append(f"real-time factor {r['real_time_factor']:.2f} (recording off), "
                 f"{r['real_time_factor_recording']:.2f} (recording on: "
                 f"{r['step_ms_recording']:.1f} ms a step, cost {r['recording_cost_pct']:.1f}%)")
    lines.append(f"physics alone: {r['physics_steps_per_s']:.0f} steps/s")
    b = r["bench"]
    if b is not None:
        for w in (1, 2):
            x = b[f"workers_{w}"]
            lines.append(f"bench, {w} worker{'s' if w > 1 else ''}: {b['episodes']} x "
                         f"{b['seconds_each']:.0f} s in {x['wall_s']:.1f} s = "
                         f"{x['simulated_s_per_s']:.2f} simulated s per s")
        lines.append(f"bench speed-up with 2 workers: {b['speedup']:.2f}x")
    lines += format_lanenet(r.get("lanenet"))
    return "\n".join(lines)


def format_lanenet(n: dict | None) -> list[str]:
    """The LaneNet timing's line (none when it was skipped)."""
    if n is None:
        return []
    if n["unavailable"]:
        return [f"LaneNet inference: unavailable ({n['unavailable']})"]
    return [f"LaneNet inference ({n['weights']}): {n['ms_median']:.1f} ms median, "
            f"{n['ms_p90']:.1f} ms p90 per {n['frame']} frame over {n['frames']} frames "
            f"(target <= 15 ms)"]

