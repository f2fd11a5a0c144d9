"""Fog taken out row by row (detectors/defog.py): on a synthetic road in fog (Koschmieder's
law), the transmission is read back from the road's own rise towards the fog's colour and the
paint's step over the road restored; a frame without fog, a dark horizon or a skyline is left
alone."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from lanekeep.detectors.config import load_config
from lanekeep.detectors.defog import estimate_fog
from lanekeep.detectors.hough import HoughDetector
from lanekeep.detectors.image_stage import region_of_interest
from lanekeep.detectors.sliding_window import SlidingWindowDetector
from lanekeep.geometry.camera_model import CameraModel

W, H = 1280, 720
K = np.array([[900.0, 0.0, W / 2], [0.0, 900.0, H / 2], [0.0, 0.0, 1.0]])
CAMERA = CameraModel.from_mounting("front", K, W, H, 1.5, math.radians(-6.0), x_m=1.0)
ROAD, PAINT = 70.0, 200.0  # grey levels of the scene without fog
LINES_M = (1.8, -1.8)  # the car's lane: its boundaries' lateral positions
AIR = np.array([188.0, 190.0, 194.0])
VISIBILITY_M = 60.0  # Koschmieder's law, as the world draws fog: t = exp(-3.912 d / V)


def _scene(visibility_m: float | None, air: np.ndarray = AIR
           ) -> tuple[np.ndarray, np.ndarray]:
    """A straight road with two lines in fog of this visibility (None: clear air): the frame,
    and each row's true transmission."""
    cols, rows = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    ground, seen = CAMERA.pixels_to_ground(np.stack([cols, rows], axis=-1))
    x = np.where(seen, ground[..., 0], np.inf)
    y = ground[..., 1]
    paint = np.zeros((H, W), bool)
    for line in LINES_M:
        paint |= seen & (np.abs(y - line) < 0.075)
    scene = np.where(paint, PAINT, ROAD)[..., None] * np.ones(3)
    if visibility_m is None:
        t = np.ones((H, W))
        scene[~seen] = air
    else:
        distance = np.hypot(x - CAMERA.position_m[0], y - CAMERA.position_m[1])
        t = np.exp(-3.912 * distance / visibility_m)  # 0 beyond the horizon
    frame = t[..., None] * scene + (1.0 - t[..., None]) * air
    return np.clip(frame, 0, 255).round().astype(np.uint8), t[:, W // 2]


def test_the_transmission_is_read_back_from_the_roads_rise():
    frame, truth = _scene(VISIBILITY_M)
    fog = estimate_fog(frame, CAMERA)
    assert fog is not None
    np.testing.assert_allclose(fog.airlight, AIR, atol=1.0)
    rows = np.arange(fog.first_row, H)
    ground, _ = CAMERA.pixels_to_ground(np.stack([np.full(len(rows), W / 2), rows + 0.5], 1))
    near = (ground[:, 0] >= 6.0) & (ground[:, 0] <= 12.0)  # the road it takes for clear
    mid = (ground[:, 0] > 8.0) & (ground[:, 0] < 40.0)
    relative = truth[rows[mid]] / np.median(truth[rows[near]])
    np.testing.assert_allclose(fog.transmission[mid], np.minimum(relative, 1.0), atol=0.03)


def test_clearing_restores_the_paints_step_over_the_road():
    """Far rows get the step the paint has over the road 6-12 m ahead (the road the clearing
    takes for clear), where the fog had taken more than half of it."""
    frame, truth = _scene(VISIBILITY_M)
    fog = estimate_fog(frame, CAMERA)
    clear = fog.clear(frame, 0, 1.0)

    def step(image: np.ndarray, row: int) -> float:
        road = np.median(image[row, W // 2 - 50:W // 2 + 50].astype(float))
        return float(image[row].astype(float).max() - road)

    rows = np.arange(H)
    ground, seen = CAMERA.pixels_to_ground(np.stack([np.full(H, W / 2), rows + 0.5], 1))
    near = rows[seen & (ground[:, 0] >= 6.0) & (ground[:, 0] <= 12.0)]
    near_step = float(np.median([step(frame, r) for r in near]))
    far = int(np.argmin(np.abs(truth - 0.5 * np.median(truth[near]))))  # half the near light
    assert step(frame, far) < 0.6 * near_step
    assert step(clear, far) == pytest.approx(near_step, rel=0.15)


@pytest.mark.parametrize("air", [AIR, np.array([40.0, 45.0, 35.0])], ids=["sky", "dark_horizon"])
def test_a_frame_without_fog_is_left_as_it_is(air):
    frame, _ = _scene(None, air)
    assert estimate_fog(frame, CAMERA) is None
    config = load_config()
    on = dataclasses.replace(config, preprocess=dataclasses.replace(config.preprocess,
                                                                      defog=True))
    view = HoughDetector(CAMERA, on).view
    plain = region_of_interest(frame, view, config.preprocess, None, CAMERA)
    defogged = region_of_interest(frame, view, on.preprocess, None, CAMERA)
    assert np.array_equal(plain.rgb, defogged.rgb)


def test_a_skyline_at_the_horizon_is_no_fog():
    """A road that brightens ahead under a horizon of buildings (a sunlit road beyond a
    shade, in clear air) is not taken for fog: fog leaves the horizon one colour."""
    frame, _ = _scene(VISIBILITY_M)
    horizon = int(CAMERA.horizon_row())
    band = frame[horizon - 30:horizon + 1]
    band[:, (np.arange(W) // 40) % 2 == 0] = 60  # dark facades between bright sky
    assert estimate_fog(frame, CAMERA) is None


@pytest.mark.parametrize("model", [HoughDetector, SlidingWindowDetector])
def test_each_model_reads_the_cleared_frame(model):
    """What clearing does to a frame the models read: on this clean synthetic road both find
    the lane with or without it (the gain is on rendered fog, whose paint is worn and whose
    road has grain: docs/experiments.md, session 35); cleared, they still find both lines and
    the centre."""
    frame, _ = _scene(VISIBILITY_M / 2)  # dense: the lines fade out within 30 m
    config = load_config()
    on = dataclasses.replace(config, preprocess=dataclasses.replace(config.preprocess,
                                                                      defog=True))
    estimate = model(CAMERA, on).detect(frame)
    assert estimate.valid, estimate.reason
    assert estimate.offset_m == pytest.approx(0.0, abs=0.03)
    assert estimate.left is not None and estimate.right is not None
