"""Pools of light under the street lamps at night (lanekeep/world/street_lights.py): real spot
lights that follow the lamps nearest the car, deterministic, absent by day."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from lanekeep.mjcf import CAR_XML
from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build
from lanekeep.world.parts import ConditionsInfo, WorldLayout
from lanekeep.world.street_lights import (
    POOL_LIGHTS,
    add_street_lights,
    pool_light_name,
    pool_weights,
)

WIDTH, HEIGHT = 160, 90


def _night_world(sc):
    """The world with the car's own lights off: only the street lamps light the road."""
    world = build(sc)
    for name in ("headlight_left", "headlight_right", "tail_light"):
        world.model.light_active[world.model.light(name).id] = 0
    return world


@pytest.fixture(scope="module")
def night():
    """The shipped night scenario without traffic."""
    sc = load_scenario("night")
    sc = dataclasses.replace(sc, traffic=dataclasses.replace(sc.traffic, vehicles_per_km=0.0))
    return sc, _night_world(sc)


def _pool_xy(world) -> np.ndarray:
    ids = [world.model.light(pool_light_name(k)).id for k in range(POOL_LIGHTS)]
    return world.data.light_xpos[ids, :2].copy()


def _lamp_s(world) -> np.ndarray:
    """Arc length of each lamp (nearest centreline sample)."""
    s = np.linspace(0.0, world.road.length_m, 4000)
    xy = world.road.position(s)
    lamps = world.conditions.street_lamps_xy
    return s[np.argmin(np.linalg.norm(lamps[:, None] - xy[None], axis=2), axis=1)]


def test_pool_lights_follow_the_lamps_as_the_car_moves(night):
    _, world = night
    lamps = world.conditions.street_lamps_xy
    lamp_s = _lamp_s(world)
    for s_car in (30.0, 150.0, 320.0):
        place_on_road(world, s_car)
        pools = _pool_xy(world)
        hit = np.min(np.linalg.norm(pools[:, None] - lamps[None], axis=2), axis=1)
        assert np.all(hit < 1e-6), "every pool light sits under a lamp"
        pool_s = lamp_s[np.argmin(np.linalg.norm(pools[:, None] - lamps[None], axis=2), axis=1)]
        assert pool_s.min() < s_car < pool_s.max(), "pools ahead of and behind the car"


def test_pool_weights_fade_the_farthest_lamp_in():
    chosen, w = pool_weights(np.array([50.0, 5.0, 30.0, 12.0, 31.0]), n=3)
    assert list(chosen) == [1, 3, 2]
    assert w[0] == 1.0 and w[1] == 1.0 and 0.0 < w[2] < 0.2  # 30 m, next at 31 m


def test_road_under_a_lamp_is_brighter_than_between_lamps(night):
    sc, world = night
    lamp_s = _lamp_s(world)
    s_lamp = float(lamp_s[(lamp_s > 100.0) & (lamp_s < 300.0)][0])
    spacing = sc.roadside.pole_spacing_m
    with CameraRig(world.model, RenderSettings.of(sc, WIDTH, HEIGHT)) as rig:
        means = []
        for s_car in (s_lamp - 1.0, s_lamp - 1.0 - spacing / 2.0):  # front sees ~ 2-10 m on
            place_on_road(world, s_car)
            image = rig.render_rgb(world.data, "front").astype(float)
            means.append(image[int(0.8 * HEIGHT):, WIDTH // 4:3 * WIDTH // 4].mean(axis=(0, 1)))
        under, between = means
    assert under.sum() > 1.5 * between.sum(), (under, between)
    assert under[0] > under[2], "sodium light: warm"


def test_same_seed_gives_identical_night_frames(night):
    sc, reused = night
    frames = []
    for world in (reused, _night_world(sc)):  # a moved world reset, and a fresh one
        world.reset()
        for _ in range(3):
            world.step(0.0, 0.3, sc.control_period_s)
        with CameraRig(world.model, RenderSettings.of(sc, WIDTH, HEIGHT)) as rig:
            frames.append(rig.render_rgb(world.data, "rear"))
    assert np.array_equal(frames[0], frames[1])


def test_no_pool_lights_by_day(night):
    sc, _ = night
    for time_of_day in ("day", "dusk"):
        day = dataclasses.replace(
            sc, conditions=dataclasses.replace(sc.conditions, time_of_day=time_of_day))
        spec, info = mujoco.MjSpec.from_file(str(CAR_XML)), ConditionsInfo()
        lit = add_street_lights(spec, day, day.build_road(), WorldLayout(), info)
        assert lit == 0 and info.street_lamps_xy is None
        assert not any(light.name.startswith("street_pool") for light in spec.lights)
    assert night[1].conditions.street_lamps_xy is not None  # the same roadside lit at night
