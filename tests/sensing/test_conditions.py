"""Conditions are visible and behave: each one changes the image statistics in the direction it
should (compared with the same scenario without it), image effects are deterministic for a seed,
shadows leave the marking masks alone, speed bumps are hit by the tyres, traffic hides markings."""

import dataclasses
import math

import cv2
import mujoco
import numpy as np
import pytest

from lanekeep.scenario.schema import (
    CameraConfig,
    Conditions,
    ScenarioError,
    load_scenario,
    parse_scenario,
)
from lanekeep.scenario.traffic import Traffic
from lanekeep.sensing import image_effects as effects
from lanekeep.sensing.camera_sensor import tone_curve
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build
from lanekeep.world.shade import PENUMBRA_M
from lanekeep.world.traffic import occluded_marking_share, update_dynamic

W, H = 320, 180


def _without(scenario, **changes):
    """The same scenario with some conditions changed (same seed, road and markings)."""
    return dataclasses.replace(
        scenario, conditions=dataclasses.replace(scenario.conditions, **changes)
    )


def _front(world, s_m, rig=None):
    place_on_road(world, s_m)
    own = rig is None
    rig = rig or CameraRig(world.model, RenderSettings(W, H))
    try:
        rgb = rig.render_rgb(world.data, "front")
        seg = rig.render_segmentation(world.data, "front")
        return rgb, seg, rig.cameras["front"]
    finally:
        if own:
            rig.close()


def _ground(camera):
    """Vehicle-frame ground point (H, W, 2) of every pixel, NaN above the horizon."""
    v, u = np.mgrid[0:camera.height, 0:camera.width]
    xy, valid = camera.pixels_to_ground(np.stack([u, v], -1).astype(float))
    xy[~valid] = np.nan
    return xy


def _patch(xy, x0, x1, y0, y1):
    with np.errstate(invalid="ignore"):
        return (xy[..., 0] >= x0) & (xy[..., 0] < x1) & (xy[..., 1] >= y0) & (xy[..., 1] < y1)


def _grey(rgb):
    return rgb.astype(float).mean(-1)


# -- world conditions ----------------------------------------------------------------------------
def test_building_shadows_darken_the_shaded_road_and_not_the_sunlit_road():
    scenario = load_scenario("case1_building_shadows")
    shaded_world, plain_world = build(scenario), build(_without(scenario, shadows=()))
    rig, rig0 = (CameraRig(w.model, RenderSettings(W, H)) for w in (shaded_world, plain_world))
    try:
        for s in (20.0, 40.0, 60.0, 80.0, 95.0):  # a pose with both shade and sun in view
            rgb, seg, camera = _front(shaded_world, s, rig)
            x, y, yaw = shaded_world.car.pose()
            c, sn = math.cos(yaw), math.sin(yaw)
            v = _ground(camera)
            world_xy = np.stack(
                [x + c * v[..., 0] - sn * v[..., 1], y + sn * v[..., 0] + c * v[..., 1]], -1
            )
            on_road = _patch(v, 3.0, 60.0, -1.8, 5.5)  # both lanes ahead (straight road)
            xy = np.nan_to_num(world_xy, nan=1e6)
            # Shade or sun all around a point half a penumbra away (the soft edge, whose
            # layers reach PENUMBRA_M / 2 either side of the exact polygon, is neither).
            around = [shaded_world.conditions.shaded(xy + PENUMBRA_M / 2 * np.array(
                [math.cos(a), math.sin(a)])) for a in np.linspace(0, 2 * np.pi, 8, False)]
            shaded = np.logical_and.reduce(around)
            sunlit = ~np.logical_or.reduce(around)
            kernel = np.ones((5, 5), np.uint8)  # keep 2 px clear of the shadow edges
            in_shadow = cv2.erode((on_road & shaded).astype(np.uint8), kernel).astype(bool)
            in_sun = cv2.erode((on_road & sunlit).astype(np.uint8), kernel).astype(bool)
            if in_shadow.sum() > 500 and in_sun.sum() > 500:
                break
        else:
            pytest.fail("no pose with both shade and sun in view")
        rgb0, seg0, _ = _front(plain_world, s, rig0)
    finally:
        rig.close()
        rig0.close()
    g, g0 = _grey(rgb), _grey(rgb0)
    assert g[in_shadow].mean() < 0.75 * g0[in_shadow].mean()
    assert g[in_sun].mean() == pytest.approx(g0[in_sun].mean(), rel=0.03)
    # The shadow overlays are hidden from the segmentation render: the same marking masks.
    mask, mask0 = shaded_world.marking_mask(seg), plain_world.marking_mask(seg0)
    assert mask.sum() > 200
    assert np.array_equal(mask, mask0)


def test_case1_shadows_cover_the_first_quarter_of_the_route_only():
    scenario = load_scenario("case1_building_shadows")
    world = build(scenario)
    road, lane = world.road, scenario.road.ego_lane
    route = scenario.start.s_m + np.array([0.0, 1.0]) * scenario.duration_s * 15.0
    s = np.linspace(*route, 2001)
    xy = road.position(s, road.lane_center_r(lane))
    shaded = world.conditions.shaded(xy)
    quarter = s < route[0] + 0.25 * (route[1] - route[0])
    assert 0.3 < shaded[quarter].mean() < 0.9  # hard stripes of shade and sun
    assert not shaded[~quarter & (s > route[0] + 0.3 * (route[1] - route[0]))].any()


def test_case4_first_half_of_the_route_in_shade_second_in_sun():
    scenario = load_scenario("case4_half_shade_straight")
    world = build(scenario)
    road = world.road
    route_end = scenario.start.s_m + scenario.duration_s * 15.0
    half = 0.5 * (scenario.start.s_m + route_end)
    for r in (road.boundary_r(0) + 0.3, road.boundary_r(road.n_lanes) - 0.3):
        first = road.position(np.linspace(scenario.start.s_m, half - 5.0, 200), r)
        second = road.position(np.linspace(half + 5.0, route_end, 200), r)
        assert world.conditions.shaded(first).all()
        assert not world.conditions.shaded(second).any()


def test_night_is_darker_and_the_headlit_road_brighter_than_the_unlit_road():
    scenario = load_scenario("night")
    # the paper camera this test's regions were set for (the file has the dashcam since #59)
    scenario = dataclasses.replace(scenario, camera=dataclasses.replace(scenario.camera,
                                                                        preset="paper"))
    night, day = build(scenario), build(_without(scenario, time_of_day="day"))
    rgb, _, camera = _front(night, 20.0)
    rgb_day, _, _ = _front(day, 20.0)
    assert _grey(rgb).mean() < 0.5 * _grey(rgb_day).mean()
    v = _ground(camera)
    lit = _patch(v, 6.0, 14.0, -1.2, 1.2)
    unlit = _patch(v, 3.0, 14.0, 7.0, 12.0)  # the gravel and grass left of the beam
    assert lit.sum() > 300 and unlit.sum() > 300
    g, g_day = _grey(rgb), _grey(rgb_day)
    assert g[lit].mean() > 3.0 * g[unlit].mean()
    assert g[lit].mean() > 35  # the lane ahead stays readable
    assert g[lit].mean() / g_day[lit].mean() > 2.0 * g[unlit].mean() / g_day[unlit].mean()


def test_fog_lowers_the_contrast_of_the_far_road():
    scenario = load_scenario("fog")
    foggy, clear = build(scenario), build(_without(scenario, fog=0.0))
    rgb, seg, camera = _front(foggy, 20.0)
    rgb0, _, _ = _front(clear, 20.0)
    v = _ground(camera)
    paint = foggy.marking_mask(seg)

    def contrast(img, x0, x1):  # paint minus asphalt, within a band ahead
        band = _patch(v, x0, x1, -2.5, 6.0)
        g = _grey(img)
        return g[band & paint].mean() - g[band & ~paint].mean()

    far = contrast(rgb, 15.0, 30.0) / contrast(rgb0, 15.0, 30.0)
    near = contrast(rgb, 2.0, 6.0) / contrast(rgb0, 2.0, 6.0)
    assert far < 0.6
    # Fog thins with distance: the near road keeps a far larger share of its contrast. (Not a
    # fixed share: part of the paint's brightness is the sun's, which fog takes away near and
    # far alike; with paint as bright as real paint, 60 DN above the asphalt, that part is a
    # larger share of the contrast: near 0.76 and far 0.36 before the [realism] paint, near
    # 0.61 and far 0.36 after.)
    assert near > 1.5 * far


def test_wet_asphalt_is_darker():
    scenario = load_scenario("heavy_rain")
    wet, dry = build(scenario), build(_without(scenario, wet=0.0))
    rgb, seg, camera = _front(wet, 30.0)
    rgb0, _, _ = _front(dry, 30.0)
    v = _ground(camera)
    road = _patch(v, 3.0, 12.0, -1.5, 1.5) & ~wet.marking_mask(seg)
    assert _grey(rgb)[road].mean() < 0.8 * _grey(rgb0)[road].mean()


def test_speed_bump_is_hit_by_the_tyres_and_bounces_the_car_without_warnings():
    scenario = load_scenario("case3_mild_turn_shade_bumps")
    world = build(scenario)
    model, data = world.model, world.data
    bump = model.geom(world.conditions.bump_geoms[1]).id  # at s = 70 m
    tyres = {model.geom(f"{w}_tyre").id for w in
             ("front_left", "front_right", "rear_left", "rear_right")}
    place_on_road(world, 55.0, speed_mps=15.0)
    car_id = model.body("car").id
    front_cam = model.camera("front").id
    hits, vz, pitch = set(), [], []
    for _ in range(int(2.0 / model.opt.timestep)):  # 30 m at 15 m/s: over the bump
        x, y, yaw = world.car.pose()
        s, r = world.road.local_coordinates(np.array([x, y]))
        lane_r = world.road.lane_center_r(scenario.road.ego_lane)
        heading_error = yaw - float(world.road.heading_at(s))
        world.car.apply(-0.1 * (r - lane_r) - 1.0 * heading_error, 0.25)
        mujoco.mj_step(model, data)
        for c in data.contact[: data.ncon]:
            if bump in (c.geom1, c.geom2):
                hits.add(c.geom2 if c.geom1 == bump else c.geom1)
        vz.append(data.cvel[car_id][5])
        forward = -data.cam_xmat[front_cam].reshape(3, 3)[:, 2]
        pitch.append(math.degrees(math.asin(forward[2])))
    counts = {mujoco.mjtWarning(i).name: w.number for i, w in enumerate(data.warning) if w.number}
    assert not counts, counts
    assert hits and hits <= tyres and len(hits) >= 2  # front and rear tyres, nothing else
    assert max(np.abs(vz)) > 0.15  # the body bounces (m/s vertical)
    assert max(pitch) - min(pitch) > 0.5  # the camera visibly pitches (degrees)
    assert world.car.rotation()[2, 2] > 0.99 and abs(data.body("car").xpos[2]) < 0.05
    assert world.car.speed_mps() > 12.0


def test_occlusion_scenario_hides_20_to_60_percent_of_the_markings_at_times():
    scenario = load_scenario("occlusion")
    world = build(scenario)
    shares = []
    with CameraRig(world.model, RenderSettings(W, H)) as rig:
        for t in np.arange(0.0, scenario.duration_s + 1e-9, 1.0):
            place_on_road(world, scenario.start.s_m + 15.0 * t)
            update_dynamic(world, float(t))
            shares.append(occluded_marking_share(world, rig))
    shares = np.array(shares)
    assert np.all((shares >= 0.0) & (shares <= 0.65)), shares
    assert np.any((shares >= 0.2) & (shares <= 0.6)), shares
    assert np.mean(shares > 0.05) > 0.4  # traffic hides paint much of the time


def test_vehicles_move_along_their_lanes_as_mocap_bodies():
    scenario = load_scenario("occlusion")
    world = build(scenario)
    spec = scenario.conditions.vehicles[1]
    track = world.conditions.vehicles[1]
    for t in (0.0, 3.0, 10.0):
        update_dynamic(world, t)
        expected = world.road.position(spec.s_m + spec.speed_mps * t,
                                       world.road.lane_center_r(spec.lane))
        np.testing.assert_allclose(world.data.body(track.name).xpos[:2], expected, atol=1e-9)
    world.reset()  # back to the start poses
    np.testing.assert_allclose(
        world.data.mocap_pos[track.mocap_id, :2],
        world.road.position(spec.s_m, world.road.lane_center_r(spec.lane)), atol=1e-9,
    )


def test_scenarios_without_traffic_report_no_occlusion():
    # clear_straight with its [traffic] table turned off: no vehicle, so nothing hides paint
    scenario = load_scenario("clear_straight")
    world = build(dataclasses.replace(scenario, traffic=Traffic()))
    assert not world.scenario.conditions.vehicles
    with CameraRig(world.model, RenderSettings(W, H)) as rig:
        place_on_road(world, 20.0)
        assert occluded_marking_share(world, rig) == 0.0


# -- image effects --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def clear_frame(straight_world):
    rgb, _, _ = _front(straight_world, 20.0)
    return rgb


def _hf_energy(rgb):
    """Laplacian energy of the bottom third (a flat road in the test frame)."""
    road = _grey(rgb[2 * rgb.shape[0] // 3:]).astype(np.float32)
    return float(np.mean(cv2.Laplacian(road, cv2.CV_32F) ** 2))


@pytest.mark.parametrize("condition", ["rain", "snow"])
def test_rain_and_snow_raise_high_frequency_energy(condition):
    flat = np.full((720, 1280, 3), 60, np.uint8)  # a smooth dark road: rain and snow show
    out = effects.apply(flat, Conditions(**{condition: 0.8}), np.random.default_rng(1),
                        speed_mps=15.0, camera=BARE_CAMERA)
    assert out.shape == flat.shape and out.dtype == np.uint8
    assert _hf_energy(flat) == 0.0 and _hf_energy(out) > 3.0  # streaks / flakes: texture


# The weather alone, through a camera that adds nothing (the auto-exposure would undo a
# whitening, as a real one does).
BARE_CAMERA = CameraConfig(read_noise_dn=0.0, auto_exposure=False, vignetting=0.0,
                           lens_blur_px=0.0, bloom=0.0, jpeg_quality=0)


def test_snow_whitens_the_image(clear_frame):
    out = effects.apply(clear_frame, Conditions(snow=0.8), np.random.default_rng(1),
                        camera=BARE_CAMERA)
    assert _grey(out).mean() > _grey(clear_frame).mean() + 15


def test_noise_raises_the_residual_against_a_denoised_image(clear_frame):
    def residual(img):
        return float(np.abs(img.astype(float) - cv2.medianBlur(img, 3)).mean())

    out = effects.apply(clear_frame, Conditions(noise=0.5), np.random.default_rng(1),
                        camera=BARE_CAMERA)
    assert residual(out) > 2.0 * residual(clear_frame)
    tone_only = effects.apply(clear_frame, Conditions(), np.random.default_rng(1),
                              camera=BARE_CAMERA)
    assert abs(_grey(out).mean() - _grey(tone_only).mean()) < 3.0  # zero-mean noise


def test_motion_blur_is_radial_about_the_focus_of_expansion():
    """Forward motion streams the image away from the focus of expansion (FOE): a horizontal
    line far below it is smeared vertically (its peak drops), one through it is not; a vertical
    line far beside it is smeared, one straight below it is not."""
    cond = Conditions(motion_blur=1.0)

    def blurred(img, speed):
        fx = effects.ImageEffects(cond, 720, 1280, np.random.default_rng(1), BARE_CAMERA)
        return _grey(fx(img, np.random.default_rng(1), speed)), fx.weather.foe

    _, (u_foe, v_foe) = blurred(np.zeros((720, 1280, 3), np.uint8), 0.0)
    u0, v0 = int(round(u_foe)), int(round(v_foe))
    lines = np.zeros((720, 1280, 3), np.uint8)  # lines 3 px wide (1-px detail is softened:
    lines[v0 - 1:v0 + 2] = lines[699:702] = 200  # the scaled exposures are made at half size)
    lines[:, u0 - 1:u0 + 2] = lines[:, 1249:1252] = 200  # through the FOE and beside it
    tone = _grey(effects.apply(lines, Conditions(), np.random.default_rng(1),
                               camera=BARE_CAMERA))
    out, _ = blurred(lines, 15.0)
    peak = tone.max()
    assert out[v0 - 2:v0 + 3, u0 + 20:u0 + 60].max() > 0.9 * peak  # through the FOE: sharp
    assert out[690:711, u0 + 20:u0 + 60].max(axis=0).max() < 0.8 * peak  # below: smeared
    assert out[v0 + 20:v0 + 60, u0 - 2:u0 + 3].max() > 0.9 * peak  # below the FOE: sharp
    assert out[v0 - 60:v0 - 20, 1235:1266].max(axis=1).max() < 0.8 * peak  # beside: smeared
    still, _ = blurred(lines, 0.0)
    assert np.array_equal(still, tone)  # no speed, no blur


def test_night_gain_brightens_and_adds_noise(clear_frame):
    dark = (clear_frame // 4).astype(np.uint8)
    out = effects.apply(dark, Conditions(time_of_day="night"), np.random.default_rng(1))
    assert _grey(out).mean() > 1.5 * _grey(dark).mean()


ALL_EFFECTS = Conditions(rain=0.7, snow=0.3, noise=0.4, motion_blur=0.5, time_of_day="dusk")


def test_effects_are_deterministic_for_a_seed(clear_frame):
    def run(seed):
        rng = np.random.default_rng(seed)
        fx = effects.ImageEffects(ALL_EFFECTS, H, W, rng)
        return [fx(clear_frame, rng, 15.0) for _ in range(3)]

    a, b, c = run(7), run(7), run(8)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not np.array_equal(a[0], c[0])
    assert not np.array_equal(a[0], a[1])  # frames differ within an episode


def test_no_conditions_and_a_bare_camera_give_the_tone_curve_only(clear_frame):
    out = effects.apply(clear_frame, Conditions(), np.random.default_rng(0), camera=BARE_CAMERA)
    tone = np.round(255.0 * tone_curve(np.arange(256) / 255.0)).astype(np.uint8)
    assert np.array_equal(out, cv2.LUT(clear_frame, tone)) and out is not clear_frame


def test_the_default_camera_changes_even_a_clear_frame(clear_frame):
    """Noise, vignetting and exposure are always on (lanekeep/sensing/camera_sensor.py)."""
    out = effects.apply(clear_frame, Conditions(), np.random.default_rng(0))
    assert not np.array_equal(out, clear_frame)
    assert abs(_grey(out).mean() - _grey(clear_frame).mean()) < 25


# -- schema ----------------------------------------------------------------------------------------
MINIMAL = """
name = "t"
description = "t"
[road]
[[road.segments]]
kind = "straight"
length_m = 200
"""


@pytest.mark.parametrize(
    "text, key",
    [
        ("[[conditions.shadows]]\ns_start_m = 0\ns_end_m = 50\nsdie = 'left'",
         "conditions.shadows[0].sdie"),
        ("[[conditions.shadows]]\ns_start_m = 0\ns_end_m = 50\nside = 'up'",
         "conditions.shadows[0].side"),
        ("[[conditions.shadows]]\ns_start_m = 60\ns_end_m = 50", "conditions.shadows[0].s_end_m"),
        ("[[conditions.vehicles]]\nlane = 0\nlength_m = 50", "conditions.vehicles[0].length_m"),
        ("[conditions]\nwet = true", "conditions.wet"),
        ("[conditions]\nspeed_bump_height_m = 0.5", "conditions.speed_bump_height_m"),
    ],
)
def test_bad_condition_keys_are_named(text, key):
    with pytest.raises(ScenarioError, match=key.replace("[", r"\[").replace("]", r"\]")):
        parse_scenario(MINIMAL + text)


def test_vehicle_in_a_missing_lane_and_shadows_away_from_the_road_raise_on_build():
    with pytest.raises(ValueError, match=r"vehicles\[0\].lane"):
        build(parse_scenario(MINIMAL + "[[conditions.vehicles]]\nlane = 5"))
    text = MINIMAL + ("[conditions]\nsun_azimuth_deg = -90\n"
                      "[[conditions.shadows]]\nside = 'left'\ns_start_m = 0\ns_end_m = 50")
    with pytest.raises(ValueError, match=r"shadows\[0\]"):
        build(parse_scenario(text))
