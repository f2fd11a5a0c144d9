"""Issue #44's optics, sky and weather look: a soft point spread and glare by default, JPEG
when asked for
(lanekeep/sensing/camera_sensor.py); translucent lens drops and snow in depth
(lanekeep/sensing/weather.py); an overcast for rain and snow (lanekeep/world/lighting.py) and
the seeded cloudy sky (lanekeep/world/sky.py)."""

import dataclasses

import numpy as np
import pytest

from lanekeep.scenario.schema import CameraConfig, Conditions, load_scenario
from lanekeep.sensing.camera_sensor import CameraSensor
from lanekeep.sensing.image_effects import default_camera
from lanekeep.sensing.lens_drops import WOBBLE_PX, LensDrops, drop_streams
from lanekeep.sensing.weather import Weather
from lanekeep.world.appearance import lighting_of
from lanekeep.world.lighting import OVERCAST_DIRECT, direct_sun_share
from lanekeep.world.sky import cube_directions, sky_texture

H, W = 180, 320


def _sensor(width=W, height=H, **changes):
    camera = dataclasses.replace(CameraConfig(), read_noise_dn=0.0, auto_exposure=False,
                                 vignetting=0.0, **changes)
    return CameraSensor(camera, 0.0, height, width, 0.1, np.random.default_rng(0))


def _rise_px(row: np.ndarray) -> int:
    """Pixels a dark-to-bright edge takes from 10% to 90% of its step."""
    lo, hi = row[:20].mean(), row[-20:].mean()
    t = (row - lo) / (hi - lo)
    return int(np.count_nonzero((t > 0.1) & (t < 0.9)))


def test_a_hard_edge_rises_over_two_pixels_or_more_by_default():
    step = np.full((H, W, 3), 60, np.uint8)
    step[:, W // 2:] = 180  # a rendered paint edge: one pixel from road to paint
    sharp = _sensor(lens_blur_px=0.0, bloom=0.0, jpeg_quality=0)(step, np.random.default_rng(0))
    soft = _sensor()(step, np.random.default_rng(0))
    rows = slice(H // 2 - 10, H // 2 + 10)
    assert _rise_px(sharp[rows, :, 1].mean(0)) <= 1
    assert _rise_px(soft[rows, :, 1].mean(0)) >= 2


def test_jpeg_is_off_by_default_and_changes_the_frame_when_asked_for():
    assert CameraConfig().jpeg_quality == 0  # an ADAS camera's frames are not compressed
    frame = np.random.default_rng(5).integers(60, 200, (H, W, 3)).astype(np.uint8)
    on = _sensor(lens_blur_px=0.0, bloom=0.0, jpeg_quality=90)(frame, np.random.default_rng(0))
    off = _sensor(lens_blur_px=0.0, bloom=0.0, jpeg_quality=0)(frame, np.random.default_rng(0))
    assert np.abs(on.astype(int) - off.astype(int)).mean() > 1.0


def test_glare_spills_from_bright_areas_onto_dark_ones_only():
    h, w = 720, 1280  # the glare's width is a share of the frame's
    frame = np.full((h, w, 3), 40, np.uint8)
    frame[:, : w // 2] = 250  # a bright sky beside a dark tree line
    plain = _sensor(lens_blur_px=0.0, bloom=0.0, jpeg_quality=0, width=w, height=h)
    glare = _sensor(lens_blur_px=0.0, jpeg_quality=0, width=w, height=h)
    plain, glare = (s(frame, np.random.default_rng(0)) for s in (plain, glare))
    near = slice(w // 2 + 2, w // 2 + 12)
    assert glare[:, near].mean() > plain[:, near].mean() + 3  # the halo beside the bright side
    assert glare[:, -10:].mean() == pytest.approx(plain[:, -10:].mean(), abs=1.0)  # far: none
    assert glare[:, :w // 4].mean() == pytest.approx(plain[:, :w // 4].mean(), abs=1.0)
    dim = np.random.default_rng(3).integers(0, 190, (H, W, 3)).astype(np.uint8)
    assert np.array_equal(  # nothing near saturation: no glare
        _sensor(lens_blur_px=0.0, jpeg_quality=0)(dim, np.random.default_rng(0)),
        _sensor(lens_blur_px=0.0, bloom=0.0, jpeg_quality=0)(dim, np.random.default_rng(0)))


def test_lens_drops_show_the_scene_through_them_upside_down():
    conditions = Conditions(rain=1.0)
    weather = Weather(conditions, default_camera(360, 640), (200.0, 200.0, 200.0),
                      np.random.default_rng(0))
    weather.lens = LensDrops(np.array([[320.0, 180.0, 30.0]]),
                             drop_streams(np.random.default_rng(0), 0, 1), 640, 360)
    ramp = np.repeat(np.linspace(20, 230, 360)[:, None], 640, 1).astype(np.uint8)  # bright below
    image = np.stack([ramp] * 3, -1)
    image[:, (np.arange(640) // 24) % 2 == 1] //= 2  # stripes: must survive inside the drop
    rng = np.random.default_rng(1)
    rng_y = 180.0 + (2.0 * rng.uniform(0.0, 1.5) / 1.5 - 1.0) * WOBBLE_PX * weather.scale
    out = weather.lens_drops(image, np.random.default_rng(1))
    y = int(round(rng_y))
    inside = out[y - 12:y + 13, 308:333, 1].astype(float)
    assert inside[:5].mean() > inside[-5:].mean() + 10  # inverted: brighter at its top
    assert inside.std(axis=1).mean() > 2.0  # the stripes show through, blurred: not a disc
    assert np.array_equal(out[:100], image[:100])  # the scene outside is untouched


def test_snowflakes_differ_in_brightness_and_size():
    weather = Weather(Conditions(snow=1.0), default_camera(360, 640), (200.0, 200.0, 200.0),
                      np.random.default_rng(0))
    out = weather.snow(np.zeros((360, 640, 3), np.uint8), np.random.default_rng(2))[..., 0]
    veil = int(np.median(out))
    flakes = out[out > veil + 20]
    assert flakes.size > 0 and np.percentile(flakes, 90) - np.percentile(flakes, 10) > 40


@pytest.mark.parametrize("weather", [{"rain": 0.6}, {"snow": 0.7}])
def test_rain_and_snow_come_with_an_overcast(weather):
    road = load_scenario("clear_straight").build_road()
    clear, grey = lighting_of(Conditions(), road), lighting_of(Conditions(**weather), road)
    assert direct_sun_share(Conditions(**weather)) <= OVERCAST_DIRECT + 1e-9  # no hard shadows
    assert np.mean(grey.sun_diffuse) < 0.05 * np.mean(clear.sun_diffuse)

    def saturation(rgb):
        return (max(rgb) - min(rgb)) / max(rgb)

    assert saturation(grey.sky_zenith) < 0.1 < saturation(clear.sky_zenith)
    dusk = lighting_of(Conditions(time_of_day="dusk", **weather), road)
    assert saturation(dusk.sky_horizon) < 0.1  # case 5's mauve sky turns grey


def test_the_sky_has_a_pale_horizon_and_seeded_clouds():
    face = 64
    args = ((0.52, 0.65, 0.84), (0.84, 0.87, 0.90), 0.3, 0.0)
    a = sky_texture(*args, np.random.default_rng(1), face_px=face).astype(float)
    b = sky_texture(*args, np.random.default_rng(1), face_px=face)
    c = sky_texture(*args, np.random.default_rng(2), face_px=face)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    up = cube_directions(face)[..., 2]
    blue = a[..., 2] - a[..., 0]
    low, high = (up > 0.0) & (up < 0.05), up > 0.9
    assert blue[low].mean() < blue[high].mean()  # paler towards the horizon
    white = (a.min(-1) > 0.9 * 255 * 0.96 * 0.78) & (blue < 15) & (up > 0.2)
    assert 0.02 < white[up > 0.2].mean() < 0.6  # some clouds, not a closed deck
    assert np.abs(a[up < -0.01] - 255 * np.array(args[1])).max() <= 1.0  # below: the horizon
