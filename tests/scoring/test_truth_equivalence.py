"""The truth's cheaper paths give the numbers of the plain ones, bit for bit: the Newton solve
of `line_points` on `Road.geometry_at`, and `StepTruth.centre` fitted only when read."""

import functools
import math

import numpy as np
import pytest

from lanekeep.geometry.road import Road, SegmentSpec
from lanekeep.scoring.metrics import ADE_POINTS_M
from lanekeep.scoring.step_truth import StepTruth, step_truth
from lanekeep.scoring.truth import (
    frenet,
    lane_centre_at,
    lane_centre_fit,
    lane_offsets,
    line_points,
)

K40 = 1.0 / 40.0
ROAD = Road([SegmentSpec("straight", 30.0), SegmentSpec("clothoid", 20.0, 0.0, K40),
             SegmentSpec("arc", 60.0, K40), SegmentSpec("clothoid", 40.0, K40, -K40),
             SegmentSpec("straight", 40.0)], start_xy=(5.0, -3.0), start_heading_rad=0.3)


def _poses(n: int = 12) -> list[tuple[float, float, float]]:
    rng = np.random.default_rng(9)
    out = []
    for s in rng.uniform(-3.0, ROAD.length_m - 20.0, n):
        x, y = ROAD.position(s, ROAD.lane_center_r(0) + rng.uniform(-0.8, 0.8))
        out.append((float(x), float(y), float(ROAD.heading_at(s)) + rng.uniform(-0.08, 0.08)))
    return out


def _line_points_reference(road, x, y, yaw, r_line, xs, s_car):
    """`line_points` as it was written before `Road.geometry_at`: three calls a step."""
    xs = np.atleast_1d(np.asarray(xs, dtype=float))
    p = np.array([x, y], dtype=float)
    f = np.array([math.cos(yaw), math.sin(yaw)])
    left = np.array([-f[1], f[0]])
    s = s_car + xs
    for _ in range(30):
        d = road.position(s, r_line) - p
        g = d @ f - xs
        slope = (1.0 - road.curvature_at(s) * r_line) * np.cos(road.heading_at(s) - yaw)
        ds = g / np.maximum(slope, 0.1)
        s = s - ds
        if np.all(np.abs(ds) < 1e-10):
            break
    d = road.position(s, r_line) - p
    return np.stack([d @ f, d @ left], axis=-1)


@pytest.mark.parametrize("r_line", [ROAD.boundary_r(0), ROAD.lane_center_r(0), ROAD.boundary_r(1)])
def test_line_points_are_those_of_the_three_call_newton(r_line):
    xs = np.concatenate([np.linspace(0.0, 30.0, 61), [-15.0, -4.0, 4.0, 6.5, 40.0]])
    for x, y, yaw in _poses():
        s_car, _ = frenet(ROAD, (x, y))
        got = line_points(ROAD, x, y, yaw, r_line, xs, s_car=s_car)
        assert np.array_equal(got, _line_points_reference(ROAD, x, y, yaw, r_line, xs, s_car))


def test_step_truth_is_the_eager_truth_with_the_centre_fitted_when_read():
    scored, drawn = [4.0, 6.25, -5.0, 12.0], [0.0, 4.0, 8.0]
    for sensed, after in zip(_poses(), _poses()[1:], strict=False):
        truth = step_truth(ROAD, 0, sensed, after, scored, np.asarray(ADE_POINTS_M), drawn)
        assert "centre" not in truth.__dict__  # nothing fitted until read
        centre, s_car = lane_centre_fit(ROAD, *sensed, 0)  # what was computed at once
        ade = lane_centre_at(ROAD, *sensed, 0, np.asarray(ADE_POINTS_M), s_car=s_car)
        keys = sorted({round(x, 3) for x in scored + drawn})
        offsets = lane_offsets(ROAD, *sensed, 0, sorted({round(x, 3) for x in scored}),
                               s_car=s_car)
        assert np.array_equal(truth.centre_at_ade_m, ade)
        assert sorted(truth.offsets_m) == keys
        for x, v in zip(sorted({round(x, 3) for x in scored}), offsets, strict=True):
            assert truth.offsets_m[x] == float(v)
        assert truth.car_offset_m == float(lane_offsets(ROAD, *after, 0, [0.0])[0])
        first = truth.centre
        assert np.array_equal(first, centre)
        assert truth.centre is first  # fitted once


def test_a_step_truth_is_still_frozen_and_its_centre_cannot_be_set():
    sensed = _poses(1)[0]
    truth = step_truth(ROAD, 0, sensed, sensed, [4.0], np.asarray(ADE_POINTS_M))
    with pytest.raises(AttributeError):
        truth.car_offset_m = 0.0
    assert isinstance(truth, StepTruth)
    assert isinstance(truth.centre_fit, functools.partial)
    assert "centre_fit" not in repr(truth)
