"""Weather in depth (lanekeep/sensing/weather.py): Koschmieder fog on every pixel's range, rain
streaks hidden behind near objects and slanted by the car's motion (away from the focus of
expansion on the front camera, towards it on the rear), hardly visible against the sky; the
depth read from the colour render agrees with the camera geometry."""

import mujoco
import numpy as np
import pytest

from lanekeep.mjcf import SCENE_XML
from lanekeep.scenario.schema import Conditions, load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.lens_drops import LensDrops
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.sensing.weather import DEPTH_STEP_PX, Weather
from lanekeep.world.camera_mount import camera_from_model
from lanekeep.world.lighting import fog_visibility_m

H, W = 180, 320
AIR = (180.0, 182.0, 185.0)


@pytest.fixture(scope="module")
def cameras(straight_world):
    with CameraRig(straight_world.model, RenderSettings(W, H)) as rig:
        return dict(rig.cameras)


def _depth(value):
    return np.full((H // DEPTH_STEP_PX, W // DEPTH_STEP_PX), value, np.float32)


def test_render_depth_matches_the_ground_under_the_camera(straight_world):
    place_on_road(straight_world, 20.0)
    with CameraRig(straight_world.model, RenderSettings(W, H, show_hood=False)) as rig:
        _, depth = rig.render_rgb_depth(straight_world.data, "front")
        camera = rig.cameras["front"]
    v, u = np.mgrid[DEPTH_STEP_PX // 2:H:DEPTH_STEP_PX, DEPTH_STEP_PX // 2:W:DEPTH_STEP_PX]
    xy, valid = camera.pixels_to_ground(np.stack([u, v], -1).astype(float))
    ground = np.concatenate([xy, np.zeros(xy.shape[:-1] + (1,))], -1)
    z_true = camera.to_opencv_frame(ground)[..., 2]
    near = valid & (z_true < 30.0)
    assert near.sum() > 200
    # The road and verges (not the few pixels of things standing on them) agree within 3%.
    assert np.mean(np.abs(depth[near] / z_true[near] - 1.0) < 0.03) > 0.95
    assert np.median(depth[~valid]) > 100.0  # the sky: far


def test_fog_follows_koschmieder(cameras):
    fog = 0.75
    weather = Weather(Conditions(fog=fog), cameras["front"], AIR, np.random.default_rng(0))
    visibility = fog_visibility_m(fog)
    frame = np.zeros((H, W, 3), np.uint8)  # a black object everywhere
    centre = (slice(H // 2 - 4, H // 2 + 4), slice(W // 2 - 4, W // 2 + 4))
    for distance, expected in ((1.0, np.exp(-3 / visibility)), (visibility, np.exp(-3.0))):
        out = weather(frame, _depth(distance), np.random.default_rng(0))
        # A black object at range d shows the airlight times 1 - t, t = exp(-3 d / V).
        seen = out[centre].astype(float).mean(axis=(0, 1))
        np.testing.assert_allclose(seen, np.array(AIR) * (1 - expected), atol=1.5)


def test_rain_is_hidden_behind_near_objects_and_faint_on_the_sky(cameras):
    weather = Weather(Conditions(rain=1.0), cameras["front"], AIR, np.random.default_rng(0))
    weather.lens = LensDrops(np.zeros((0, 3)), [], W, H)  # no lens drops: the streaks alone
    frame = np.zeros((H, W, 3), np.uint8)
    frame[: H // 2] = np.round(AIR).astype(np.uint8)  # sky of the airlight's colour above
    frame[H // 2:] = 50  # dark road below
    depth = _depth(200.0)
    depth[:, : depth.shape[1] // 2] = 0.5  # a wall 0.5 m away on the left: before every layer
    out = weather(frame, depth, np.random.default_rng(1), speed_mps=15.0)
    diff = np.abs(out.astype(int) - frame.astype(int)).sum(-1)
    road_right = diff[H // 2 + 5:, W // 2 + 5:]
    assert (road_right > 10).mean() > 0.01  # streaks over the road
    assert diff[H // 2 + 5:, : W // 2 - 5].max() == 0  # none in front of the near wall
    assert diff[: H // 2 - 5, W // 2 + 5:].mean() < 0.05 * road_right.mean()  # faint on sky


def _streak_angle_deg(alpha):
    """Dominant direction of the streaks (degrees in [0, 180), image x right, y down): the
    structure tensor's weakest-gradient direction."""
    gy, gx = np.gradient(alpha.astype(float))
    sxx, syy, sxy = (gx * gx).sum(), (gy * gy).sum(), (gx * gy).sum()
    gradient = 0.5 * np.degrees(np.arctan2(2 * sxy, sxx - syy))
    return float((gradient + 90.0) % 180.0)


def _radial_deg(du, dv):
    return float(np.degrees(np.arctan2(dv, du)) % 180.0)


def test_rain_slants_away_from_the_focus_in_front_and_towards_it_behind(cameras):
    """Streaks run along the image flow of the drops: radial from the focus (the car's motion)
    plus the fall. Moving forward (front camera) the fall steepens the outward flow; moving away
    (rear camera) it flattens the inward flow, so the same patch slants differently."""
    deviation = {}
    for name in ("front", "rear"):
        weather = Weather(Conditions(rain=1.0), cameras[name], AIR, np.random.default_rng(0))
        alpha = weather.rain_alpha(_depth(200.0), np.random.default_rng(2), speed_mps=15.0)
        u0, v0 = weather.foe
        rows, cols = slice(int(v0) + 20, int(v0) + 60), slice(int(u0) - 140, int(u0) - 60)
        streaks = _streak_angle_deg(alpha[rows, cols])
        radial = _radial_deg((cols.start + cols.stop) / 2 - u0, (rows.start + rows.stop) / 2 - v0)
        deviation[name] = (streaks - radial + 90.0) % 180.0 - 90.0
    # Left of and below the focus the radial line runs down-left; the fall turns the front
    # streaks towards vertical and the rear streaks away from it.
    assert deviation["front"] * deviation["rear"] < 0, deviation
    assert abs(deviation["front"]) > 3.0 and abs(deviation["rear"]) > 3.0, deviation
    still = Weather(Conditions(rain=1.0), cameras["front"], AIR, np.random.default_rng(0))
    alpha = still.rain_alpha(_depth(200.0), np.random.default_rng(2), speed_mps=0.0)
    assert abs(_streak_angle_deg(alpha) - 90.0) < 5.0  # parked: falling straight down


def test_scenario_weather_turns_on_depth_and_off_mujoco_fog():
    fog = RenderSettings.of(load_scenario("fog"))
    clear = RenderSettings.of(load_scenario("clear_curve"))
    assert fog.depth and not fog.fog
    assert not clear.depth


def test_a_wet_road_mirrors_the_sky_near_the_horizon_only_on_the_ground():
    # the car's own (paper) front camera, whose bottom rows see the road steeply; clear_straight's
    # dashcam (#59) looks only 21 deg down there, where a wet road still mirrors 11 DN
    front = camera_from_model(mujoco.MjModel.from_xml_path(str(SCENE_XML)), "front", W, H)
    weather = Weather(Conditions(wet=1.0), front, AIR, np.random.default_rng(0))
    top = weather.horizon
    frame = np.zeros((H, W, 3), np.uint8)
    frame[:top] = 200  # bright sky
    frame[top:] = 40  # dark wet asphalt
    ground = np.where(np.isfinite(weather.ground_z), weather.ground_z, 500.0)
    out = weather.wet_reflection(frame, ground).astype(float)
    grazing = out[top + 2:top + 6].mean()  # a few rows below the horizon: strong Fresnel
    steep = out[H - 6:].mean()  # the road just ahead: seen steeply, hardly reflects
    assert grazing > 40 + 40 and steep < 40 + 5
    wall = weather.wet_reflection(frame, np.minimum(ground, 1.0))  # nothing is flat ground
    assert np.array_equal(wall[top + 8:], frame[top + 8:])


def test_headlights_light_the_fog_ahead_below_their_cut_off_only_at_night(cameras):
    """The low beams' veil: brightest along the beam, nothing above the cut-off line, none by
    day or on the rear camera."""
    dark = np.full((H, W, 3), 10, np.uint8)
    depth = _depth(200.0)
    night = Weather(Conditions(fog=0.5, time_of_day="night"), cameras["front"], (8, 8, 9),
                    np.random.default_rng(0))
    out = night(dark, depth, np.random.default_rng(1)).astype(float).mean(-1)
    horizon = int(round(cameras["front"].horizon_row()))
    centre = out[horizon + 2:horizon + 12, W // 2 - 10:W // 2 + 10].mean()
    side = out[horizon + 2:horizon + 12, :10].mean()
    sky = out[: max(horizon - 25, 1)].mean()
    assert centre > side + 20.0 and centre > sky + 20.0, (centre, side, sky)
    for conditions, camera in ((Conditions(fog=0.5), "front"),
                               (Conditions(fog=0.5, time_of_day="night"), "rear")):
        weather = Weather(conditions, cameras[camera], (8, 8, 9), np.random.default_rng(0))
        assert weather.beam is None
