"""Odometry alignment: a model's past lane points, carried to where the reference looks now."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lanekeep.estimators.alignment import OdometryAlignedHistory


def _drive(history: OdometryAlignedHistory, heading: float, centre_y: float, steps: int,
           step_m: float = 1.5) -> tuple[float, float, float]:
    """The car drives straight along `heading`, a lane centre `centre_y` to its left; each step
    the model reports that centre at 4 m ahead. Returns the final pose."""
    c, s = math.cos(heading), math.sin(heading)
    pose = (0.0, 0.0, heading)
    for k in range(steps):
        pose = (k * step_m * c, k * step_m * s, heading)
        history.push(pose, [np.array([centre_y, 0.0, 0.0])], [0.01], look_ahead_m=4.0)
    return pose


@pytest.mark.parametrize("heading", [0.0, 0.7, -2.5])
def test_a_straight_lane_is_found_behind_the_car_at_its_offset(heading):
    history = OdometryAlignedHistory(1)
    pose = _drive(history, heading, centre_y=0.3, steps=12)
    offsets, variances = history.offsets_at(pose, -4.0)
    assert offsets[0] == pytest.approx(-0.3, abs=1e-12)
    assert variances[0] == pytest.approx(0.01)


def test_a_point_the_model_never_saw_has_no_offset():
    history = OdometryAlignedHistory(1)
    pose = _drive(history, 0.0, centre_y=0.3, steps=3)  # points at x = 4, 5.5, 7 world
    assert history.offsets_at(pose, -4.0) == ([None], [None])  # behind the oldest point
    one = OdometryAlignedHistory(1)
    _drive(one, 0.0, centre_y=0.3, steps=1)
    assert one.offsets_at((0.0, 0.0, 0.0), 4.0) == ([None], [None])  # needs two points


def test_the_car_turning_away_from_stored_points_changes_their_offset():
    """The stored points are world points: a car now yawed by 0.1 rad sees the same line at
    the offset its new heading gives, which a car-relative history would miss."""
    history = OdometryAlignedHistory(1)
    pose = _drive(history, 0.0, centre_y=0.0, steps=12)
    x, y, _ = pose
    offsets, _ = history.offsets_at((x, y, 0.1), -4.0)
    # The line y = 0 seen from a car at the origin yawed 0.1 rad, 4 m behind along its axis:
    # its lateral coordinate there is 4 tan(0.1) to the car's left of the line.
    assert offsets[0] == pytest.approx(-4.0 * math.tan(0.1), abs=1e-3)


def test_missing_estimates_are_skipped_and_reset_forgets():
    history = OdometryAlignedHistory(2)
    for k in range(6):
        history.push((1.5 * k, 0.0, 0.0), [np.array([0.2, 0.0, 0.0]), None], [0.01, None], 4.0)
    offsets, _ = history.offsets_at((7.5, 0.0, 0.0), -1.0)
    assert offsets[0] == pytest.approx(-0.2) and offsets[1] is None
    history.reset()
    assert history.offsets_at((7.5, 0.0, 0.0), -1.0) == ([None, None], [None, None])
