"""What anti-aliasing does to the detectors, same pose for same pose (open loop).

    MUJOCO_GL=egl python -m lanekeep.tuning.antialiasing --workers 2 --every 2

A closed-loop bench cannot answer this: a different frame steers the car onto another path,
and the paths' errors differ by more than the renders do. Here each scenario's episode drives
as configured, and at every `--every`-th step the same state is rendered again by one camera
rig per variant (MuJoCo multisampling `msaa4`, none, none plus a 3x3 Gaussian `blur`); each
variant's frames go through the scenario's image effects (the same random numbers for every
variant) and its own detector instances, and each detection is scored against the truth of
that pose. Seeds are the scenario's seed + `--seed-offset` (default 1000), so the bench's
scored episodes are not what this measures. Prints each detector's offset RMSE (cm) and valid
share per variant and scenario, and the render cost per variant. tools/measure_antialiasing.py
runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

VARIANTS = ("msaa4", "none", "blur")


def _variant_frame(variant: str, rgb: np.ndarray) -> np.ndarray:
    import cv2

    return cv2.GaussianBlur(rgb, (3, 3), 0) if variant == "blur" else rgb


def measure(name: str, seed_offset: int, every: int, seconds: float | None) -> dict:
    """{variant: {detector: (rmse_cm, valid_share)}, 'render_ms': {variant: ms}} of one run."""
    from lanekeep.detectors.registry import make_detector
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.scoring.truth import lane_truth
    from lanekeep.sensing.cameras import CameraRig, RenderSettings
    from lanekeep.sensing.snapshot import make_effects

    scenario = load_scenario(name)
    scenario = dataclasses.replace(scenario, seed=scenario.seed + seed_offset)
    est = scenario.estimation
    errors: dict[str, dict[str, list[float | None]]] = {v: {} for v in VARIANTS}
    render_s = dict.fromkeys(VARIANTS, 0.0)
    with Episode(scenario) as episode:
        world = episode.world
        rigs, detectors, effects = {}, {}, {}
        for variant in VARIANTS:
            world.model.vis.quality.offsamples = 4 if variant == "msaa4" else 0
            rig = CameraRig(world.model, RenderSettings.of(scenario, 1280, 720))
            rigs[variant] = rig
            # Each variant's own effects, made alike (lens drops persist between frames).
            effects[variant] = make_effects(scenario, world, rig,
                                            np.random.default_rng(scenario.seed))
            detectors[variant] = {
                **{d: make_detector(d, rig.cameras["front"]) for d in est.front_detectors},
                "reference": make_detector(est.reference_detector,
                                           rig.cameras[est.reference_camera]),
            }
        world.model.vis.quality.offsamples = scenario.camera.antialias_samples
        steps = episode.total_steps if seconds is None else int(round(seconds / episode.dt_s))
        try:
            for index in range(steps):
                if index % every == 0:
                    pose = world.car.pose()
                    speed = world.car.speed_mps()
                    for variant in VARIANTS:
                        rng = np.random.default_rng([scenario.seed, index])
                        frames = {}
                        for cam in rigs[variant].CAMERA_NAMES:
                            start = time.perf_counter()
                            rig = rigs[variant]
                            if rig.settings.depth:  # the weather needs the depth too
                                rgb, depth = rig.render_rgb_depth(world.data, cam)
                            else:
                                rgb, depth = rig.render_rgb(world.data, cam), None
                            rgb = _variant_frame(variant, rgb)
                            render_s[variant] += time.perf_counter() - start
                            frames[cam] = effects[variant][cam](rgb, rng, speed_mps=speed,
                                                                depth_m=depth)
                        for det_name, det in detectors[variant].items():
                            camera = "front" if det_name != "reference" else est.reference_camera
                            e = det.detect(frames[camera])
                            truth = lane_truth(world.road, *pose, scenario.road.ego_lane,
                                               lookahead_m=e.x_m).offset_m
                            errors[variant].setdefault(det_name, []).append(
                                (e.offset_m - truth) * 100.0 if e.valid else None)
                episode.step()
        finally:
            for rig in rigs.values():
                rig.close()
    out: dict = {"render_ms": {}}
    n_frames = max(1, len(next(iter(errors["none"].values()))) * 2)
    for variant in VARIANTS:
        out["render_ms"][variant] = 1000.0 * render_s[variant] / n_frames
        out[variant] = {}
        for det_name, errs in errors[variant].items():
            valid = np.array([e for e in errs if e is not None])
            rmse = float(np.sqrt(np.mean(valid**2))) if len(valid) else math.nan
            out[variant][det_name] = (rmse, len(valid) / max(len(errs), 1))
    return out


def main(argv: list[str] | None = None) -> int:
    from lanekeep.scenario.schema import shipped_scenarios

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenarios", nargs="*", help="default: every shipped scenario")
    parser.add_argument("--seed-offset", type=int, default=1000)
    parser.add_argument("--every", type=int, default=2, help="measure every N-th step")
    parser.add_argument("--seconds", type=float, default=None)
    parser.add_argument("--workers", type=int, default=1)
    args = parser.parse_args(argv)
    names = args.scenarios or shipped_scenarios()
    with ProcessPoolExecutor(args.workers) as pool:
        results = dict(zip(names, pool.map(measure, names, [args.seed_offset] * len(names),
                                           [args.every] * len(names),
                                           [args.seconds] * len(names)), strict=True))
    detectors = list(results[names[0]]["none"])
    header = f"{'scenario':<28}" + "".join(f"{d[:14] + ' ' + v:>22}" for d in detectors
                                            for v in VARIANTS)
    print("offset RMSE cm (valid share), same poses for every variant")
    print(header)
    sums = {(d, v): [] for d in detectors for v in VARIANTS}
    for name, r in results.items():
        row = f"{name:<28}"
        for d in detectors:
            for v in VARIANTS:
                rmse, share = r[v][d]
                sums[d, v].append(rmse)
                row += f"{rmse:>15.2f} ({share:4.2f})"
        print(row)
    row = f"{'mean':<28}"
    for d in detectors:
        for v in VARIANTS:
            row += f"{np.nanmean(sums[d, v]):>22.2f}"
    print(row)
    for v in VARIANTS:
        ms = np.mean([r["render_ms"][v] for r in results.values()])
        print(f"render + filter, {v}: {ms:.1f} ms per 1280x720 frame")
    return 0


if __name__ == "__main__":
    sys.exit(main())
