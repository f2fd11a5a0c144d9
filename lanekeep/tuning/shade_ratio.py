"""Shade/sun luma ratio of the shipped shadow scenarios' front renders, measured exactly.

    MUJOCO_GL=egl python -m lanekeep.tuning.shade_ratio [--out DIR]

For each (scenario, arc length) pose in POSES: the bare front render (no camera chain, so the
ratio is the world's, not the exposure's), and the road pixels within 30 m (asphalt between
the outer lines, paint and 1 px around it left out) that lie at least MARGIN_M inside the
exact shadow polygons (`ConditionsInfo.shaded`, the middle of each penumbra) against those at
least MARGIN_M outside all of them. Prints the mean luma of each and their ratio. Real dashcam
frames show about 0.26 (the [realism] issue, #44); a sunlit-road tool reading, not a detector
input: it reads the world's own shadow polygons and the car's pose. tools/measure_shade.py
runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import cv2
import mujoco
import numpy as np

from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.tuning.realism import luma
from lanekeep.world.build import build

POSES = (("case1_building_shadows", 10.0), ("case1_building_shadows", 92.0),
         ("case3_mild_turn_shade_bumps", 60.0), ("case3_mild_turn_shade_bumps", 215.0),
         ("case4_half_shade_straight", 183.0), ("case4_half_shade_straight", 188.0))
MARGIN_M = 0.4  # clear of the penumbra (0.5 m wide, centred on the exact edge)
RANGE_M = 30.0
FIRST_ROW = 430  # below the paper camera's horizon (row 425)
STEP_PX = 3
MIN_PIXELS = 200


def shade_ratio(name: str, s_m: float, out: Path | None) -> str:
    scenario = load_scenario(name)
    world = build(scenario)
    place_on_road(world, s_m)
    mujoco.mj_forward(world.model, world.data)
    with CameraRig(world.model, RenderSettings.of(scenario, 1280, 720)) as rig:
        rgb = rig.render_rgb(world.data, "front")
        paint = world.marking_mask(rig.render_segmentation(world.data, "front"))
        camera = rig.cameras["front"]
    if out is not None:
        cv2.imwrite(str(out / f"{name}_{int(s_m)}.png"), rgb[..., ::-1])
    v, u = np.mgrid[FIRST_ROW:rgb.shape[0]:STEP_PX, 0:rgb.shape[1]:STEP_PX]
    ground, valid = camera.pixels_to_ground(np.stack([u, v], -1).astype(float))
    paint = cv2.dilate(paint.astype(np.uint8), np.ones((3, 3)))[FIRST_ROW::STEP_PX, ::STEP_PX]
    car = world.data.body("car")
    rot = car.xmat.reshape(3, 3)[:2, :2]
    world_xy = np.nan_to_num(ground, nan=1e6) @ rot.T + car.xpos[:2]
    near = valid & (np.hypot(ground[..., 0], ground[..., 1]) < RANGE_M)
    road = world.road
    r = np.full(near.shape, 1e6)
    r[near] = road.local_coordinates(world_xy[near])[1]
    on_road = (near & (r > road.boundary_r(0)) & (r < road.boundary_r(road.n_lanes))
               & ~paint.astype(bool))
    in_shade = np.ones(near.shape, bool)
    in_sun = np.ones(near.shape, bool)
    for angle in [None, *np.linspace(0.0, 2.0 * math.pi, 8, endpoint=False)]:
        shift = (0.0, 0.0) if angle is None else (MARGIN_M * math.cos(angle),
                                                   MARGIN_M * math.sin(angle))
        shaded = np.zeros(near.shape, bool)
        shaded[on_road] = world.conditions.shaded(world_xy[on_road] + shift)
        in_shade &= shaded
        in_sun &= ~shaded
    y = luma(rgb)[FIRST_ROW::STEP_PX, ::STEP_PX]
    shade, sun = y[on_road & in_shade], y[on_road & in_sun]
    if len(shade) < MIN_PIXELS or len(sun) < MIN_PIXELS:
        return f"{name} s={s_m:g}: too few pixels (shade {len(shade)}, sun {len(sun)})"
    return (f"{name} s={s_m:g}: shade {shade.mean():.1f} ({len(shade)} px), sun {sun.mean():.1f}"
            f" ({len(sun)} px), ratio {shade.mean() / sun.mean():.3f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="also write each render here (PNG)")
    args = parser.parse_args(argv)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
    for name, s_m in POSES:
        print(shade_ratio(name, s_m, args.out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
