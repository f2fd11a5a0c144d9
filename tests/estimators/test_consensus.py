"""Corroboration between detectors, and the tracker restart it triggers."""

import numpy as np
import pytest

from lanekeep.estimators.consensus import corroborated
from lanekeep.estimators.kalman import LaneTracker, TrackerConfig, UpdateStatus

R = np.diag(np.square([0.05, 0.01, 4e-4]))


def test_agreeing_detections_corroborate_and_a_wild_one_does_not():
    lane = np.array([0.1, 0.01, 1e-3])
    wild = np.array([-1.7, 0.31, 0.0])  # a boundary bent onto a passing car
    agree = corroborated([lane, lane + [0.03, -0.004, 1e-4], wild], R)
    assert agree == [True, True, False]


def test_missing_detections_corroborate_nothing():
    assert corroborated([None, np.zeros(3)], R) == [False, False]
    assert corroborated([np.zeros(3)], R) == [False]


def test_far_curvature_disagreement_alone_does_not_break_agreement():
    """Two fits of one arc differ most in c2 far ahead; near position and heading agree."""
    a = np.array([0.0, 0.0, 0.0100])
    b = np.array([0.0, 0.0, 0.0112])  # 12% apart in curvature: 0.3 m at 15 m, 1 m at 30 m
    assert corroborated([a, b], R, points_m=(5.0, 15.0)) == [True, True]


def test_each_detector_brings_its_own_noise():
    """S = R_a + R_b: a gap that two noisy detectors explain is too wide for two steady ones,
    and a wrong shape of R is refused."""
    a, b = np.zeros(3), np.array([0.25, 0.0, 0.0])
    noisy, steady = 4.0 * R, R / 16.0
    assert corroborated([a, b], [noisy, noisy]) == [True, True]
    assert corroborated([a, b], [steady, steady]) == [False, False]
    assert corroborated([a, b], np.stack([steady, noisy])) == corroborated([a, b], [noisy, steady])
    with pytest.raises(ValueError, match="one per measurement"):
        corroborated([a, b, a], [R, R])


def test_restart_replaces_a_lagging_track_with_the_measurement():
    tracker = LaneTracker(TrackerConfig())
    tracker.update_coefficients([0.0, 0.0, 0.0])
    for _ in range(5):
        tracker.predict(0.1, 15.0, 0.0)
        tracker.update_coefficients([0.0, 0.0, 0.0])
    far = np.array([-0.6, 0.05, 0.01])
    tracker.predict(0.1, 15.0, 0.0)
    assert tracker.update_coefficients(far).status is UpdateStatus.GATED
    result = tracker.restart(far)
    assert result.status is UpdateStatus.RESTARTED
    np.testing.assert_allclose(tracker.coefficients, far, atol=1e-3)
    assert tracker.missed_steps == 0


def test_full_measurement_covariance_is_used_and_checked():
    cov = ((3e-3, -5e-4, 2e-5), (-5e-4, 1e-4, -4e-6), (2e-5, -4e-6, 2e-7))
    np.testing.assert_allclose(TrackerConfig(coefficient_covariance=cov).coefficient_r, cov)
    with pytest.raises(ValueError, match="positive-definite"):
        TrackerConfig(coefficient_covariance=((1, 2, 0), (2, 1, 0), (0, 0, 1)))
