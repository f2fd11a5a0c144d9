"""The horizon of a photo from its lane lines' vanishing point (lanekeep/realcam/horizon.py)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from lanekeep.realcam.camera_file import camera_for_image
from lanekeep.realcam.horizon import horizon_row, vanishing_point

W, H = 1280, 720


def road(vp: tuple[float, float], bottoms=(150, 1130, 640), clutter: bool = False) -> np.ndarray:
    """Grey asphalt with white lines from the bottom row towards `vp` (stopping short of it),
    narrowing as painted lines do in perspective, so both their edges point at `vp`."""
    img = np.full((H, W, 3), 90, np.uint8)
    img[: int(vp[1])] = (200, 170, 120)  # sky
    for u in bottoms:
        edges = [np.array([u + du, H - 1.0]) for du in (-12, 12)]
        far = [e + 0.85 * (np.array(vp) - e) for e in edges]
        corners = np.array([edges[0], edges[1], far[1], far[0]]) * 16  # 4 fractional bits
        cv2.fillPoly(img, [np.round(corners).astype(np.int32)], (255, 255, 255),
                     cv2.LINE_AA, shift=4)
    if clutter:  # a pole and a horizontal guard rail: not lane lines
        cv2.line(img, (1200, 100), (1200, 600), (30, 30, 30), 6)
        cv2.line(img, (0, 560), (400, 560), (220, 220, 220), 5)
    return img


@pytest.mark.parametrize("vp", [(640.0, 260.0), (600.0, 430.0), (700.0, 330.0)])
def test_vanishing_point_of_converging_lines_within_a_few_pixels(vp):
    found = vanishing_point(road(vp, clutter=True))
    assert found is not None
    assert abs(found[0] - vp[0]) < 4.0 and abs(found[1] - vp[1]) < 4.0


def test_no_lines_no_horizon_and_the_camera_falls_back():
    blank = np.full((H, W, 3), 90, np.uint8)
    assert horizon_row(blank) is None
    _, _, horizon = camera_for_image(blank, None, horizon_fraction=0.5)
    assert horizon == 0.5 * H


def test_lines_on_one_side_only_are_no_consensus():
    img = np.full((H, W, 3), 90, np.uint8)
    for u in (100, 300):  # both rising to the right, parallel: no second side
        cv2.line(img, (u, H - 1), (u + 300, 300), (255, 255, 255), 8)
    assert horizon_row(img) is None


def test_the_camera_pitch_follows_the_found_horizon():
    camera, cam, horizon = camera_for_image(road((640.0, 280.0)), None)
    assert abs(horizon - 280.0) < 4.0
    assert abs(camera.horizon_row() - horizon) < 1.0  # the model puts the horizon there
