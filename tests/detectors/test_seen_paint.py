"""The observer's look under each point: a paint-wide ridge brighter than the road on both sides
is paint; flat road, a one-sided edge (a shoulder) and the sky are not."""

import math

import numpy as np
import pytest

from lanekeep.detectors.seen_paint import PaintTest, paint_under_points
from lanekeep.geometry.camera_model import CameraModel

W, H = 1280, 720


def _rear_camera() -> CameraModel:
    f = (W / 2.0) / math.tan(math.radians(75.0))
    K = np.array([[f, 0, (W - 1) / 2.0], [0, f, (H - 1) / 2.0], [0, 0, 1]])  # noqa: N806
    return CameraModel.from_mounting("rear", K, W, H, 1.5, math.radians(-20.0), -2.0,
                                     yaw_rad=math.pi)


def _frame() -> np.ndarray:
    """Road 90 below the horizon, a 6 px stripe of 130 at column 400, a shoulder of 140 from
    column 900 on (bright on one side only)."""
    frame = np.full((H, W, 3), 90, np.uint8)
    frame[:, 397:403] = 130
    frame[:, 900:] = 140
    return frame


def test_points_on_a_stripe_are_paint_and_points_beside_it_are_not():
    camera, frame = _rear_camera(), _frame()
    points = np.array([[400.0, 600.0], [403.0, 500.0], [430.0, 600.0], [640.0, 550.0],
                       [900.0, 600.0], [400.0, 100.0]])
    seen = paint_under_points(frame, points, camera, PaintTest())
    # on it, on it within the placement tolerance, 30 px off, flat road, a shoulder's edge,
    # the same column in the sky (no ground there)
    np.testing.assert_array_equal(seen, [1, 1, 0, 0, 0, 0])


def test_a_faint_stripe_needs_the_configured_contrast():
    camera, frame = _rear_camera(), _frame()
    frame[:, 397:403] = 96  # 6 grey levels over the road
    point = np.array([[400.0, 600.0]])
    assert paint_under_points(frame, point, camera, PaintTest())[0] == 0
    assert paint_under_points(frame, point, camera, PaintTest(min_ratio=0.05, min_step=5.0))[0]


def _double_line_frame(gap_px: int, stripe_px: int) -> np.ndarray:
    """Road 90, rows 590-610 crossed by two stripes of 130 either side of column 640."""
    frame = np.full((H, W, 3), 90, np.uint8)
    inner = gap_px // 2
    frame[590:611, 640 - inner - stripe_px:640 - inner] = 130
    frame[590:611, 640 + inner:640 + inner + stripe_px] = 130
    return frame


def test_a_point_on_a_double_lines_gap_is_paint_only_with_the_double_test():
    """At row 600 of this camera a 15 cm stripe is 28 px and a 12 cm gap 23 px: the one-stripe
    test finds the two stripes beside the point and takes them for the road."""
    camera, frame = _rear_camera(), _double_line_frame(gap_px=23, stripe_px=28)
    point = np.array([[640.0, 600.0]])
    assert paint_under_points(frame, point, camera, PaintTest(double_gap_m=0.0))[0] == 0
    assert paint_under_points(frame, point, camera, PaintTest())[0] == 1  # the default: 0.12 m


def test_the_double_test_needs_a_stripe_on_both_sides():
    camera, double = _rear_camera(), PaintTest(double_gap_m=0.12)
    one_side = _double_line_frame(gap_px=23, stripe_px=28)
    one_side[590:611, 640:] = 90  # the right stripe gone
    wide = _double_line_frame(gap_px=200, stripe_px=28)  # two lines a metre apart
    point = np.array([[640.0, 600.0]])
    assert paint_under_points(one_side, point, camera, double)[0] == 0
    assert paint_under_points(wide, point, camera, double)[0] == 0
    # a single stripe under the point passes either way
    np.testing.assert_array_equal(
        paint_under_points(_frame(), np.array([[400.0, 600.0]]), camera, double), [1])


def test_a_negative_double_gap_is_refused():
    with pytest.raises(ValueError, match="double_gap_m"):
        PaintTest(double_gap_m=-0.1)


def test_grain_passes_a_one_pixel_peak_but_not_a_stripe_wide_mean():
    """Coarse asphalt: road 90 with bright grains of 160 every 7 and 5 pixels. After the 3x3
    blur the brightest pixel near a point on bare road stands well over the road's median; the
    brightest mean over a stripe's width does not. A painted stripe passes either way."""
    camera = _rear_camera()
    frame = np.full((H, W, 3), 90, np.uint8)
    frame[:, ::7] = 160
    frame[:, ::5] = 160
    frame[:, 386:414] = 130  # a 28 px stripe at column 400 (15 cm at row 600)
    bare, painted = np.array([[800.0, 600.0]]), np.array([[400.0, 600.0]])
    assert paint_under_points(frame, bare, camera, PaintTest())[0] == 1  # grain taken for paint
    assert paint_under_points(frame, bare, camera, PaintTest(stripe_mean=True))[0] == 0
    assert paint_under_points(frame, painted, camera, PaintTest(stripe_mean=True))[0] == 1
