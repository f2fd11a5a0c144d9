"""The observer's look under each point: a paint-wide ridge brighter than the road on both sides
is paint; flat road, a one-sided edge (a shoulder) and the sky are not."""

import math

import numpy as np

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
