"""Road geometry: analytic positions, Frenet round trips, continuity, markings."""

import math

import numpy as np
import pytest

from lanekeep.geometry.road import MarkingStyle, Road, SegmentSpec

K40 = 1.0 / 40.0  # sharp-turn curvature, 1/m

ROADS = {
    "straight": [SegmentSpec("straight", 200.0)],
    "arc": [SegmentSpec("arc", 120.0, K40)],
    "clothoid": [SegmentSpec("clothoid", 80.0, 0.0, K40)],
    "mixed": [
        SegmentSpec("straight", 30.0),
        SegmentSpec("clothoid", 20.0, 0.0, K40),
        SegmentSpec("arc", 50.0, K40),
        SegmentSpec("clothoid", 40.0, K40, -K40),
        SegmentSpec("arc", 30.0, -K40),
        SegmentSpec("clothoid", 20.0, -K40, 0.0),
        SegmentSpec("straight", 30.0),
    ],
}


@pytest.fixture(params=sorted(ROADS))
def road(request):
    return Road(ROADS[request.param], start_xy=(5.0, -3.0), start_heading_rad=0.3)


def test_arc_matches_circle():
    road = Road([SegmentSpec("arc", 0.5 * math.pi * 40.0, K40)])
    np.testing.assert_allclose(road.position(road.length_m), [40.0, 40.0], atol=1e-9)
    s = np.linspace(0.0, road.length_m, 50)
    expected = np.stack([40.0 * np.sin(s / 40.0), 40.0 * (1.0 - np.cos(s / 40.0))], -1)
    np.testing.assert_allclose(road.position(s), expected, atol=1e-9)
    # A point r to the left lies on the circle of radius 40 - r.
    np.testing.assert_allclose(np.linalg.norm(road.position(s, 3.0) - [0.0, 40.0], axis=-1), 37.0)


def test_clothoid_matches_fresnel_integrals():
    special = pytest.importorskip("scipy.special")
    length, k1 = 80.0, K40
    road = Road([SegmentSpec("clothoid", length, 0.0, k1)])
    a = math.sqrt(length / k1)  # clothoid parameter: kappa(u) = u / a^2
    u = np.linspace(0.0, length, 41)
    sin_i, cos_i = special.fresnel(u / (a * math.sqrt(math.pi)))
    expected = a * math.sqrt(math.pi) * np.stack([cos_i, sin_i], -1)
    np.testing.assert_allclose(road.position(u), expected, atol=1e-9)
    assert road.heading_at(length) == pytest.approx(0.5 * k1 * length)


def test_frenet_round_trip_within_1mm(road):
    rng = np.random.default_rng(1)
    # Uniform along the road, plus points straddling each join and beyond both ends.
    joins = np.array([a for a, _ in road.segment_bounds()[1:]] + [0.0, road.length_m])
    s = np.concatenate(
        [
            rng.uniform(0.0, road.length_m, 4000),
            (joins[:, None] + rng.uniform(-1.5, 1.5, (len(joins), 50))).ravel(),
            rng.uniform(-20.0, 0.0, 50),
            rng.uniform(road.length_m, road.length_m + 20.0, 50),
        ]
    )
    r = rng.uniform(-8.0, 8.0, s.size)
    p = road.position(s, r)
    s2, r2 = road.local_coordinates(p)
    assert np.max(np.abs(s2 - s)) < 1e-3
    assert np.max(np.abs(r2 - r)) < 1e-3
    assert np.max(np.linalg.norm(road.position(s2, r2) - p, axis=-1)) < 1e-3


def test_local_coordinates_of_world_points(road):
    """Points drawn in the world (not from position()) map back onto themselves."""
    rng = np.random.default_rng(2)
    centre = road.position(rng.uniform(0.0, road.length_m, 2000))
    p = centre + rng.uniform(-5.5, 5.5, centre.shape)
    s, r = road.local_coordinates(p)
    assert np.max(np.linalg.norm(road.position(s, r) - p, axis=-1)) < 1e-3
    # The foot point is the nearest: its tangent is perpendicular to the offset.
    heading = road.heading_at(s)
    d = p - road.position(s)
    along = d[:, 0] * np.cos(heading) + d[:, 1] * np.sin(heading)
    assert np.max(np.abs(along)) < 1e-6


def test_vectorised_shapes_and_scalars():
    road = Road(ROADS["mixed"])
    s = np.linspace(0.0, 100.0, 12).reshape(3, 4)
    p = road.position(s, 1.0)
    assert p.shape == (3, 4, 2)
    s2, r2 = road.local_coordinates(p)
    assert s2.shape == r2.shape == (3, 4)
    np.testing.assert_allclose(r2, 1.0, atol=1e-9)
    s1, r1 = road.local_coordinates(p[1, 2])
    assert isinstance(s1, float) and s1 == pytest.approx(s[1, 2], abs=1e-9)
    assert isinstance(road.heading_at(10.0), float)
    assert isinstance(road.curvature_at(10.0), float)


def test_heading_continuous_and_tangent_to_position(road):
    for join, _ in road.segment_bounds()[1:]:
        assert road.heading_at(join - 1e-6) == pytest.approx(road.heading_at(join + 1e-6), abs=1e-6)
    # The heading is the direction of dP/ds (central differences), on and beyond the road.
    s = np.linspace(-5.0, road.length_m + 5.0, 500)
    h = 1e-4
    d = road.position(s + h) - road.position(s - h)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1) / (2 * h), 1.0, atol=1e-6)
    direction = np.arctan2(d[:, 1], d[:, 0])
    err = (direction - road.heading_at(s) + math.pi) % (2 * math.pi) - math.pi
    assert np.max(np.abs(err)) < 1e-6


def test_curvature_is_derivative_of_heading(road):
    bounds = road.segment_bounds()
    s = np.concatenate([np.linspace(a + 0.01, b - 0.01, 100) for a, b in bounds])
    h = 1e-4
    numeric = (road.heading_at(s + h) - road.heading_at(s - h)) / (2 * h)
    np.testing.assert_allclose(road.curvature_at(s), numeric, atol=1e-7)
    assert road.curvature_at(-1.0) == 0.0 and road.curvature_at(road.length_m + 1.0) == 0.0


def test_total_turn_angle():
    road = Road(ROADS["mixed"])
    # clothoid 0->k: k L / 2; arc: k L; clothoid k->-k: 0.
    expected = K40 * 20 / 2 + K40 * 50 - K40 * 30 - K40 * 20 / 2
    assert road.heading_at(road.length_m) == pytest.approx(expected, abs=1e-12)
    assert road.segment_bounds()[2] == (50.0, 100.0)


def test_lane_geometry():
    road = Road(ROADS["straight"], n_lanes=3, lane_width_m=3.5)
    assert [road.boundary_r(i) for i in range(4)] == pytest.approx([-5.25, -1.75, 1.75, 5.25])
    assert [road.lane_center_r(i) for i in range(3)] == pytest.approx([-3.5, 0.0, 3.5])
    with pytest.raises(IndexError):
        road.lane_center_r(3)


def _pieces(style, length=200.0, seed=0, segments=None):
    road = Road(
        segments or [SegmentSpec("straight", length)],
        n_lanes=1,
        markings=[style, MarkingStyle("none")],
        rng_seed=seed,
    )
    return road.marking_pieces()


def test_dashed_pattern_lengths():
    pieces = _pieces(MarkingStyle("dashed", dash_m=3.0, gap_m=9.0), length=100.0)
    starts = np.array([p.s_start_m for p in pieces])
    lengths = np.array([p.s_end_m - p.s_start_m for p in pieces])
    assert len(pieces) == 9  # dashes start at 0, 12, ..., 96
    np.testing.assert_allclose(np.diff(starts), 12.0)
    np.testing.assert_allclose(lengths, 3.0)
    cut = _pieces(MarkingStyle("dashed", dash_m=3.0, gap_m=9.0), length=98.0)
    assert cut[-1].s_end_m == pytest.approx(98.0)  # the last dash ends with the road
    assert all(p.boundary == 0 and p.r_m == pytest.approx(-1.85) for p in pieces)


def test_solid_split_at_joins_and_20m():
    segs = [SegmentSpec("straight", 45.0), SegmentSpec("arc", 30.0, 0.01)]
    pieces = _pieces(MarkingStyle("solid"), segments=segs)
    edges = sorted({p.s_start_m for p in pieces} | {p.s_end_m for p in pieces})
    assert 45.0 in edges and edges[0] == 0.0 and edges[-1] == 75.0
    assert max(p.s_end_m - p.s_start_m for p in pieces) <= 20.0
    assert sum(p.s_end_m - p.s_start_m for p in pieces) == pytest.approx(75.0)


def test_none_double_and_worn():
    assert _pieces(MarkingStyle("none")) == []
    double = _pieces(MarkingStyle("double", width_m=0.1, double_gap_m=0.12))
    rs = sorted({round(p.r_m, 9) for p in double})
    assert rs == pytest.approx([-1.85 - 0.11, -1.85 + 0.11])  # centres (gap + width) apart
    assert len(double) == 2 * len(_pieces(MarkingStyle("solid")))

    worn = MarkingStyle("worn", wear=0.4)
    a, b, c = _pieces(worn, seed=3), _pieces(worn, seed=3), _pieces(worn, seed=4)
    assert a == b and a != c
    painted = sum(p.s_end_m - p.s_start_m for p in a)
    assert 0.45 * 200.0 < painted < 0.75 * 200.0  # about 1 - wear of the line
    assert all(0.0 < p.brightness < 1.0 for p in a)
    assert len({p.brightness for p in a}) > 10


def test_default_markings_and_validation():
    road = Road(ROADS["straight"], n_lanes=2)
    assert [m.kind for m in road.markings] == ["solid", "dashed", "solid"]
    assert [p.boundary for p in road.marking_pieces()] == sorted(
        p.boundary for p in road.marking_pieces()
    )
    with pytest.raises(ValueError, match="kind"):
        SegmentSpec("spiral", 10.0)
    with pytest.raises(ValueError, match="length_m"):
        SegmentSpec("arc", 0.0, 0.01)
    with pytest.raises(ValueError, match="wear"):
        MarkingStyle("worn", wear=1.5)
    with pytest.raises(ValueError, match="marking styles"):
        Road(ROADS["straight"], n_lanes=2, markings=[MarkingStyle()] * 2)
