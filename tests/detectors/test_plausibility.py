"""Plausibility of a detected lane (detectors/plausibility.py) on synthetic estimates."""

from __future__ import annotations

import numpy as np
import pytest

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.plausibility import check, support_share, vehicle_cover

X_RANGE = (6.0, 40.0)


def lane(left, right, confidence=0.8, **kwargs) -> LaneEstimate:
    return LaneEstimate(True, 0.0, 6.0, None if left is None else np.asarray(left, float),
                        None if right is None else np.asarray(right, float), confidence,
                        **kwargs)


def test_a_straight_lane_of_usual_width_is_valid_and_keeps_its_confidence():
    verdict = check(lane([1.8, 0.0, 0.0], [-1.8, 0.0, 0.0]), X_RANGE)
    assert verdict.valid and verdict.reasons == () and verdict.confidence == pytest.approx(0.8)


def test_a_gentle_curve_is_valid():
    c2 = 1.0 / (2 * 500.0)  # 500 m radius, a highway curve
    assert check(lane([1.8, 0.02, c2], [-1.8, 0.02, c2]), X_RANGE).valid


def test_crossing_boundaries_are_invalid():
    verdict = check(lane([1.8, -0.1, 0.0], [-1.8, 0.1, 0.0]), X_RANGE)  # cross at x = 18 m
    assert not verdict.valid and verdict.confidence == 0.0
    assert any("cross at x = 1" in r for r in verdict.reasons)


def test_too_wide_or_too_narrow_lanes_are_invalid_and_unusual_widths_low_confidence():
    wide = check(lane([4.0, 0.0, 0.0], [-4.0, 0.0, 0.0]), X_RANGE)
    narrow = check(lane([0.8, 0.0, 0.0], [-0.8, 0.0, 0.0]), X_RANGE)
    assert not wide.valid and "8.0-8.0 m wide" in wide.reasons[0]
    assert not narrow.valid
    unusual = check(lane([2.7, 0.0, 0.0], [-2.7, 0.0, 0.0]), X_RANGE)  # 5.4 m
    assert unusual.valid and unusual.confidence == pytest.approx(0.4)


def test_too_curved_boundaries_are_invalid():
    c2 = 1.0 / (2 * 20.0)  # 20 m radius at the car: tighter than any road a dashcam shows
    verdict = check(lane([1.8, 0.0, c2], [-1.8, 0.0, c2]), X_RANGE)
    assert not verdict.valid
    # tightest in range at x = 6 m: (1 + 0.3^2)^1.5 * 20 m = 22.8 m
    assert any("left boundary bends to a 23 m radius" in r for r in verdict.reasons)


def test_boundaries_that_diverge_are_invalid():
    verdict = check(lane([1.5, 0.05, 0.0], [-1.5, 0.0, 0.0]), X_RANGE)  # 3.3 -> 5.0 m
    assert not verdict.valid and any("not parallel" in r for r in verdict.reasons)


def test_an_invalid_detection_stays_invalid_with_its_reason():
    verdict = check(LaneEstimate.invalid("no paint"), X_RANGE)
    assert not verdict.valid and verdict.reasons == ("detector: no paint",)


def test_support_on_a_vehicle_is_invalid():
    covered = np.zeros((100, 200), bool)
    covered[40:80, 100:160] = True
    points = {"left": np.array([[110.0, 50.0], [120.0, 60.0], [130.0, 70.0]]),
              "right": np.array([[20.0, 90.0]])}
    estimate = lane([1.8, 0.0, 0.0], [-1.8, 0.0, 0.0], image_points=points)
    share = support_share(estimate, covered)
    assert share == pytest.approx(0.75)
    verdict = check(estimate, X_RANGE, share)
    assert not verdict.valid and "75% of its support lies on a vehicle" in verdict.reasons
    assert support_share(estimate, None) is None


def test_vehicle_cover_finds_a_dark_band_as_wide_as_a_car():
    from lanekeep.detectors.config import load_config
    from lanekeep.realcam.camera_file import camera_for_image

    config = load_config(None)
    image = np.full((720, 1280, 3), 120, np.uint8)
    dash = config.dashcam
    camera, _, _ = camera_for_image(image, None, dash.hfov_deg, dash.height_m,
                                    dash.horizon_fraction, dash.min_horizon_fraction,
                                    dash.max_horizon_fraction)
    assert vehicle_cover(image, camera, config.preprocess) is None  # an empty road
    image[500:520, 560:720] = 5  # the shade under a car ~15 m ahead, 160 px wide
    covered = vehicle_cover(image, camera, config.preprocess)
    assert covered is not None and covered[450, 640] and not covered[450, 100]
