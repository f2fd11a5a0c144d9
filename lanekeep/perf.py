"""`lanekeep perf`: speed benchmarks (kept out of unit tests, which check behaviour only).

Measures, on this machine: ms per 1280x720 RGB and segmentation frame (shadows off/on),
physics steps per second, each detector's ms per frame on one OpenCV thread, and the whole
closed-loop step with recording off and on.
"""

from __future__ import annotations

import dataclasses
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import mujoco
import numpy as np


def _time_ms(fn: Callable[[], object], repeats: int) -> float:
    fn()  # warm-up
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        samples.append((time.perf_counter() - start) * 1000.0)
    return statistics.median(samples)


def measure(scenario_name: str = "clear_curve", repeats: int = 10,
            loop_steps: int = 30) -> dict[str, float]:
    """All figures as a flat dict (ms, or steps/s)."""
    import cv2

    from detectors.registry import make_detector
    from lanekeep.cameras import CameraRig, RenderSettings
    from lanekeep.episode import Episode
    from lanekeep.render import place_on_road
    from lanekeep.scenario import load_scenario
    from lanekeep.world import build

    results: dict[str, float] = {}
    scenario = load_scenario(scenario_name)
    world = build(scenario)
    place_on_road(world, 120.0)
    for shadows in (False, True):
        tag = "shadows_on" if shadows else "shadows_off"
        with CameraRig(world.model, RenderSettings(1280, 720, shadows)) as rig:
            results[f"rgb_ms_{tag}"] = _time_ms(lambda r=rig: r.render_rgb(world.data, "front"),
                                                repeats)
            results[f"segmentation_ms_{tag}"] = _time_ms(
                lambda r=rig: r.render_segmentation(world.data, "front"), repeats)
            frame = rig.render_rgb(world.data, "front").copy()
            cameras = rig.cameras
    world.car.apply(0.0, 0.3)
    n = 2000
    start = time.perf_counter()
    for _ in range(n):
        mujoco.mj_step(world.model, world.data)
    results["physics_steps_per_s"] = n / (time.perf_counter() - start)

    from lanekeep.conditions import ImageEffects
    from lanekeep.scenario import Conditions

    rng = np.random.default_rng(0)
    for label in ("rain", "snow", "noise", "motion_blur"):
        cond = Conditions(**{label: 1.0})
        effect = ImageEffects(cond, 720, 1280, rng)
        results[f"effect_ms_{label}"] = _time_ms(lambda e=effect: e(frame, rng, 15.0), repeats)

    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        for name in dict.fromkeys(scenario.estimation.front_detectors):
            detector = make_detector(name, cameras["front"])
            results[f"detector_ms_{name}"] = _time_ms(lambda d=detector: d.detect(frame),
                                                      repeats * 3)
    finally:
        cv2.setNumThreads(threads)

    short = dataclasses.replace(scenario, duration_s=loop_steps * scenario.control_period_s)
    with Episode(short) as episode:
        episode.step()
        start = time.perf_counter()
        for _ in range(loop_steps - 1):
            episode.step()
        results["loop_step_ms_record_off"] = (time.perf_counter() - start) * 1000 / (
            loop_steps - 1)
    try:
        from lanekeep.record import RerunRecorder
    except ImportError:
        return results
    with tempfile.TemporaryDirectory() as tmp:
        recorder = RerunRecorder(Path(tmp) / "perf.rrd", short)
        with Episode(short, recorder=recorder) as episode:
            episode.step()
            start = time.perf_counter()
            for _ in range(loop_steps - 1):
                episode.step()
            results["loop_step_ms_record_on"] = (time.perf_counter() - start) * 1000 / (
                loop_steps - 1)
    results["recording_overhead_pct"] = 100.0 * (
        results["loop_step_ms_record_on"] / results["loop_step_ms_record_off"] - 1.0)
    return results


def register(sub) -> None:
    p = sub.add_parser("perf", help="speed benchmarks: render, physics, detectors, loop")
    p.add_argument("--scenario", default="clear_curve")
    p.add_argument("--repeats", type=int, default=10)
    p.add_argument("--loop-steps", type=int, default=30)
    p.set_defaults(func=_cmd_perf)


def _cmd_perf(args) -> int:
    results = measure(args.scenario, args.repeats, args.loop_steps)
    width = max(len(k) for k in results)
    for key, value in results.items():
        print(f"{key:<{width}}  {value:10.1f}")
    return 0
