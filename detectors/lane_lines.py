"""Which of the lines a classical model found bound the car's lane, and which are the others.

Both classical models find every line they can across their bird's-eye view (the view is
12 m wide: the car's lane and one neighbour each side). Choosing the car's pair from all of
them, rather than searching each side for the nearest line only, lets the lane's geometry
decide: the two boundaries lie on either side of the car, about one lane width apart. A line
the car is passing over (a lane change, a wide drift in the data) is the nearest on one side
only, so the lane that holds the car is the one chosen, as the labels define it.

The lines that are not the car's are reported too (`LaneEstimate.others`) when they lie a
whole number of lane widths from one of its boundaries: neighbouring lanes' lines, as a
TuSimple-style evaluation counts every lane. A road's edge on grass, a barrier's foot or a
crack lies anywhere, so most fail that test.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lanekeep.detectors.boundaries import Boundary, take_direction
from lanekeep.detectors.config import LaneRules


@dataclass(frozen=True)
class LaneLines:
    """The car's left and right boundary (None where not found) and the other lane lines."""

    left: Boundary | None
    right: Boundary | None
    others: tuple[Boundary, ...] = ()


def support(b: Boundary) -> float:
    """How much a fit rests on: its points times the distance they cover."""
    return b.n_points * b.x_span_m


def distinct(lines: list[Boundary], x_at: float, min_gap_m: float) -> list[Boundary]:
    """The lines with no two closer than `min_gap_m` at `x_at` (of two such, the one with more
    support stays): one painted line found twice (both edges of a wide stripe, two seeds on
    one dashed line) is one line."""
    kept: list[Boundary] = []
    for b in sorted(lines, key=support, reverse=True):
        y = b.lane.y(x_at)
        if all(abs(y - k.lane.y(x_at)) >= min_gap_m for k in kept):
            kept.append(b)
    return kept


def parallel_lines(lines: list[Boundary], x_at: float, max_divergence_deg: float
                   ) -> list[Boundary]:
    """The lines that run with the others: within `max_divergence_deg` of the support-weighted
    median direction at `x_at` (lane lines are parallel; a fit that crosses between two of
    them, or a vehicle's edge, is not)."""
    if len(lines) < 2:
        return lines
    slopes = np.array([b.lane.slope(x_at) for b in lines])
    weights = np.array([support(b) for b in lines])
    order = np.argsort(slopes)
    cum = np.cumsum(weights[order])
    median = float(slopes[order][np.searchsorted(cum, cum[-1] / 2.0)])
    tol = float(np.tan(np.radians(max_divergence_deg)))
    return [b for b, s in zip(lines, slopes, strict=True) if abs(s - median) <= tol]


def choose_lanes(lines: list[Boundary], x_at: float, rules: LaneRules, width_m: float,
                 min_gap_m: float) -> LaneLines:
    """The car's lane among `lines` (vehicle-frame fits), judged at `x_at` (the near edge of
    the view: the nearest the car that every line reaches), after dropping the lines that do
    not run with the others (`parallel_lines`) and merging duplicates (`distinct`).

    Left are the lines with y > 0 there, right those with y < 0, nearest first, within
    `rules.max_half_width` lane widths (a line further out is a neighbour's) and, where
    `rules.min_half_width` is set, no nearer than that (a line under the car's wheels is taken
    for a sun fleck, a bump's stripe or a crack; 0, the default, keeps every line). The pair is
    the nearest line on each side unless those two are not a lane width apart (within
    `rules.width_tolerance_m`) and a pair among the two nearest on each side is: then that
    pair, the one with the most support (a crack or a shadow's edge between the car and its
    line, found as a line, is skipped this way). Without a consistent pair the nearest two go
    on, and `boundaries.assemble` keeps the better one.
    """
    if rules.min_half_width > 0:  # under the wheels: no lane line, so it neither votes on
        near = rules.min_half_width * width_m  # the lines' direction nor hides one nearby
        lines = [b for b in lines if abs(float(b.lane.y(x_at))) >= near]
    lines = distinct(parallel_lines(lines, x_at, rules.max_divergence_deg), x_at, min_gap_m)
    ys = {id(b): float(b.lane.y(x_at)) for b in lines}
    reach = rules.max_half_width * width_m  # further out: a neighbour's line, never the car's
    left = sorted((b for b in lines if 0.0 < ys[id(b)] <= reach), key=lambda b: ys[id(b)])
    right = sorted((b for b in lines if -reach <= ys[id(b)] < 0.0), key=lambda b: -ys[id(b)])
    if not left or not right:
        pair = (left[0] if left else None, right[0] if right else None)
    else:
        tol = rules.width_tolerance_m

        def fits(a: Boundary, b: Boundary) -> bool:
            return abs(ys[id(a)] - ys[id(b)] - width_m) <= tol

        pair = (left[0], right[0])
        if not fits(*pair):
            consistent = [(a, b) for a in left[:2] for b in right[:2] if fits(a, b)]
            if consistent:
                pair = max(consistent, key=lambda p: support(p[0]) + support(p[1]))
    others = tuple(b for b in lines if b is not pair[0] and b is not pair[1]
                   and _lane_widths_away(ys[id(b)], pair, ys, width_m, rules))
    return LaneLines(pair[0], pair[1], others)


def _lane_widths_away(y: float, pair: tuple[Boundary | None, Boundary | None],
                      ys: dict[int, float], width_m: float, rules: LaneRules) -> bool:
    """Whether a line at `y` lies a whole number (>= 1) of lane widths from the nearer of the
    car's boundaries (within the width tolerance per lane width)."""
    anchors = [ys[id(b)] for b in pair if b is not None]
    if not anchors:
        return False
    gap = min(abs(y - a) for a in anchors)
    lanes = round(gap / width_m)
    return lanes >= 1 and abs(gap - lanes * width_m) <= 0.5 * rules.width_tolerance_m * lanes


def aligned(lines: LaneLines, rules: LaneRules, camera_x_m: float = 0.0) -> LaneLines:
    """Lane lines are parallel: every short line (under `rules.quadratic_span_m`, a dash or
    two) takes the direction and curvature of the longest line found (when that one is at
    least twice as long) and keeps only its own lateral position. A lone dash's own slope
    is a poor guide 15 m away; the longest line's, from the same frame, is a good one."""
    found = [b for b in (lines.left, lines.right, *lines.others) if b is not None]
    if len(found) < 2:
        return lines
    longest = max(found, key=lambda b: b.x_span_m)

    def align(b: Boundary | None) -> Boundary | None:
        if (b is None or b is longest or b.x_span_m >= rules.quadratic_span_m
                or longest.x_span_m < 2.0 * b.x_span_m):
            return b
        return take_direction(b, longest, camera_x_m)

    return LaneLines(align(lines.left), align(lines.right),
                     tuple(align(b) for b in lines.others))

