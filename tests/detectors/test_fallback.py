"""A classical model's fallback binarisation (detectors/classical.py `detect`, the `fallback`
settings): asked only on a frame where the model's own finds no lane, taken only when it finds
one, and off unless set."""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np
import pytest

from lanekeep.core.config_io import ConfigError
from lanekeep.detectors.config import load_config
from lanekeep.detectors.registry import make_detector
from lanekeep.geometry.camera_model import CameraModel

W, H = 1280, 720
LANE_Y_M = (1.8, -1.8)
FALLBACK = {"hough": "ridge", "sliding_window": "edges"}


def _camera() -> CameraModel:
    f = (W / 2.0) / math.tan(math.radians(30.0))  # a 60 deg dashcam, 1.5 m up, level
    K = np.array([[f, 0, (W - 1) / 2.0], [0, f, (H - 1) / 2.0], [0, 0, 1]])  # noqa: N806
    return CameraModel.from_mounting("front", K, W, H, 1.5, math.radians(-1.0), 1.0)


def _concrete_frame(camera: CameraModel, paint_gain: float, seed: int = 0) -> np.ndarray:
    """Light concrete (150 DN with 6 DN of grain) under sky, two solid lines 15 cm wide whose
    paint is `paint_gain` times the road: 1.12 is the faint paint on concrete that the
    per-pixel test (1.2x the road beside it) misses, as on the tuning clear set's concrete
    world."""
    rng = np.random.default_rng(seed)
    img = np.full((H, W), 150.0)
    img[: int(camera.horizon_row()) + 1] = 200.0
    x = np.linspace(4.0, 60.0, 300)
    for y0 in LANE_Y_M:
        edge = np.concatenate([camera.project_ground(np.stack([x, np.full_like(x, y0 + 0.075)],
                                                              -1))[0],
                               camera.project_ground(np.stack([x, np.full_like(x, y0 - 0.075)],
                                                              -1))[0][::-1]])
        mask = np.zeros((H, W), np.uint8)
        cv2.fillPoly(mask, [np.round(edge * 4).astype(np.int32)], 1, shift=2)
        img[mask > 0] *= paint_gain
    img += rng.normal(0.0, 6.0, img.shape)
    grey = np.clip(img, 0, 255).astype(np.uint8)
    return np.repeat(grey[..., None], 3, axis=2)


def _with_fallback(name: str, mode: str):
    config = load_config()
    table = getattr(config, name)
    return dataclasses.replace(config, **{name: dataclasses.replace(table, fallback=mode)})


@pytest.mark.parametrize("name", ["hough", "sliding_window"])
def test_the_fallback_finds_faint_paint_the_own_binarisation_misses(name):
    camera = _camera()
    frame = _concrete_frame(camera, 1.12)
    alone = make_detector(name, camera)
    assert not alone.detect(frame).valid  # the per-pixel test misses paint 12% over the road
    both = make_detector(name, camera, _with_fallback(name, FALLBACK[name]))
    estimate = both.detect(frame)
    assert estimate.valid, estimate.reason
    assert abs(estimate.offset_m) < 0.15  # the car is centred between the two lines
    for coeffs, y0 in ((estimate.left, LANE_Y_M[0]), (estimate.right, LANE_Y_M[1])):
        assert coeffs is not None and abs(coeffs[0] + coeffs[1] * 10.0
                                          + coeffs[2] * 100.0 - y0) < 0.15


@pytest.mark.parametrize("name", ["hough", "sliding_window"])
def test_the_fallback_is_not_asked_where_the_own_binarisation_finds_the_lane(name, monkeypatch):
    camera = _camera()
    frame = _concrete_frame(camera, 1.6)  # bright paint: the per-pixel test finds it
    both = make_detector(name, camera, _with_fallback(name, FALLBACK[name]))
    asked = []
    fallback = both._fallback
    original = fallback.detect
    monkeypatch.setattr(fallback, "detect", lambda f: asked.append(1) or original(f))
    alone = make_detector(name, camera).detect(frame)
    estimate = both.detect(frame)
    assert alone.valid and estimate.valid and not asked
    assert estimate.offset_m == alone.offset_m
    blank = np.full_like(frame, 150)
    assert not both.detect(blank).valid and asked == [1]  # asked, found nothing: still invalid


def test_the_fallback_is_off_as_shipped_and_in_paper_mode():
    from lanekeep.driver.paper_mode import front_detector_config

    shipped = load_config()
    assert shipped.hough.fallback == "" and shipped.sliding_window.fallback == ""
    set_both = dataclasses.replace(
        shipped, hough=dataclasses.replace(shipped.hough, fallback="ridge"),
        sliding_window=dataclasses.replace(shipped.sliding_window, fallback="edges"))
    for name in ("hough", "sliding_window"):
        paper = front_detector_config(name, "paper", set_both)
        assert getattr(paper, name).binarisation == "paper"
        assert getattr(paper, name).fallback == ""
        assert make_detector(name, _camera(), paper)._fallback is None


@pytest.mark.parametrize(("text", "message"), [
    ('[hough]\nfallback = "edges"\n', "fallback"),
    ('[sliding_window]\nfallback = "ridge"\n', "fallback"),
    ('[hough]\nbinarisation = "ridge"\nfallback = "ridge"\n', "fallback"),
    ('[sliding_window]\nfallback = "image"\n', "fallback"),
    ('[hough]\nfallback = "paper"\n', "fallback"),
])
def test_a_fallback_a_model_does_not_have_is_refused(tmp_path, text, message):
    path = tmp_path / "detectors.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_config(path)


def test_a_bird_eye_binarisation_can_fall_back_on_the_image_one(tmp_path):
    path = tmp_path / "detectors.toml"
    path.write_text('[sliding_window]\nbinarisation = "edges"\nfallback = "image"\n')
    detector = make_detector("sliding_window", _camera(), load_config(path))
    assert detector.bird_eye_paint and not detector._fallback.bird_eye_paint
    assert detector._fallback._fallback is None  # one level: the fallback has none of its own
