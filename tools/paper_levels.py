"""Paint lightness as the car's camera delivers it, and the fixed white level of the paper's
binarisations chosen from it (detectors/config.py `PaperThresholds.white_level`, #58).

    MUJOCO_GL=egl .venv/bin/python tools/paper_levels.py                    # both parts
    MUJOCO_GL=egl .venv/bin/python tools/paper_levels.py --real ../shared/real/tusimple_dev

Part 1, the level: on a tuning scenario in sun (never a paper case), front frames at five
poses through the camera chain (auto-exposure settled over 30 frames), the HLS lightness of
paint pixels (the segmentation's markings, eroded by one pixel) and of the asphalt between the
road's outer edges 4-30 m ahead (paint and 3 px about it left out); the level that best
separates them (Youden's J: the share of paint at or above it minus the asphalt's).
Part 2, the paper cases: the paint's lightness percentiles in case 1 and case 2 and the share
at or above the authors' 200; the lightness of the rest of model #1's ground window (shoulders,
verges and rails too), the share of it at or above the level of part 1, and the level that
would separate that case's own paint from it (a diagnostic, never paper mode's level: the
cases are scored); with --real, the same for a TuSimple folder's labelled lanes
(brightest of 7 px about each labelled point below row 300; validation frames, read only).
Ground truth (segmentation, road geometry) is read here, on the measuring side only.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import cv2
import mujoco
import numpy as np

from lanekeep.scenario.schema import Scenario, load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import camera_frame, make_effects, place_on_road
from lanekeep.tuning.scenarios import tuning_dir
from lanekeep.world.build import build

TUNING = "tune_gentle_s_curve_r700_r500"
TUNING_POSES_M = (30.0, 90.0, 150.0, 250.0, 400.0)
CASE_POSES_M = {"case1_building_shadows": (10.0, 40.0, 92.0, 130.0),
                "case2_sharp_turn": (20.0, 60.0, 100.0)}
AUTHORS_LEVEL = 200


def _lightness(scenario: Scenario, poses_m: tuple[float, ...]
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(paint, asphalt, ground) HLS lightness of the front frames at `poses_m`, 4-30 m ahead;
    ground: every pixel of that window (|y| < 6 m, model #1's) that is not paint or next to
    it, the shoulders, verges and rails as well as the asphalt."""
    world = build(scenario)
    paint_l, asphalt_l, ground_l = [], [], []
    with CameraRig(world.model, RenderSettings.of(scenario, 1280, 720)) as rig:
        camera = rig.cameras["front"]
        v, u = np.mgrid[0:camera.height, 0:camera.width]
        ground, valid = camera.pixels_to_ground(np.stack([u, v], -1).astype(float))
        x = np.nan_to_num(ground[..., 0], nan=-1.0)
        y = np.nan_to_num(ground[..., 1], nan=99.0)
        near = valid & (x > 4.0) & (x < 30.0) & (np.abs(y) < 6.0)
        for s_m in poses_m:
            place_on_road(world, s_m)
            mujoco.mj_forward(world.model, world.data)
            rng = np.random.default_rng(0)
            effects = make_effects(scenario, world, rig, rng)
            for _ in range(30):  # let the auto-exposure settle on this view
                rgb = camera_frame(rig, world, "front", effects["front"], rng, 15.0)
            paint = world.marking_mask(rig.render_segmentation(world.data, "front"))
            light = cv2.cvtColor(rgb, cv2.COLOR_RGB2HLS)[..., 1]
            core = cv2.erode(paint.astype(np.uint8), np.ones((3, 3))).astype(bool) & near
            ring = cv2.dilate(paint.astype(np.uint8), np.ones((7, 7))).astype(bool)
            car = world.data.body("car")
            xy = np.stack([x, y], -1)[near] @ car.xmat.reshape(3, 3)[:2, :2].T + car.xpos[:2]
            r = world.road.local_coordinates(xy)[1]
            road = np.zeros_like(near)
            road[near] = ((r > world.road.boundary_r(0))
                          & (r < world.road.boundary_r(world.road.n_lanes)))
            paint_l.append(light[core])
            asphalt_l.append(light[road & ~ring])
            ground_l.append(light[near & ~ring])
    return np.concatenate(paint_l), np.concatenate(asphalt_l), np.concatenate(ground_l)


def best_level(paint: np.ndarray, asphalt: np.ndarray) -> int:
    """The lightness level with the largest share of paint minus share of asphalt at or above."""
    return max(range(1, 256), key=lambda t: np.mean(paint >= t) - np.mean(asphalt >= t))


def real_lightness(folder: Path) -> np.ndarray:
    """Brightest lightness of 7 px about each labelled lane point below row 300."""
    values = []
    for label in sorted((folder / "labels").glob("*.txt")):
        image = cv2.imread(str(folder / f"{label.stem}.jpg"))
        if image is None:
            continue
        light = cv2.cvtColor(image, cv2.COLOR_BGR2HLS)[..., 1]
        for line in label.read_text().splitlines():
            for x, y in np.array(line.split(), float).reshape(-1, 2).astype(int):
                if y >= 300:
                    values.append(light[y, max(0, x - 3):x + 4].max())
    return np.array(values)


def _describe(name: str, paint: np.ndarray) -> str:
    p10, p50, p90 = np.percentile(paint, [10, 50, 90])
    return (f"{name}: paint L p10/p50/p90 {p10:.0f} / {p50:.0f} / {p90:.0f}, share at or above "
            f"{AUTHORS_LEVEL}: {np.mean(paint >= AUTHORS_LEVEL):.3f} (n {len(paint)})")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--real", type=Path, help="a TuSimple folder with labels/ to compare")
    args = parser.parse_args(argv)
    if args.real is not None and not (args.real / "labels").is_dir():
        print(f"error: {args.real} has no labels/ folder", file=sys.stderr)
        return 2
    paint, asphalt, ground = _lightness(load_scenario(tuning_dir() / f"{TUNING}.toml"),
                                        TUNING_POSES_M)
    level = best_level(paint, asphalt)
    print(_describe(TUNING, paint) + f"; asphalt p50/p99 {np.percentile(asphalt, 50):.0f} / "
          f"{np.percentile(asphalt, 99):.0f}")
    print(f"white level {level}: paint at or above {np.mean(paint >= level):.3f}, asphalt "
          f"{np.mean(asphalt >= level):.4f}; the rest of model #1's window: L p90/p99 "
          f"{np.percentile(ground, 90):.0f} / {np.percentile(ground, 99):.0f}, at or above "
          f"{level}: {np.mean(ground >= level):.4f}; the level that would separate the paint "
          f"from it: {best_level(paint, ground)}")
    for name, poses in CASE_POSES_M.items():
        case_paint, _, ground = _lightness(load_scenario(name), poses)
        print(_describe(name, case_paint))
        own = best_level(case_paint, ground)  # a diagnostic: paper mode's level is `level`
        print(f"  the rest of model #1's window: L p90/p99 {np.percentile(ground, 90):.0f} / "
              f"{np.percentile(ground, 99):.0f}, at or above {level}: "
              f"{np.mean(ground >= level):.4f}; the level that would separate this case's "
              f"paint from it: {own} (paint {np.mean(case_paint >= own):.3f}, the rest "
              f"{np.mean(ground >= own):.4f})")
    if args.real is not None:
        print(_describe(f"{args.real} labelled lanes", real_lightness(args.real)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
