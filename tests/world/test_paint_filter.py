"""Filtered lane paint (lanekeep/world/paint.py): a distant solid line stays continuous, the
segmentation masks still come from the exact geometry, and shadows still fall on the paint."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build
from lanekeep.world.groups import GROUP_MARKING_LABEL, GROUP_RGB_OVERLAY
from lanekeep.world.paint import FAR_DEPTH_M, SPREAD, profile_rgba
from lanekeep.world.shade import shade_transmission


def test_the_profile_is_paint_in_the_middle_and_clear_beside_it():
    alpha = profile_rgba()[0, :, 3].astype(float) / 255.0
    assert alpha.sum() / alpha.size == pytest.approx(1.0 / SPREAD, abs=0.01)  # its coverage
    assert alpha[len(alpha) // 2] == 1.0 and alpha[0] == alpha[-1] == 0.0


@pytest.fixture(scope="module")
def clear_straight():
    scenario = load_scenario("clear_straight")
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, 1280, 720)) as rig:
        yield scenario, world, rig


def _far_line_contrast(world, rig, boundary: int, s0: float) -> np.ndarray:
    """Summed contrast over the road of the boundary line, per image column it crosses
    30-60 m ahead of the car at arc length s0."""
    place_on_road(world, s0)
    mujoco.mj_forward(world.model, world.data)
    luma = rig.render_rgb(world.data, "front").astype(float).mean(axis=2)
    road, cam = world.road, rig.cameras["front"]
    pos = world.data.body("car").xpos[:2]
    rot = world.data.body("car").xmat.reshape(3, 3)[:2, :2]
    s = np.linspace(s0 + 30.0, s0 + 60.0, 600)
    ground = road.position(s, np.full(s.size, road.boundary_r(boundary)))
    pixels, _ = cam.project_ground((ground - pos) @ rot)
    columns: dict[int, float] = {}
    for u, v in pixels:
        if 0 <= u < luma.shape[1] and 8 <= v < luma.shape[0] - 16:
            columns.setdefault(int(round(u)), v)
    sums = []
    for u, v in sorted(columns.items()):
        row = int(round(v))
        road_level = np.median(luma[row + 8:row + 14, u])
        sums.append(np.clip(luma[row - 4:row + 5, u] - road_level, 0.0, None).sum())
    return np.asarray(sums)


def test_a_distant_solid_line_is_continuous(clear_straight):
    """Rendered as thin geometry the left edge line 30-60 m ahead changed by 0.80 of its mean
    from one column to the next (a dotted line); filtered, 0.21."""
    scenario, world, rig = clear_straight
    left_edge = len(scenario.road.markings) - 1
    changes = []
    for s0 in (20.0, 47.3, 91.1):
        sums = _far_line_contrast(world, rig, left_edge, s0)
        assert len(sums) > 20 and sums.mean() > 0.0
        changes.append(np.std(np.diff(sums)) / sums.mean())
    assert np.mean(changes) < 0.4, changes


def test_masks_come_from_the_thin_geometry_only(clear_straight):
    _, world, rig = clear_straight
    model = world.model
    labelled = np.flatnonzero(world.marking_boundary >= 0)
    ribbons = [g for g in range(model.ngeom) if model.geom(g).name.endswith("_rgb")]
    assert ribbons and all(model.geom_group[g] == GROUP_RGB_OVERLAY for g in ribbons)
    assert not set(ribbons) & set(labelled)  # a ribbon never labels a pixel
    assert any(model.geom_group[g] == GROUP_MARKING_LABEL for g in labelled)
    place_on_road(world, 20.0)
    mujoco.mj_forward(model, world.data)
    ids = rig.render_segmentation(world.data, "front")
    seen = set(np.unique(ids)) - {-1}
    assert seen & set(labelled) and not seen & set(ribbons)


def _front_luma_and_paint(scenario, s_m: float) -> tuple[np.ndarray, np.ndarray]:
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, 1280, 720)) as rig:
        place_on_road(world, s_m)
        mujoco.mj_forward(world.model, world.data)
        luma = rig.render_rgb(world.data, "front").astype(float).mean(axis=2)
        paint = world.marking_mask(rig.render_segmentation(world.data, "front"))
    return luma, paint


def test_a_shadow_zone_darkens_the_paint_it_falls_on():
    """case 4's paint in its shade against the same world without the shade: as dark as the
    asphalt there (paint in a cast shadow stays geometry: world._add_markings; a filtered
    ribbon would keep sqrt(T) of the light T the shade leaves the asphalt)."""
    scenario = load_scenario("case4_half_shade_straight")
    sunny = dataclasses.replace(scenario, conditions=dataclasses.replace(
        scenario.conditions, shadows=()))
    shaded, paint = _front_luma_and_paint(scenario, 5.0)
    lit, _ = _front_luma_and_paint(sunny, 5.0)
    darker = shaded[paint] < lit[paint] - 5.0
    assert paint.sum() > 500 and darker.mean() > 0.2  # the shade covers part of the paint
    # The lower quartile: the shade's soft edge (lanekeep/world/shade.py) darkens part of the
    # paint by less; a ribbon in the shade would keep sqrt(T) of its light everywhere.
    ratio = np.percentile(shaded[paint][darker] / lit[paint][darker], 25)
    darkness = scenario.conditions.shadows[0].darkness
    assert ratio == pytest.approx(shade_transmission(darkness, scenario.conditions),
                                  abs=0.05), ratio


def test_overlays_are_ordered_after_the_paint():
    model = build(load_scenario("case1_building_shadows")).model
    overlays = [g for g in range(model.ngeom) if model.geom_group[g] == GROUP_RGB_OVERLAY
                and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH]
    ribbons = [g for g in overlays if model.geom(g).name.endswith("_rgb")]
    others = [g for g in overlays if g not in ribbons]
    assert ribbons and others
    # MuJoCo orders translucent geoms by distance minus bounding radius.
    assert min(model.geom_rbound[others]) > FAR_DEPTH_M + max(model.geom_rbound[ribbons])
