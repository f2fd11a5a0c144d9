"""Cast shadows darken the road as their darkness and the scenario's sun say, no more: shaded
asphalt (clear of the soft edge) keeps `shade_transmission(darkness, conditions)` of the
sunlit light (MuJoCo blends a translucent geom twice, and two casters' overlapping shadows
used to add up), and a speed bump in the shade is shaded too.

Pixel values are compared as rendered (8-bit sRGB-encoded, no gamma conversion): the overlay
is blended in the framebuffer, so a shadow keeping T of the light scales the pixel values by T.
"""

import dataclasses
import math

import cv2
import mujoco
import numpy as np
import pytest

from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.world.build import build
from lanekeep.world.shade import PENUMBRA_M, shade_transmission

W, H = 640, 360
AHEAD_M = np.arange(7.0, 22.0, 0.5)  # where patches are looked for, ahead of the car
PATCH_M = (1.2, 0.9)  # along the road, across it: between the lane lines of a 3.7 m lane


def _place(world, s_m: float) -> tuple[float, float, float]:
    road = world.road
    x, y = road.position(s_m, road.lane_center_r(0))
    yaw = float(road.heading_at(s_m))
    world.car.place(float(x), float(y), yaw)
    mujoco.mj_forward(world.model, world.data)
    return float(x), float(y), yaw


def _to_vehicle(points, pose):
    """World points (..., 3) to the vehicle frame of a car at pose (x, y, yaw)."""
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    p = np.asarray(points, float) - np.array([x, y, 0.0])
    return np.stack([c * p[..., 0] + s * p[..., 1], -s * p[..., 0] + c * p[..., 1], p[..., 2]], -1)


def _patch_points(road, s_m: float, r_m: float, n: int = 7) -> np.ndarray:
    """Road points (n*n, 2) of a patch of PATCH_M around (s, r)."""
    ds, dr = np.meshgrid(np.linspace(-0.5, 0.5, n) * PATCH_M[0],
                         np.linspace(-0.5, 0.5, n) * PATCH_M[1])
    return road.position(s_m + ds.ravel(), r_m + dr.ravel())


def _patch_state(world, s_m: float) -> int:
    """1 if the ego-lane patch at s is all in shade, 0 if all in sun, -1 if mixed; a patch
    within half the penumbra of a shadow's edge is mixed."""
    road, r, d = world.road, world.road.lane_center_r(0), 0.5 * PENUMBRA_M
    points = np.concatenate([_patch_points(road, s_m + ds, r + dr)
                             for ds, dr in ((0, 0), (d, 0), (-d, 0), (0, d), (0, -d))])
    shaded = world.conditions.shaded(points)
    return 1 if shaded.all() else 0 if not shaded.any() else -1


def _find_view(world, s_from: float, s_to: float) -> tuple[float, float, float]:
    """A car position with a shaded and a sunlit patch of its lane ahead in view, as near to
    each other as can be (the same lighting, distance and texture scale): (s_car, shade, sun)."""
    best, known = None, {}
    for s_car in np.arange(s_from, s_to, 1.0):
        states = {d: known.setdefault(round(s_car + d, 3), _patch_state(world, s_car + d))
                  if round(s_car + d, 3) not in known else known[round(s_car + d, 3)]
                  for d in AHEAD_M}
        shade = [d for d, st in states.items() if st == 1]
        sun = [d for d, st in states.items() if st == 0]
        for a in shade:
            for b in sun:
                key = (abs(a - b), a + b)
                if best is None or key < best[0]:
                    best = (key, s_car, a, b)
    assert best is not None, "no view with both a shaded and a sunlit patch"
    return best[1], best[1] + best[2], best[1] + best[3]


def _patch_mask(world, camera, pose, s_m: float) -> np.ndarray:
    """Pixels of the ego-lane patch at s (its quad projected into the image)."""
    road, r = world.road, world.road.lane_center_r(0)
    ds, dr = 0.5 * PATCH_M[0], 0.5 * PATCH_M[1]
    corners = road.position(s_m + np.array([-ds, ds, ds, -ds]), r + np.array([-dr, -dr, dr, dr]))
    uv, in_front = camera.project(_to_vehicle(np.c_[corners, np.zeros(4)], pose))
    assert in_front.all()
    mask = np.zeros((camera.height, camera.width), np.uint8)
    cv2.fillPoly(mask, [np.round(uv * 16).astype(np.int32)], 1, shift=4)
    return cv2.erode(mask, np.ones((3, 3), np.uint8)).astype(bool)  # clear of the patch edges


def _grey(rgb: np.ndarray) -> np.ndarray:
    return rgb.astype(float).mean(-1)


@pytest.mark.parametrize("name, s_from, s_to", [
    ("case1_building_shadows", 10.0, 100.0),
    ("case4_half_shade_straight", 170.0, 200.0),  # the end of the shade, half way along
])
def test_shaded_asphalt_keeps_the_shade_transmission_of_the_sunlit_light(name, s_from, s_to):
    """The same pixels of a shaded patch of the ego lane, rendered with and without the
    scenario's shadows: the shade passes shade_transmission(darkness) of the light.
    (Comparing a shaded patch with a sunlit one beside it measures the pavement too: wheel
    paths, cracks and patches differ by more than the 10% tolerance within a metre.)"""
    scenario = load_scenario(name)
    (zone,) = scenario.conditions.shadows
    s_car, s_shade, s_sun = _find_view(build(scenario), s_from, s_to)
    g, g0, camera, pose, world = _pixel_ratio(scenario, s_car)
    shade, sun = (_patch_mask(world, camera, pose, s) for s in (s_shade, s_sun))
    assert shade.sum() >= 30 and sun.sum() >= 30
    ratio = np.median(g[shade] / np.maximum(g0[shade], 1.0))
    expected = shade_transmission(zone.darkness, scenario.conditions)
    assert 0.2 <= expected <= 0.35  # skylight only, as real shade on a clear day
    assert ratio == pytest.approx(expected, rel=0.10), (
        f"shaded/unshaded {ratio:.3f} at s = {s_shade:.1f} m (car at {s_car:.1f} m), "
        f"darkness {zone.darkness}"
    )
    assert np.median(g[sun] / np.maximum(g0[sun], 1.0)) == pytest.approx(1.0, abs=0.02)


def _covering(polygons, xy: np.ndarray) -> np.ndarray:
    """How many of the convex CCW polygons cover each point (..., 2)."""
    count = np.zeros(xy.shape[:-1], int)
    for poly in polygons:
        inside = np.ones(xy.shape[:-1], bool)
        for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
            normal = np.array([b[1] - a[1], a[0] - b[0]])
            inside &= xy @ normal <= normal @ a
        count += inside
    return count


def _pixel_ratio(scenario, s_car: float):
    """Front renders of the scenario with and without its shadows at one pose, the camera,
    the pose and the world with shadows."""
    shaded = build(scenario)
    plain = build(dataclasses.replace(
        scenario, conditions=dataclasses.replace(scenario.conditions, shadows=())))
    renders = []
    for world in (shaded, plain):
        pose = _place(world, s_car)
        with CameraRig(world.model, RenderSettings.of(scenario, W, H)) as rig:
            renders.append(_grey(rig.render_rgb(world.data, "front")))
            camera = rig.cameras["front"]
    return renders[0], renders[1], camera, pose, shaded


def test_overlapping_shadows_of_two_casters_are_no_darker_than_one():
    scenario = load_scenario("case4_half_shade_straight")  # touching buildings: overlaps
    (zone,) = scenario.conditions.shadows
    g, g0, camera, pose, world = _pixel_ratio(scenario, 105.0)
    v, u = np.mgrid[0:H, 0:W]
    xy, valid = camera.pixels_to_ground(np.stack([u, v], -1).astype(float))
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    world_xy = np.stack([x + c * xy[..., 0] - s * xy[..., 1],
                         y + s * xy[..., 0] + c * xy[..., 1]], -1)
    count = _covering(world.conditions.shadow_polygons, np.nan_to_num(world_xy, nan=1e6))
    near = valid & (np.hypot(xy[..., 0], xy[..., 1]) < 40.0)
    kernel = np.ones((5, 5), np.uint8)  # keep 2 px clear of the shadow edges
    twice = cv2.erode((near & (count >= 2)).astype(np.uint8), kernel).astype(bool)
    once = cv2.erode((near & (count == 1)).astype(np.uint8), kernel).astype(bool)
    twice &= g0 > 40
    once &= g0 > 40
    assert twice.sum() > 50 and once.sum() > 500
    for mask in (twice, once):
        # lower quartile: the penumbra's steps lie inside the masks too (shade.py); a
        # doubled overlap would keep T^2 there
        assert np.percentile(g[mask] / g0[mask], 25) == pytest.approx(
            shade_transmission(zone.darkness, scenario.conditions), rel=0.10)


def test_a_speed_bump_in_the_shade_is_shaded():
    scenario = load_scenario("case3_mild_turn_shade_bumps")
    s_bump, zone = 190.0, scenario.conditions.shadows[1]  # under the trees' shade
    assert s_bump in scenario.conditions.speed_bumps_m
    g, g0, camera, pose, world = _pixel_ratio(scenario, s_bump - 8.0)
    road = world.road
    h = scenario.conditions.speed_bump_height_m
    shaded_r = [r for r in np.arange(road.boundary_r(0), road.boundary_r(road.n_lanes), 0.1)
                if world.conditions.shaded(_patch_points(road, s_bump, r, 5)).all()]
    assert len(shaded_r) >= 10
    # The bump's top, across its shaded part (the flat overlay lay under it and missed it).
    ds, rs = np.meshgrid(np.linspace(-0.08, 0.08, 5), np.linspace(min(shaded_r), max(shaded_r), 40))
    top = road.position(s_bump + ds.ravel(), rs.ravel())
    uv, _ = camera.project(_to_vehicle(np.c_[top, np.full(len(top), h)], pose))
    px = np.unique(np.round(uv).astype(int), axis=0)
    ratio = g[px[:, 1], px[:, 0]] / np.maximum(g0[px[:, 1], px[:, 0]], 1.0)
    # Under trees the shade is dappled: leaf shade keeps shade_transmission, sunflecks more.
    leaf = shade_transmission(zone.darkness, scenario.conditions)
    assert np.percentile(ratio, 25) == pytest.approx(leaf, rel=0.15)
    assert np.median(ratio) < 0.5 * (1.0 + leaf)


def test_a_shadow_too_faint_to_change_a_pixel_is_not_drawn_and_its_shade_stays_recorded():
    """Case 5's dusk rain keeps 0.99998 of the light under its props' shadows: no 8-bit pixel
    changes, so no overlay geom is added (they cost 60% of its render), while the shade
    zones the scoring and the paint read stay. Heavy rain's 0.988 (1.5 levels) is drawn."""
    from lanekeep.world.shade import changes_no_pixel

    assert changes_no_pixel(1.0 - 1e-5) and not changes_no_pixel(0.988)
    assert not changes_no_pixel(0.995) and changes_no_pixel(0.995, layers=3)
    scenario = load_scenario("case5_wet_rain_turn")
    assert changes_no_pixel(shade_transmission(scenario.roadside.shadow_darkness,
                                               scenario.conditions))
    world = build(scenario)
    names = [mujoco.mj_id2name(world.model, mujoco.mjtObj.mjOBJ_GEOM, i) or ""
             for i in range(world.model.ngeom)]
    assert not [n for n in names if n.startswith("props_shadow")]
    assert world.conditions.shadow_polygons  # the trees' and poles' shade, where the sun puts it
