"""Snapshots of a scenario: front/rear RGB and colourised segmentation PNGs at a road pose.

The RGB frames are what the car's cameras deliver: the render with the scenario's weather (fog,
rain, snow, motion blur, from the render's depth) and camera model (vignetting, exposure, noise,
tone, JPEG), drawn from the scenario's seed and name as an episode draws them, so the snapshot
at the start pose is the episode's first frame; `effects=False` gives the bare render (without
fog where the scenario's fog is done in image space).
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

from lanekeep.core.config_io import ConfigError
from lanekeep.scenario.schema import Scenario, ScenarioError
from lanekeep.scenario.streams import stream_entropy
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.image_effects import ImageEffects
from lanekeep.sensing.road_water import RoadWater
from lanekeep.world.build import World, build
from lanekeep.world.parts import WorldLayout
from lanekeep.world.street_lights import update_pools


def drive_time_s(scenario: Scenario, s_m: float) -> float:
    """When the scenario's drive reaches arc length s at its target speed (0 before its
    start): the time a snapshot there shows (what changes with time: the lens drops)."""
    ahead = s_m - scenario.start.s_m
    return max(ahead, 0.0) / scenario.target_speed_mps if scenario.target_speed_mps > 0 else 0.0


def place_on_road(world: World, s_m: float, offset_m: float = 0.0, heading_deg: float = 0.0,
                  speed_mps: float = 0.0) -> tuple[float, float, float]:
    """Put the car in the ego lane at arc length s with an offset and heading error, and the
    world's clock at the time its drive gets there (`drive_time_s`; the traffic stays where
    it is until the world moves it)."""
    road, lane = world.road, world.scenario.road.ego_lane
    x, y = road.position(s_m, road.lane_center_r(lane) + offset_m)
    yaw = float(road.heading_at(s_m)) + math.radians(heading_deg)
    world.car.place(float(x), float(y), yaw, speed_mps)
    world.data.time = drive_time_s(world.scenario, s_m)
    update_pools(world)  # the street lamps' pools of light near the car
    return float(x), float(y), yaw


def colourise_segmentation(world: World, geom_ids: np.ndarray) -> np.ndarray:
    """RGB image: markings coloured per boundary, other geoms in grey shades, sky black."""
    palette = np.array(
        [[255, 80, 80], [80, 255, 80], [80, 160, 255], [255, 220, 60], [220, 80, 255]], np.uint8
    )
    out = np.zeros(geom_ids.shape + (3,), np.uint8)
    known = geom_ids >= 0
    out[known] = (40 + (geom_ids[known] * 37) % 120)[:, None].astype(np.uint8)
    boundaries = np.append(world.marking_boundary, -1)[geom_ids]
    marked = boundaries >= 0
    out[marked] = palette[boundaries[marked] % len(palette)]
    return out


def make_effects(scenario: Scenario, world: World, rig: CameraRig,
                 rng: np.random.Generator) -> dict[str, ImageEffects]:
    """The image effects of each camera, as `Episode` makes them (same draws from `rng`),
    their first frame at the world's time."""
    airlight = 255.0 * world.model.vis.rgba.fog[:3]
    settings = rig.settings
    water = road_water(world) if scenario.conditions.wet > 0.0 else None
    return {cam: ImageEffects(scenario.conditions, settings.height, settings.width, rng,
                              scenario.camera, rig.cameras[cam], airlight,
                              scenario.control_period_s, float(world.data.time), water)
            for cam in rig.CAMERA_NAMES}


def road_water(world: World) -> RoadWater:
    """Where a wet world's water lies: its paved surface (the lanes and asphalt shoulders,
    along the road and its straight leads) and its puddles."""
    road, layout = world.road, world.layout
    paved = (road.boundary_r(0) - layout.shoulder_m,
             road.boundary_r(road.n_lanes) + layout.shoulder_m)
    puddles = tuple(world.conditions.puddle_polygons) if world.conditions is not None else ()
    return RoadWater(road, paved, (-layout.lead_m, road.length_m + layout.lead_m), puddles)


def camera_frame(rig: CameraRig, world: World, cam: str, effects: ImageEffects | None,
                 rng: np.random.Generator, speed_mps: float) -> np.ndarray:
    """What camera `cam` delivers now: the render (with its depth where the weather needs
    it) through its effects; `effects=None` gives the bare render."""
    if rig.settings.depth:
        rgb, depth = rig.render_rgb_depth(world.data, cam)
    else:
        rgb, depth = rig.render_rgb(world.data, cam), None
    return rgb if effects is None else effects(rgb, rng, speed_mps=speed_mps, depth_m=depth,
                                               pose=world.car.pose())


def paved_offsets(scenario: Scenario, layout: WorldLayout | None = None
                  ) -> tuple[float, float]:
    """The offsets (m, + = left) from the ego lane's centre that keep the car's centre on the
    paved surface: the lanes and the asphalt shoulders `build` lays (`layout`)."""
    road, shoulder_m = scenario.road, (layout or WorldLayout()).shoulder_m
    centre = (road.ego_lane + 0.5 - 0.5 * road.n_lanes) * road.lane_width_m  # Road.lane_center_r
    edge = 0.5 * road.n_lanes * road.lane_width_m + shoulder_m
    return -edge - centre, edge - centre


def render_snapshot(scenario: Scenario, out_dir: Path, at_s: float | None = None,
                    offset_m: float = 0.0, heading_deg: float = 0.0,
                    effects: bool = True) -> list[Path]:
    """Writes front.png, rear.png, front_seg.png, rear_seg.png; returns their paths.

    Raises:
      ConfigError: `at_s` is off the road (key "--at"), or `offset_m` puts the car's centre
        off the paved surface (key "--offset"); ScenarioError: the start is off the road.
    """
    s = scenario.start.s_m if at_s is None else at_s
    length = scenario.road.length_m
    if not 0.0 <= s <= length:  # before the build (~1 s) and before any file is written
        where = f"is outside the road (0..{length:g} m)"
        if at_s is None:
            raise ScenarioError(scenario.source or scenario.name, "start.s_m", f"{s:g} m {where}")
        raise ConfigError("", "--at", f"{s:g} m {where}")
    low, high = paved_offsets(scenario)
    if not low <= offset_m <= high:  # a picture of the verge is no view of the road
        raise ConfigError("", "--offset", f"{offset_m:g} m puts the car off the road: the "
                                          f"paved surface spans {low:+.2f}..{high:+.2f} m "
                                          f"from the ego lane's centre")
    world = build(scenario)
    place_on_road(world, s, offset_m, heading_deg)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    settings = RenderSettings.of(scenario)
    speed = scenario.start.speed_mps
    with CameraRig(world.model, settings) as rig:
        rng = np.random.default_rng(stream_entropy(scenario))  # as Episode: cameras in order
        camera_effects = make_effects(scenario, world, rig, rng)
        for cam in rig.CAMERA_NAMES:
            rgb = camera_frame(rig, world, cam, camera_effects[cam] if effects else None, rng,
                               speed)
            seg = colourise_segmentation(world, rig.render_segmentation(world.data, cam))
            for name, image in ((f"{cam}.png", rgb), (f"{cam}_seg.png", seg)):
                path = out_dir / name
                cv2.imwrite(str(path), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
                written.append(path)
    return written
