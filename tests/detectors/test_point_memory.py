"""The observer's memory of painted points: carried by the car's motion, aged out, and never
carried without the motion (a still frame's points cannot be placed in the next)."""

import numpy as np

from lanekeep.detectors.point_memory import PointMemory
from lanekeep.geometry.vehicle_motion import PeriodMotion

STRAIGHT_2M = PeriodMotion.of(speed_mps=20.0, yaw_rate_rps=0.0, dt_s=0.1)


def test_points_move_back_by_the_distance_driven_and_keep_their_slots():
    memory = PointMemory(frames=3, max_range_m=30.0)
    memory.remember(np.array([[-4.0, 1.8], [-6.0, -1.7]]), np.array([0, 1]))
    memory.move(STRAIGHT_2M)
    xy, slots = memory.recall()
    np.testing.assert_allclose(xy, [[-6.0, 1.8], [-8.0, -1.7]])
    np.testing.assert_array_equal(slots, [0, 1])


def test_points_older_than_the_memory_or_out_of_range_are_dropped():
    memory = PointMemory(frames=2, max_range_m=6.5)
    memory.remember(np.array([[-3.0, 0.0], [-1.0, 0.0]]), np.array([0, 0]))
    memory.move(STRAIGHT_2M)
    memory.remember(np.zeros((0, 2)), np.zeros(0))
    memory.move(STRAIGHT_2M)
    xy, _ = memory.recall()
    np.testing.assert_allclose(xy, [[-5.0, 0.0]])  # -3 - 4 = -7 m: beyond 6.5 m
    memory.remember(np.zeros((0, 2)), np.zeros(0))
    memory.move(STRAIGHT_2M)
    assert len(memory.recall()[0]) == 0  # three frames old: beyond `frames`


def test_without_the_motion_nothing_is_carried():
    memory = PointMemory(frames=5, max_range_m=30.0)
    memory.remember(np.array([[-4.0, 1.8]]), np.array([0]))
    assert len(memory.recall()[0]) == 0  # no move since that frame
    memory.remember(np.array([[-5.0, 1.8]]), np.array([0]))  # the first is forgotten
    memory.move(STRAIGHT_2M)
    np.testing.assert_allclose(memory.recall()[0], [[-7.0, 1.8]])


def test_no_memory_keeps_nothing():
    memory = PointMemory(frames=0, max_range_m=30.0)
    memory.remember(np.array([[-4.0, 1.8]]), np.array([0]))
    memory.move(STRAIGHT_2M)
    assert len(memory.recall()[0]) == 0
