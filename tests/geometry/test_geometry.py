"""Bird's-eye geometry: the warp agrees with the camera model's projection, for both cameras."""

import math

import numpy as np
import pytest

import lanekeep  # noqa: F401 - MUJOCO_GL before mujoco
from lanekeep.detectors.birds_eye import BirdsEye, ground_homography, visible_window
from lanekeep.detectors.config import GroundWindow, Preprocess
from lanekeep.detectors.image_stage import open_along_rows, remove_streaks, streak_pixels
from lanekeep.geometry.camera_model import CameraModel

K = np.array([[369.29, 0.0, 639.5], [0.0, 369.29, 359.5], [0.0, 0.0, 1.0]])
FRONT = CameraModel.from_mounting("front", K, 1280, 720, 1.5, math.radians(10.0), x_m=1.0)
REAR_K = np.array([[171.56, 0.0, 639.5], [0.0, 171.56, 359.5], [0.0, 0.0, 1.0]])
REAR = CameraModel.from_mounting("rear", REAR_K, 1280, 720, 1.5, math.radians(-20.0), x_m=-2.0,
                                 yaw_rad=math.pi)


@pytest.mark.parametrize("camera", [FRONT, REAR], ids=["front", "rear"])
def test_homography_matches_projection(camera):
    sign = 1.0 if camera is FRONT else -1.0
    xy = np.array([[sign * 5.0, 1.85], [sign * 12.0, -1.85], [sign * 20.0, 0.3]])
    uv, ok = camera.project_ground(xy)
    assert ok.all()
    h = ground_homography(camera)
    p = (h @ np.column_stack([xy, np.ones(3)]).T).T
    np.testing.assert_allclose(p[:, :2] / p[:, 2:], uv, atol=1e-6)


@pytest.mark.parametrize("camera,window", [
    (FRONT, GroundWindow(4.0, 20.0, 6.0, 0.05, 0.1)),
    (REAR, GroundWindow(-4.0, -16.0, 6.0, 0.05, 0.1)),
], ids=["front", "rear"])
def test_warp_puts_a_ground_point_at_its_metric_pixel(camera, window):
    view = BirdsEye(camera, window, scale=0.5, crop_top=300)
    # Pixel <-> metre maps invert each other; row 0 is the far edge, the last row the near one.
    cols, rows = np.array([3.0, 100.0, 200.0]), np.array([5.0, 80.0, 150.0])
    x, y = view.to_ground(cols, rows)
    c2, r2 = view.to_pixels(x, y)
    np.testing.assert_allclose(np.c_[c2, r2], np.c_[cols, rows], atol=1e-9)
    assert abs(view.to_ground(0, view.rows - 1)[0] - window.x_near_m) < window.m_per_row
    # Column 0 is the camera's left: +y ahead of the car, -y behind it.
    assert np.sign(view.to_ground(0, 0)[1]) == (1.0 if camera is FRONT else -1.0)
    # A bright blob painted where a ground point projects lands at that point's BEV pixel.
    target = np.array([window.x_near_m + window.direction * 6.0, 1.2])
    uv, _ = camera.project_ground(target)
    col, row = int(round(uv[0] * 0.5)), int(round((uv[1] - 300) * 0.5))
    image = np.zeros((int(round((camera.height - 300) * 0.5)), camera.width // 2), np.uint8)
    image[row - 1 : row + 2, col - 1 : col + 2] = 255
    bev = view.warp(image).astype(float)
    rows_i, cols_i = np.indices(bev.shape)
    c, r = (bev * cols_i).sum() / bev.sum(), (bev * rows_i).sum() / bev.sum()
    x, y = view.to_ground(c, r)
    assert abs(x - target[0]) < 0.3 and abs(y - target[1]) < 0.1


def test_visible_window_moves_the_near_edge_out_of_the_blind_zone():
    level = CameraModel.from_mounting("dashcam", np.array(
        [[1108.5, 0, 639.5], [0, 1108.5, 359.5], [0, 0, 1]]), 1280, 720, 1.5, 0.0)
    window = visible_window(level, GroundWindow(2.0, 40.0))
    # Bottom row 360 px below the centre: ground at 1.5 * 1108.5 / 360.5 = 4.6 m.
    assert window.x_near_m == pytest.approx(1.5 * 1108.5 / 360.5 + 0.3, abs=0.05)
    assert visible_window(FRONT, GroundWindow(4.0, 20.0)).x_near_m == 4.0


def test_remove_streaks_drops_thin_vertical_rain_and_keeps_slanted_and_thick_paint():
    import cv2

    mask = np.zeros((136, 640), np.uint8)
    for col in range(20, 620, 37):  # rain: 2 px wide, 20 rows tall, leaning a little
        cv2.line(mask, (col, 10), (col + 3, 30), 255, 2)
    cv2.line(mask, (100, 135), (300, 0), 255, 3)  # a far boundary: thin but 56 deg from vertical
    cv2.line(mask, (560, 135), (470, 60), 255, 14)  # a near boundary: thick, 50 deg
    kept = remove_streaks(mask, min_rows=12, max_tilt_deg=15.0, max_width=5)
    rain = np.zeros_like(mask)
    rain[5:35] = 255
    rain[:, 90:310] = 0  # where the thin boundary crosses the rain band
    assert cv2.countNonZero(cv2.bitwise_and(kept, rain)) < 0.05 * cv2.countNonZero(
        cv2.bitwise_and(mask, rain))
    assert kept[100:136, 450:600].sum() >= 0.95 * mask[100:136, 450:600].sum()  # thick paint
    assert kept[50:136, 100:300].sum() >= 0.95 * mask[50:136, 100:300].sum()  # thin slant kept
    assert remove_streaks(mask, 0, 15.0) is mask  # 0 switches it off


def test_streak_sizes_scale_with_the_frame_and_the_working_scale():
    pre = Preprocess(scale=0.5, streak_min_rows=24)
    assert streak_pixels(pre, 720) == (12, 5)
    assert streak_pixels(pre, 360) == (6, 2)  # a half-size camera: half the pixels
    assert streak_pixels(Preprocess(scale=1.0, streak_min_rows=24), 720) == (24, 10)
    assert streak_pixels(pre, 120)[0] == 0  # too few rows to tell a streak from a speck


def test_opening_along_rows_removes_thin_rain_and_keeps_slanted_paint():
    import cv2

    grey = np.full((136, 640), 80, np.uint8)
    for col in range(20, 620, 37):  # rain: 1 px wide, 30 rows tall, 14 deg from vertical
        cv2.line(grey, (col, 10), (col + 7, 40), 160, 1)
    cv2.line(grey, (100, 135), (300, 0), 220, 2)  # far paint: 2 px wide, 56 deg from vertical
    image = np.dstack([grey] * 3)
    opened = open_along_rows(image, 3)
    rain_band = (slice(10, 40), slice(320, 640))  # right of the paint
    assert opened[rain_band].max() == 80  # every streak is gone
    paint = grey >= 200
    assert np.all(opened[..., 0][paint][10:-10] >= 200)  # the paint keeps its brightness
    assert open_along_rows(image, 1) is image  # width < 2: off
