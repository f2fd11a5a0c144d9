"""Issue #59's five broken details, measured on rendered frames (one command, reproducible).

    MUJOCO_GL=egl .venv/bin/python tools/broken_details.py [--out DIR] [--only NAME ...]

Each detail renders the frames it needs as the car's cameras deliver them (the scenario's
world, seed and image effects: lanekeep/sensing/snapshot.py, as `lanekeep render` and the
contact sheet make them) and prints its statistics:

  tail_pool    night and case5_wet_rain_turn, rear camera at the start: the share of the frame
               (and of its bottom third) that is red-dominant (R >= 1.5 max(G, B) and at least
               20 DN above it), and the red excess R - max(G, B) of the near road behind the
               car (0.5-3.5 m behind the camera, +-1 m) against the headlit road ahead (10-25 m,
               +-1 m, luma), both in the delivered frames.
  spindle      heavy_rain, rear camera at the start: what the puddles change (the frame against
               the same frame with the puddles taken out): the share of the frame they change
               by more than 10 DN of luma, and the height of the largest such patch (a share of
               the frame's rows).
  lens_drops   heavy_rain, front and rear camera at the start and at mid-drive (the contact
               sheet's two poses): how many drops of the mid-drive frame sit within 3 px of a
               drop of the start frame.
  reflection   case5_wet_rain_turn, front camera at the start and mid-drive: the wet-road
               reflection's change (the weather with `wet` against the same without) on grass
               and gravel pixels (segmentation) and on paved ones: the share changed by more
               than 6 DN of luma.
  snow_props   snow, front camera at the start and mid-drive: tree crowns (their mean HSV
               saturation and share of snow-white pixels) and the guard rail with its posts
               (share of snow-white pixels); snow-white = saturation below 0.1 and luma at
               least the snowy verge's median in the same frame.

`--out DIR` writes the frames and crops looked at (PNG). The numbers hold for this checkout;
run the same file with PYTHONPATH pointing at another checkout to measure that one.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import sys
from collections.abc import Callable
from pathlib import Path

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import cv2
import mujoco
import numpy as np

from lanekeep.scenario.schema import Scenario, load_scenario
from lanekeep.scenario.streams import stream_entropy
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import camera_frame, make_effects, place_on_road
from lanekeep.world.build import World, build
from lanekeep.world.props import prop_kind

Frames = dict[str, np.ndarray]


def luma(rgb: np.ndarray) -> np.ndarray:
    return rgb.astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)


def mid_drive_s(scenario: Scenario) -> float:
    """The contact sheet's mid-drive pose (lanekeep/tuning/contact_sheet.py)."""
    s = scenario.start.s_m + 0.5 * scenario.duration_s * scenario.target_speed_mps
    return float(min(max(s, 0.0), scenario.road.length_m))


@dataclasses.dataclass
class Shot:
    """Delivered frames of both cameras at one pose, with what made them."""

    frames: Frames
    effects: dict
    seg: Frames


def shoot(world: World, rig: CameraRig, s_m: float, segment: bool = False,
          before: Callable[[dict], None] | None = None) -> Shot:
    """Both cameras at arc length s_m, each effects stream fresh from the scenario's seed (as
    `render_snapshot` and the contact sheet do); `before(effects)` may change them first."""
    scenario = world.scenario
    place_on_road(world, s_m)
    rng = np.random.default_rng(stream_entropy(scenario))
    effects = make_effects(scenario, world, rig, rng)
    if before is not None:
        before(effects)
    frames, seg = {}, {}
    for cam in rig.CAMERA_NAMES:
        frames[cam] = camera_frame(rig, world, cam, effects[cam], rng, scenario.start.speed_mps)
        if segment:
            seg[cam] = rig.render_segmentation(world.data, cam)
    return Shot(frames, effects, seg)


def ground_patch(camera, x_m: tuple[float, float], y_m: tuple[float, float]) -> np.ndarray:
    """Boolean mask of the pixels that see the ground rectangle x_m x y_m (vehicle frame)."""
    h, w = camera.height, camera.width
    v, u = np.mgrid[0:h, 0:w]
    xy, valid = camera.pixels_to_ground(np.stack([u, v], -1).astype(float))
    return (valid & (xy[..., 0] >= x_m[0]) & (xy[..., 0] <= x_m[1])
            & (xy[..., 1] >= y_m[0]) & (xy[..., 1] <= y_m[1]))


def geom_mask(world: World, ids: np.ndarray, test: Callable[[str], bool]) -> np.ndarray:
    names = np.array([mujoco.mj_id2name(world.model, mujoco.mjtObj.mjOBJ_GEOM, i) or ""
                      for i in range(world.model.ngeom)] + [""])
    keep = np.array([test(str(n)) for n in names])
    return keep[ids]


def save(out: Path | None, name: str, image: np.ndarray) -> None:
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(out / f"{name}.png"), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))


# -- the details --------------------------------------------------------------------------------
def tail_pool(out: Path | None) -> None:
    for name in ("night", "case5_wet_rain_turn"):
        scenario = load_scenario(name)
        world = build(scenario)
        with CameraRig(world.model, RenderSettings.of(scenario)) as rig:
            shot = shoot(world, rig, scenario.start.s_m)
            rear, front = shot.frames["rear"].astype(np.int16), shot.frames["front"]
            others = np.maximum(rear[..., 1], rear[..., 2])
            red = (rear[..., 0] >= 1.5 * others) & (rear[..., 0] - others >= 20)
            third = red[2 * red.shape[0] // 3:]
            near = ground_patch(rig.cameras["rear"], (-5.5, -2.5), (-1.0, 1.0))
            lit = ground_patch(rig.cameras["front"], (10.0, 25.0), (-1.0, 1.0))
            excess = float((rear[..., 0] - others)[near].mean())
            ratio = excess / float(luma(front)[lit].mean())
            print(f"tail_pool  {name:22s} red-dominant share of the rear frame "
                  f"{red.mean():6.1%} (bottom third {third.mean():6.1%}); near road behind: red "
                  f"excess {excess:5.1f} DN, {ratio:5.1%} of the headlit road's luma")
            save(out, f"tail_{name}_rear", shot.frames["rear"])
            save(out, f"tail_{name}_front", front)


def _hide_puddles(world: World) -> Callable[[dict], None]:
    gid = mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_GEOM, "cond_puddles")
    world.model.geom_matid[gid] = -1
    world.model.geom_rgba[gid] = 0.0

    def clear(effects: dict) -> None:  # the image-space water of the puddles, where there is one
        for fx in effects.values():
            water = getattr(fx.weather, "water", None)
            if water is not None:
                fx.weather.water = dataclasses.replace(water, puddles=())

    return clear


def spindle(out: Path | None) -> None:
    scenario = load_scenario("heavy_rain")
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario)) as rig:
        shot = shoot(world, rig, scenario.start.s_m)
        matid = world.model.geom_matid.copy()
        rgba = world.model.geom_rgba.copy()
        bare = shoot(world, rig, scenario.start.s_m, before=_hide_puddles(world))
        world.model.geom_matid[:], world.model.geom_rgba[:] = matid, rgba
    for cam in ("rear", "front"):
        diff = np.abs(luma(shot.frames[cam]) - luma(bare.frames[cam])) > 10.0
        n, labels, stats, _ = cv2.connectedComponentsWithStats(diff.astype(np.uint8), 8)
        tallest = int(stats[1:, cv2.CC_STAT_HEIGHT].max()) if n > 1 else 0
        biggest = int(stats[1:, cv2.CC_STAT_AREA].max()) if n > 1 else 0
        h = diff.shape[0]
        print(f"spindle    heavy_rain {cam:5s} puddles change {diff.mean():6.2%} of the frame by "
              f"> 10 DN; largest patch {biggest / diff.size:6.2%} of the frame, "
              f"{tallest / h:5.1%} of its rows high")
        save(out, f"spindle_{cam}", shot.frames[cam])
        save(out, f"spindle_{cam}_without", bare.frames[cam])


def lens_drops(out: Path | None) -> None:
    scenario = load_scenario("heavy_rain")
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario)) as rig:
        start = shoot(world, rig, scenario.start.s_m)
        mid = shoot(world, rig, mid_drive_s(scenario))
    for cam in rig.CAMERA_NAMES:
        a = start.effects[cam].weather.drops[:, :2]
        b = mid.effects[cam].weather.drops[:, :2]
        d = np.hypot(*(b[:, None, :] - a[None, :, :]).transpose(2, 0, 1)) if len(a) else None
        same = int((d.min(1) <= 3.0).sum()) if d is not None and len(b) else 0
        print(f"lens_drops heavy_rain {cam:5s} drops at mid-drive within 3 px of a start drop: "
              f"{same} of {len(b)} (start: {len(a)})")
        save(out, f"drops_{cam}_start", start.frames[cam])
        save(out, f"drops_{cam}_mid", mid.frames[cam])


def reflection(out: Path | None) -> None:
    scenario = load_scenario("case5_wet_rain_turn")
    dry = dataclasses.replace(scenario, conditions=dataclasses.replace(scenario.conditions,
                                                                       wet=0.0))
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario)) as rig:
        for pose, s in (("start", scenario.start.s_m), ("mid", mid_drive_s(scenario))):
            place_on_road(world, s)
            rgb, depth = rig.render_rgb_depth(world.data, "front")
            ids = rig.render_segmentation(world.data, "front")
            out_frames = []
            for sc in (scenario, dry):
                rng = np.random.default_rng(stream_entropy(scenario))
                weather = make_effects(sc, world, rig, rng)["front"].weather
                where = {"pose": world.car.pose()} if "pose" in inspect.signature(
                    weather.__call__).parameters else {}  # a checkout before the fix has none
                out_frames.append(weather(rgb, depth, rng, scenario.start.speed_mps, **where))
            change = np.abs(luma(out_frames[0]) - luma(out_frames[1])) > 6.0
            rough = geom_mask(world, ids, lambda n: n.startswith(("ground", "shoulder_")))
            paved = geom_mask(world, ids, lambda n: n.startswith("road_"))
            print(f"reflection case5 front {pose:5s} changed by > 6 DN: grass and gravel "
                  f"{change[rough].mean():6.2%} of {rough.sum()} px, paved "
                  f"{change[paved].mean():6.2%} of {paved.sum()} px")
            save(out, f"reflection_{pose}", out_frames[0])
            save(out, f"reflection_{pose}_dry", out_frames[1])


def snow_props(out: Path | None) -> None:
    scenario = load_scenario("snow")
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario)) as rig:
        for pose, s in (("start", scenario.start.s_m), ("mid", mid_drive_s(scenario))):
            shot = shoot(world, rig, s, segment=True)
            rgb, ids = shot.frames["front"], shot.seg["front"]
            hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV_FULL).astype(np.float32)
            sat, y = hsv[..., 1] / 255.0, luma(rgb)
            verge = geom_mask(world, ids, lambda n: n.startswith("ground"))
            white = (sat < 0.1) & (y >= float(np.median(y[verge])))
            crowns = geom_mask(world, ids, lambda n: n.startswith(("props_foliage",
                                                                    "props_conifer")))
            rails = geom_mask(world, ids, lambda n: prop_kind(n) in ("props_steel", "props_pole",
                                                                     "props_snow"))
            print(f"snow_props snow front {pose:5s} crowns ({crowns.sum()} px): saturation "
                  f"{sat[crowns].mean():.3f}, snow-white {white[crowns].mean():6.1%}; rail and "
                  f"posts ({rails.sum()} px): snow-white {white[rails].mean():6.1%}")
            save(out, f"snow_{pose}", rgb)


DETAILS = {"tail_pool": tail_pool, "spindle": spindle, "lens_drops": lens_drops,
           "reflection": reflection, "snow_props": snow_props}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, help="write the frames looked at here (PNG)")
    parser.add_argument("--only", nargs="+", choices=list(DETAILS), help="these details only")
    args = parser.parse_args(argv)
    for name in args.only or DETAILS:
        DETAILS[name](args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
