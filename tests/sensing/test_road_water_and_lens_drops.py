"""Issue #59's broken sensing details, fixed: the lens drops are those of the drive's time
(lanekeep/sensing/lens_drops.py), and the wet road mirrors only on the paved surface and in
the puddles, not on the grass (lanekeep/sensing/road_water.py)."""

import numpy as np

from lanekeep.scenario.schema import Conditions
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.image_effects import default_camera
from lanekeep.sensing.lens_drops import WOBBLE_PX
from lanekeep.sensing.road_water import RoadWater
from lanekeep.sensing.snapshot import place_on_road, road_water
from lanekeep.sensing.weather import Weather

AIR = (200.0, 200.0, 200.0)
H, W = 180, 320


def test_lens_drops_are_those_of_the_drive_time_and_move_no_other_draw():
    camera = default_camera(360, 640)
    rain = Conditions(rain=1.0)
    start = Weather(rain, camera, AIR, np.random.default_rng(5))
    mid = Weather(rain, camera, AIR, np.random.default_rng(5), 0.1, 12.5)
    a, b = start.drops[:, :2], mid.drops[:, :2]
    gap = np.hypot(*(b[:, None] - a[None]).transpose(2, 0, 1)).min(1)
    assert len(a) == 14 and (gap > 3.0).all()  # before: the same 14 drops at the same pixels
    frame, far = np.zeros((360, 640, 3), np.uint8), np.full((90, 160), 500.0, np.float32)
    for _ in range(125):  # 12.5 s of frames reach mid-drive's drops (up to their shiver)
        start(frame, far, np.random.default_rng(0))
    assert start.time_s == 12.5 and np.abs(start.drops - start.lens.at(12.4)).max() < 3.0
    stepped = start.lens.at(12.5)
    assert stepped.shape == mid.drops.shape
    assert np.abs(stepped - mid.lens.at(12.5)).max() < 1e-9
    # The episode's generator gives the next draw it gave before the drops had a clock.
    rng, old = np.random.default_rng(5), np.random.default_rng(5)
    Weather(rain, camera, AIR, rng)
    old.uniform(8.0, 30.0, 14), old.uniform(0, 640, 14), old.uniform(0, 360, 14)
    assert rng.random() == old.random()
    assert WOBBLE_PX * start.scale < 3.0


def test_the_wet_road_mirrors_on_the_pavement_and_puddles_not_on_the_grass(straight_world):
    place_on_road(straight_world, 20.0)
    pose = straight_world.car.pose()
    with CameraRig(straight_world.model, RenderSettings(W, H)) as rig:
        camera = rig.cameras["front"]
    water = road_water(straight_world)
    x, y, yaw = pose
    ahead = np.array([np.cos(yaw), np.sin(yaw)])
    left = np.array([-np.sin(yaw), np.cos(yaw)])
    spot = np.array([x, y]) + 9.0 * ahead  # a puddle 9 m ahead, in the lane
    ang = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    puddle = spot + 1.5 * np.cos(ang)[:, None] * ahead + 0.6 * np.sin(ang)[:, None] * left
    wet = Weather(Conditions(wet=1.0), camera, AIR, np.random.default_rng(0),
                  water=RoadWater(water.road, water.paved_r, water.s_range, (puddle,)))
    frame = np.zeros((H, W, 3), np.uint8)
    frame[:wet.horizon] = 220  # a bright sky
    frame[wet.horizon:] = 30  # dark ground
    depth = np.where(np.isfinite(wet.ground_z), wet.ground_z, 500.0).astype(np.float32)
    out = wet.wet_reflection(frame, depth, pose).astype(float) - frame
    uv = lambda forward, side: np.round(camera.project_ground(  # noqa: E731
        np.array([forward, side]))[0]).astype(int)
    road_u, road_v = uv(40.0, 0.0)
    grass_u, grass_v = uv(40.0, -12.0)
    assert out[road_v, road_u].mean() > 20.0  # the asphalt mirrors the sky near the horizon
    assert out[grass_v, grass_u].max() == 0.0  # the grass beside it does not (before: +40)
    pud_u, pud_v = uv(9.0, 0.0)
    lane_u, lane_v = uv(9.0, 1.2)
    assert out[pud_v, pud_u].mean() > out[lane_v, lane_u].mean() + 10.0  # a puddle: all water
    assert np.array_equal(wet.wet_reflection(frame, depth), wet.wet_reflection(frame, depth))
