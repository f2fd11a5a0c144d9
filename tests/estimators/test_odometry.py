"""Dead reckoning from wheel speed and yaw rate (estimators/odometry.py)."""

import math

import numpy as np
import pytest

from lanekeep.estimators.odometry import DeadReckoning


def test_a_constant_turn_dead_reckons_onto_its_circle():
    """15 m/s at 0.375 rad/s is a 40 m radius; 100 steps of 0.1 s sweep 3.75 rad. The
    reference point, 1.4 m ahead of the rolling rear axle, keeps the radius
    sqrt(R_rear^2 + 1.4^2) about the turn centre."""
    dt, v, r, lever = 0.1, 15.0, 0.375, 1.4
    odometry = DeadReckoning(dt, lever)
    poses = [odometry.update(v, r).pose for _ in range(101)]
    xy = np.array([p[:2] for p in poses])
    # The turn centre lies to the left of the start, at the rear-axle radius v / r from the
    # rear axle (which starts 1.4 m behind the reference point).
    rear_radius = v / r
    centre = np.array([-lever, rear_radius])
    radius = np.hypot(rear_radius, lever)
    np.testing.assert_allclose(np.linalg.norm(xy - centre, axis=1), radius, atol=0.05)
    assert poses[-1][2] == pytest.approx(100 * r * dt)
    assert odometry.travelled_m == pytest.approx(100 * v * dt)


def test_sideslip_is_estimated_from_the_yaw_rate_not_read():
    odometry = DeadReckoning(0.1, 1.4)
    ego = odometry.update(15.0, 0.2)
    assert ego.lateral_speed_mps == pytest.approx(0.28)
    assert ego.pose == (0.0, 0.0, 0.0)  # the first sample only sets the origin


def test_a_bad_sample_repeats_the_last_good_one():
    odometry = DeadReckoning(0.1, 1.4)
    odometry.update(10.0, 0.0)
    ego = odometry.update(math.nan, 0.0)
    assert ego.speed_mps == 10.0
    assert ego.pose[0] == pytest.approx(1.0)


def test_reset_returns_to_the_origin():
    odometry = DeadReckoning(0.1, 1.4)
    for _ in range(5):
        odometry.update(10.0, 0.1)
    odometry.reset()
    assert odometry.pose == (0.0, 0.0, 0.0) and odometry.travelled_m == 0.0
