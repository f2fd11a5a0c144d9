"""The recorded marking masks hold only paint a camera can see: fog hides far paint by its
contrast (lanekeep/sensing/paint_visibility.py), clear air keeps it, near paint always stays."""

import numpy as np
import pytest

from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.paint_visibility import visible_paint
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.sensing.weather import Weather
from lanekeep.world.build import build
from lanekeep.world.lighting import fog_visibility_m

W, H = 320, 180


@pytest.fixture(scope="module")
def fog_view():
    """Paint, bare render, range and weather of the fog scenario's front camera at s = 30 m."""
    scenario = load_scenario("fog")
    world = build(scenario)
    place_on_road(world, 30.0)
    with CameraRig(world.model, RenderSettings(W, H, fog=False, depth=True)) as rig:
        paint = world.marking_mask(rig.render_segmentation(world.data, "front"))
        bare, depth = rig.render_rgb_depth(world.data, "front")
        weather = Weather(scenario.conditions, rig.cameras["front"],
                          255.0 * world.model.vis.rgba.fog[:3], np.random.default_rng(0))
    return scenario, paint, bare, weather.range_m(depth), weather


def test_the_mask_hides_paint_beyond_visibility_in_fog(fog_view):
    scenario, paint, bare, range_m, weather = fog_view
    visibility = fog_visibility_m(scenario.conditions.fog)
    air = float(weather.airlight.mean())
    foggy = visible_paint(paint, bare, range_m, weather.extinction_per_m, air)
    clear = visible_paint(paint, bare, range_m, 0.0, air)
    far = paint & (range_m > 1.15 * visibility)  # a 255 DN step at most: t >= 0.05 A / 255
    near = paint & (range_m < 0.2 * visibility)
    assert far.sum() >= 1 and near.sum() > 100
    assert not (foggy & ~paint).any()
    assert not (foggy & far).any()  # fog hides all paint beyond the visibility
    assert (clear & far).any()  # ... which clear air shows
    assert (foggy & near).sum() >= 0.99 * near.sum()  # and the paint close by stays


def test_visibility_distance_follows_the_fog_density(fog_view):
    _, paint, bare, range_m, weather = fog_view
    air = float(weather.airlight.mean())
    reach, count = [], []
    for fog in (0.2, 0.75, 1.0):
        extinction = 3.0 / fog_visibility_m(fog)
        mask = visible_paint(paint, bare, range_m, extinction, air)
        reach.append(float(range_m[mask].max()))
        count.append(int(mask.sum()))
    # Denser fog, shorter reach of the visible paint (and less of it).
    assert reach[0] >= reach[1] >= reach[2] and reach[0] > reach[2]
    assert count[0] >= count[1] >= count[2] and count[0] > count[2]


def test_paint_in_the_dark_is_not_visible(fog_view):
    """Light: the same scene 15 times darker has a paint step below the camera's noise.
    (40 times before the [realism] paint: the step was 100-150 DN then, 40-70 DN now.)"""
    _, paint, bare, range_m, _ = fog_view
    dark = (bare // 15).astype(np.uint8)
    assert visible_paint(paint, bare, range_m, 0.0, 0.0).sum() > 0.9 * paint.sum()
    assert visible_paint(paint, dark, range_m, 0.0, 0.0).sum() < 0.1 * paint.sum()
    # The exposure gain brings it back where the step is large enough.
    assert visible_paint(paint, dark, range_m, 0.0, 0.0, gain=4.0).sum() > 0.5 * paint.sum()


def test_episode_masks_use_the_visibility():
    from lanekeep.loop.episode import Episode

    scenario = load_scenario("fog")
    with Episode(scenario, render_size=(W, H)) as episode:
        masks = episode.simulator.marking_masks()
        seg = episode.simulator.rig.render_segmentation(episode.world.data, "front")
        paint = episode.world.marking_mask(seg)
    assert masks["front"].dtype == np.uint8
    assert not (masks["front"].astype(bool) & ~paint).any()
    assert 0 < masks["front"].sum() <= paint.sum()
