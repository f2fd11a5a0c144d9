"""The camera model (lanekeep/sensing/camera_sensor.py): noise always on at a realistic level,
causal
auto-exposure with highlight protection, a shadow-lifting tone curve, vignetting, optional JPEG,
the ego hood in the front image only, and the `[camera]` keys validated."""

import dataclasses

import cv2
import numpy as np
import pytest

from lanekeep.scenario.schema import CameraConfig, ScenarioError, load_scenario, parse_scenario
from lanekeep.sensing.camera_sensor import MAX_GAIN, CameraSensor, tone_curve, vignetting_map
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build

H, W = 180, 320
OPTICS_OFF = {"lens_blur_px": 0.0, "bloom": 0.0, "jpeg_quality": 0}  # the sensor alone


def _sensor(seed=0, **changes):
    camera = dataclasses.replace(CameraConfig(), **changes)
    return CameraSensor(camera, 0.0, H, W, 0.1, np.random.default_rng(seed))


def _flat(level):
    return np.full((H, W, 3), level, np.uint8)


def test_default_camera_adds_realistic_noise_to_a_flat_frame():
    out = _sensor(vignetting=0.0, auto_exposure=False, **OPTICS_OFF)(_flat(105),
                                                                     np.random.default_rng(1))
    centre = out[40:140, 80:240].astype(float)
    assert 0.7 < centre.std() < 3.0  # a few DN, as a good automotive camera at day
    assert abs(centre.mean() - 255 * tone_curve(105 / 255)) < 0.5  # zero-mean noise


def test_the_chain_equals_a_straightforward_reference():
    """Vignetting, then the signed noise added in int16 and clipped, then gain and tone: the
    sensor's one-plane passes and its split noise bank give the same frame, bit for bit."""
    sensor = _sensor(seed=2, auto_exposure=False, read_noise_dn=6.0, vignetting=0.3,
                     **OPTICS_OFF)
    frame = np.random.default_rng(3).integers(0, 256, (H, W, 3), dtype=np.uint8)
    got = sensor(frame, np.random.default_rng(4))
    positive, negative = sensor.read_bank
    assert ((positive == 0) | (negative == 0)).all()  # each pixel's noise has one sign
    start = int(np.random.default_rng(4).integers(0, positive.shape[0] - H + 1))
    noise = (positive.astype(np.int16) - negative)[start:start + H].reshape(H, W, 3)
    lit = cv2.multiply(frame, vignetting_map(H, W, 0.3), scale=1.0 / 255.0)
    tone = np.clip(np.round(255.0 * tone_curve(np.arange(256) / 255.0)), 0, 255).astype(np.uint8)
    expected = tone[np.clip(lit.astype(np.int16) + noise, 0, 255)]
    np.testing.assert_array_equal(got, expected)
    assert got.shape == frame.shape and got.base is not frame.base  # a new frame


def test_frames_differ_and_a_seed_repeats_them():
    def frames(seed):
        sensor, rng = _sensor(seed), np.random.default_rng(seed)
        return [sensor(_flat(90), rng) for _ in range(3)]

    a, b, c = frames(3), frames(3), frames(4)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not np.array_equal(a[0], a[1]) and not np.array_equal(a[0], c[0])


def test_shade_is_dark_grey_not_black():
    """A frame of shaded asphalt (12 DN rendered) comes out clearly above black: the
    auto-exposure brightens a frame that is all shade. Without it the tone curve keeps the
    level about where it was, neither lifted (the old toe's 17-25 DN, a lift real cameras do
    not show, issue #59) nor crushed to black."""
    out = _sensor(read_noise_dn=0.0, vignetting=0.0)(_flat(12), np.random.default_rng(0))
    assert out.mean() > 35  # exposure
    tone_only = _sensor(read_noise_dn=0.0, vignetting=0.0, auto_exposure=False)(
        _flat(12), np.random.default_rng(0))
    assert 8 <= tone_only.mean() <= 13


def test_the_tone_curve_crushes_blacks_and_keeps_the_midtones():
    """Real dashcams crush deep shadows (their darkest 1% at 7-8 DN): the curve darkens them,
    keeps shaded road about where the shade's physics puts it and a sunlit road's midtones."""
    t = np.arange(256) / 255.0
    out = 255.0 * tone_curve(t)
    assert np.all(np.diff(out) > 0)  # monotonic
    assert out[8] < 7 and out[4] < 3.5  # blacks crushed
    assert abs(out[25] - 25) < 2.5  # shaded road (~0.26 of a sunlit one)
    assert 0 <= out[80] - 80 <= 8 and abs(out[160] - 160) < 4  # a sunlit road, the sky
    assert out[255] == pytest.approx(255, abs=0.01)


def test_auto_exposure_is_causal_and_follows_with_its_time_constant():
    rng = np.random.default_rng(0)
    sensor = _sensor(read_noise_dn=0.0, vignetting=0.0, exposure_time_constant_s=0.3)
    sensor(_flat(105), rng)  # a well-exposed road
    assert sensor.gain == pytest.approx(1.0, abs=0.01)
    dark = _flat(40)
    first = sensor(dark, rng)  # exposed with the gain of the past (bright) frames
    assert np.array_equal(first, np.round(255 * tone_curve(dark / 255.0)).astype(np.uint8))
    gains = []
    for _ in range(30):
        sensor(dark, rng)
        gains.append(sensor.gain)
    assert all(b >= a for a, b in zip(gains, gains[1:], strict=False))  # rising, no overshoot
    settled = 105.0 / 40.0
    after_03s = 1.0 + (1 - np.exp(-1.0)) * (settled - 1.0)  # ~1 time constant: 3 frames
    assert gains[1] == pytest.approx(after_03s, rel=0.25)
    assert gains[-1] == pytest.approx(settled, rel=0.02)


def test_highlights_are_protected_and_the_gain_is_bounded():
    rng = np.random.default_rng(0)
    night = _flat(4)
    night[100:140] = 20  # dim road beyond the lamps' pool
    night[140:, 120:200] = 110  # a headlit patch, ~11% of the frame
    sensor = _sensor(read_noise_dn=0.0, vignetting=0.0)
    out = sensor(night, rng)
    assert out[150:, 130:190].mean() < 240  # not blown out
    # the dark is brightened (the black sky stays black: the tone curve crushes it again)
    assert sensor.gain > 1.2 and out[105:135].mean() > night[105:135].mean() + 5
    black = _sensor(read_noise_dn=0.0, vignetting=0.0)
    black(_flat(1), rng)
    assert black.gain == pytest.approx(MAX_GAIN)


def test_vignetting_darkens_the_corners():
    out = _sensor(read_noise_dn=0.0, auto_exposure=False, vignetting=0.3)(
        _flat(200), np.random.default_rng(0)).astype(float)
    centre, corner = out[85:95, 155:165].mean(), out[:5, :5].mean()
    assert corner < 0.8 * centre and centre > 195


def test_jpeg_compression_is_optional():
    frame = np.random.default_rng(5).integers(60, 200, (H, W, 3)).astype(np.uint8)
    plain = _sensor(read_noise_dn=0.0, auto_exposure=False, vignetting=0.0, **OPTICS_OFF)(
        frame, np.random.default_rng(0))
    jpeg = _sensor(read_noise_dn=0.0, auto_exposure=False, vignetting=0.0,
                   **dict(OPTICS_OFF, jpeg_quality=30))(
        frame, np.random.default_rng(0))
    assert plain.shape == jpeg.shape and jpeg.dtype == np.uint8
    assert np.abs(plain.astype(int) - jpeg.astype(int)).mean() > 5  # noise is what JPEG drops


@pytest.mark.parametrize("key, value", [("jpeg_quality", 5), ("vignetting", 0.9),
                                        ("read_noise_dn", -1.0),
                                        ("exposure_time_constant_s", 0.0)])
def test_bad_camera_keys_are_named(key, value):
    text = ('name = "t"\ndescription = "t"\n[road]\n[[road.segments]]\nkind = "straight"\n'
            f'length_m = 200\n[camera]\n{key} = {value}\n')
    with pytest.raises(ScenarioError, match=f"camera.{key}"):
        parse_scenario(text)


def test_the_hood_shows_low_in_the_front_image_only(straight_world):
    # the paper camera: clear_straight's dashcam (#59) looks over the hood (no hood pixel)
    base = straight_world.scenario
    straight_world = build(dataclasses.replace(base, camera=dataclasses.replace(
        base.camera, preset="paper")))
    hood = straight_world.model.geom("hood").id
    place_on_road(straight_world, 20.0)
    shares = {}
    for show in (True, False):
        with CameraRig(straight_world.model, RenderSettings(W, H, show_hood=show)) as rig:
            for cam in rig.CAMERA_NAMES:
                seg = rig.render_segmentation(straight_world.data, cam)
                rows = np.nonzero((seg == hood).any(axis=1))[0]
                shares[show, cam] = (rows.min() / H if len(rows) else 1.0,
                                     float((seg == hood).mean()))
    top, area = shares[True, "front"]
    assert 0.88 <= top <= 0.96 and area > 0.02  # the bottom 4-12% of the front image
    assert shares[True, "rear"][1] == 0.0 and shares[False, "front"][1] == 0.0


def test_shipped_scenarios_show_the_hood_by_default():
    assert load_scenario("clear_curve").camera.show_hood
    assert RenderSettings.of(load_scenario("clear_curve")).show_hood
