"""`Road.geometry_at`: position, heading and curvature from one table search, bit for bit the
numbers of the three separate calls (the Newton solves of the truth and of the Frenet
projection use it in their inner loops)."""

import math

import numpy as np
import pytest

from lanekeep.geometry.road import Road, SegmentSpec

K40 = 1.0 / 40.0

ROADS = {
    "mixed": [
        SegmentSpec("straight", 30.0),
        SegmentSpec("clothoid", 20.0, 0.0, K40),
        SegmentSpec("arc", 50.0, K40),
        SegmentSpec("clothoid", 40.0, K40, -K40),
        SegmentSpec("arc", 30.0, -K40),
        SegmentSpec("clothoid", 20.0, -K40, 0.0),
        SegmentSpec("straight", 30.0),
    ],
    # Lengths that are no multiple of the table step, a segment shorter than one step, and
    # one far from the start, where a metre holds fewer floats.
    "odd": [
        SegmentSpec("arc", 0.03, -0.01),
        SegmentSpec("straight", 12.345678),
        SegmentSpec("clothoid", 0.1000001, 0.0, 0.02),
        SegmentSpec("arc", 7.77, 0.02),
        SegmentSpec("straight", 9000.0),
        SegmentSpec("clothoid", 33.3, 0.02, -0.03),
    ],
}


@pytest.fixture(params=sorted(ROADS))
def road(request):
    return Road(ROADS[request.param], start_xy=(5.0, -3.0), start_heading_rad=0.3)


def _queries(road: Road) -> np.ndarray:
    """Every table node and segment start, the floats either side of each, the ends and
    beyond, and random s."""
    rng = np.random.default_rng(3)
    edges = np.concatenate([road._node_s, road._s0, [0.0, road.length_m]])
    near = np.concatenate([edges, np.nextafter(edges, -np.inf), np.nextafter(edges, np.inf)])
    outside = [-50.0, -1e-9, -0.0, road.length_m + 1e-9, road.length_m + 40.0]
    return np.concatenate([near, outside, rng.uniform(-5.0, road.length_m + 5.0, 2000)])


def _same(a, b) -> bool:
    return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)


def test_geometry_at_is_the_three_calls_bit_for_bit(road):
    s = _queries(road)
    for r in (0.0, 1.85, -5.55):
        xy, heading, curvature = road.geometry_at(s, r)
        assert _same(xy, road.position(s, r))
        assert _same(heading, road.heading_at(s))
        assert _same(curvature, road.curvature_at(s))


def test_geometry_at_broadcasts_as_position_does(road):
    s = np.linspace(-3.0, road.length_m + 3.0, 7)
    r = np.array([-1.85, 0.0, 1.85])
    xy, heading, curvature = road.geometry_at(s[None, :], r[:, None])
    assert _same(xy, road.position(s[None, :], r[:, None]))
    assert heading.shape == curvature.shape == (3, 7)
    for row in range(3):
        assert _same(heading[row], road.heading_at(s))
        assert _same(curvature[row], road.curvature_at(s))
    one = road.geometry_at(12.5)
    assert _same(one[0], road.position(12.5))
    assert float(one[1]) == road.heading_at(12.5) and float(one[2]) == road.curvature_at(12.5)


def _local_coordinates_reference(road: Road, xy: np.ndarray):
    """`Road.local_coordinates` as it was written before `geometry_at`: three calls a step."""
    p = np.asarray(xy, dtype=float).reshape(-1, 2)
    d2 = ((p[:, None, :] - road._coarse_xy[None, :, :]) ** 2).sum(-1)
    s = road._coarse_s[np.argmin(d2, axis=1)]
    for _ in range(12):
        d = p - road.position(s)
        th = np.asarray(road.heading_at(s))
        t = np.stack([np.cos(th), np.sin(th)], -1)
        along = (d * t).sum(-1)
        r = d[:, 1] * t[:, 0] - d[:, 0] * t[:, 1]
        slope = np.maximum(1.0 - np.asarray(road.curvature_at(s)) * r, 0.2)
        ds = along / slope
        s = s + ds
        if np.all(np.abs(ds) < 1e-10):
            break
    d = p - road.position(s)
    th = np.asarray(road.heading_at(s))
    return s, d[:, 1] * np.cos(th) - d[:, 0] * np.sin(th)


def test_local_coordinates_are_those_of_the_three_call_newton(road):
    rng = np.random.default_rng(5)
    s = rng.uniform(-2.0, road.length_m + 2.0, 300)
    r = rng.uniform(-6.0, 6.0, 300)
    xy = road.position(s, r) + rng.normal(0.0, 1e-3, (300, 2))
    got_s, got_r = road.local_coordinates(xy)
    want_s, want_r = _local_coordinates_reference(road, xy)
    assert _same(got_s, want_s) and _same(got_r, want_r)
    one = road.local_coordinates(xy[7])
    assert one == (float(want_s[7]), float(want_r[7]))
    assert math.isfinite(one[0])
