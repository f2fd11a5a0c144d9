"""One period's motion applied to ground points, checked against circles and against the tracks'
polynomial transform (estimators/kalman.py), which moves the same points."""

import numpy as np
import pytest

from lanekeep.estimators.kalman import ego_motion_transform
from lanekeep.geometry.vehicle_motion import PeriodMotion


def test_a_straight_drive_moves_points_back_by_the_distance_driven():
    motion = PeriodMotion.of(speed_mps=20.0, yaw_rate_rps=0.0, dt_s=0.1)
    moved = motion.carry(np.array([[-3.0, 1.8], [5.0, -1.7]]))
    np.testing.assert_allclose(moved, [[-5.0, 1.8], [3.0, -1.7]], atol=1e-12)


def test_a_quarter_circle_to_the_left_keeps_the_circles_centre_on_the_left():
    radius, speed = 10.0, 5.0
    dt = (np.pi / 2) * radius / speed
    motion = PeriodMotion.of(speed, speed / radius, dt)
    assert (motion.tx_m, motion.ty_m) == pytest.approx((radius, radius))
    assert motion.yaw_rad == pytest.approx(np.pi / 2)
    np.testing.assert_allclose(motion.carry(np.array([[0.0, radius]])), [[0.0, radius]],
                               atol=1e-9)
    # the start point now lies behind the car and to its left, on the same circle
    np.testing.assert_allclose(motion.carry(np.array([[0.0, 0.0]])), [[-radius, radius]],
                               atol=1e-9)


@pytest.mark.parametrize("lateral_speed", [0.0, 0.4])
def test_carried_points_refit_give_the_tracks_transform(lateral_speed):
    coefficients = np.array([1.7, 0.02, 0.004])
    speed, yaw_rate, dt = 18.0, 0.25, 0.1
    a, b = ego_motion_transform(coefficients, speed, yaw_rate, dt, 30.0, 16, lateral_speed)
    motion = PeriodMotion.of(speed, yaw_rate, dt, lateral_speed)
    x_old = motion.tx_m + np.linspace(0.0, 30.0, 16)
    y_old = np.polynomial.polynomial.polyval(x_old, coefficients)
    moved = motion.carry(np.stack([x_old, y_old], -1))
    refit = np.polynomial.polynomial.polyfit(moved[:, 0], moved[:, 1], 2)
    # the transform takes each point's new x at the curve's mean, as the refit does
    np.testing.assert_allclose(a @ coefficients + b, refit, rtol=1e-6, atol=1e-9)
