"""Choosing the car's lane among every line a classical model found (detectors/lane_lines.py)."""

import dataclasses

import numpy as np
import pytest

from lanekeep.detectors.boundaries import Boundary
from lanekeep.detectors.config import LaneRules
from lanekeep.detectors.lane_lines import aligned, choose_lanes, distinct, parallel_lines

RULES = LaneRules()
WIDTH = RULES.lane_width_m
X_AT = 5.0


def line(y0: float, slope: float = 0.0, x=(5.0, 20.0), n: int = 40) -> Boundary:
    """A straight line y = y0 + slope * x found over `x` (its points on it)."""
    xs = np.linspace(*x, n)
    coeffs = np.array([y0, slope, 0.0])
    return Boundary(coeffs, n, float(x[1] - x[0]), np.stack([xs, y0 + slope * xs], 1))


def ys(*lines) -> list[float | None]:
    return [None if b is None else round(float(b.lane.y(X_AT)), 3) for b in lines]


def test_the_pair_around_the_car_is_chosen_and_the_neighbours_lines_are_others():
    found = [line(y) for y in (WIDTH * 1.5, WIDTH / 2, -WIDTH / 2, -WIDTH * 1.5, -5.9)]
    lanes = choose_lanes(found, X_AT, RULES, WIDTH, 0.4)
    assert ys(lanes.left, lanes.right) == pytest.approx([WIDTH / 2, -WIDTH / 2])
    # The lines a lane width out are the neighbours'; one 2.3 m past the last is not a line
    # of a lane (a road's edge on grass, a barrier's foot).
    assert sorted(ys(*lanes.others)) == pytest.approx([-WIDTH * 1.5, WIDTH * 1.5])


def test_a_car_passing_over_a_line_is_in_the_lane_that_holds_its_centre():
    found = [line(y) for y in (WIDTH - 0.1, 0.1, -WIDTH + 0.1)]
    lanes = choose_lanes(found, X_AT, RULES, WIDTH, 0.4)
    assert ys(lanes.left, lanes.right) == pytest.approx([0.1, -WIDTH + 0.1])
    mirrored = choose_lanes([line(-b.coeffs[0]) for b in found], X_AT, RULES, WIDTH, 0.4)
    assert ys(mirrored.left, mirrored.right) == pytest.approx([WIDTH - 0.1, -0.1])


def test_with_min_half_width_a_line_under_the_wheels_is_not_the_cars():
    """In dappled shade a model finds its right line and a sun fleck found as a line 0.3 m
    beside the car, not its left line: by default the fleck is the nearest line on the left
    and goes on as a boundary (as a line the car passes over does, the test above); with
    `min_half_width` set it is none, and the right line alone goes on. A line just outside
    the limit still is a boundary."""
    right = line(-WIDTH / 2 + 0.2)
    found = [line(0.3, n=20), right]
    lanes = choose_lanes(found, X_AT, RULES, WIDTH, 0.4)
    assert ys(lanes.left, lanes.right) == pytest.approx([0.3, -WIDTH / 2 + 0.2])
    rules = dataclasses.replace(RULES, min_half_width=0.25)
    lanes = choose_lanes(found, X_AT, rules, WIDTH, 0.4)
    assert lanes.left is None and lanes.right is right
    edge = 0.25 * WIDTH + 0.01
    lanes = choose_lanes([line(edge), line(edge - WIDTH)], X_AT, rules, WIDTH, 0.4)
    assert ys(lanes.left, lanes.right) == pytest.approx([edge, edge - WIDTH])


def test_min_half_width_must_lie_below_max_half_width():
    with pytest.raises(ValueError, match="min_half_width"):
        LaneRules(min_half_width=1.2)
    with pytest.raises(ValueError, match="min_half_width"):
        LaneRules(min_half_width=-0.1)


def test_a_crack_between_the_car_and_its_line_is_skipped_for_a_pair_a_lane_wide():
    crack = line(0.9, x=(5.0, 9.0), n=8)  # short and weak, nearer than the line
    found = [line(WIDTH / 2), crack, line(-WIDTH / 2)]
    lanes = choose_lanes(found, X_AT, RULES, WIDTH, 0.4)
    assert ys(lanes.left, lanes.right) == pytest.approx([WIDTH / 2, -WIDTH / 2])


def test_a_line_further_out_than_a_boundary_can_be_is_never_the_cars():
    lanes = choose_lanes([line(WIDTH * 1.5)], X_AT, RULES, WIDTH, 0.4)
    assert lanes.left is None and lanes.right is None


def test_lines_found_twice_are_one_and_lines_across_the_lane_are_none():
    strong, twin = line(1.7, n=60), line(1.85, n=20)
    assert [b is strong for b in distinct([twin, strong], X_AT, 0.4)] == [True]
    across = line(1.0, slope=-0.3)  # a track that jumped from one line to the next
    kept = parallel_lines([line(1.7), line(-1.8), line(5.3), across], X_AT,
                          RULES.max_divergence_deg)
    assert len(kept) == 3 and all(b is not across for b in kept)


def test_a_lone_dash_takes_the_direction_of_the_longest_line():
    long = line(-1.8, slope=0.02, x=(5.0, 20.0))
    dash = line(1.8, slope=-0.05, x=(12.0, 15.0), n=6)  # its own slope is off
    lanes = aligned(choose_lanes([long, dash], X_AT, RULES, WIDTH, 0.4), RULES)
    assert lanes.left.coeffs[1:] == pytest.approx(long.coeffs[1:])
    # It keeps its own position where its points are (weighted to the nearest of them).
    assert lanes.left.lane.y(12.0) == pytest.approx(dash.lane.y(12.0), abs=0.1)
