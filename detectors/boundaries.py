"""Boundary fits in the vehicle frame and their assembly into a `LaneEstimate`."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.birds_eye import BirdsEye
from lanekeep.detectors.config import LaneRules
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.lane_poly import LanePoly


@dataclass(frozen=True)
class Boundary:
    """A fitted boundary: y(x) coefficients [c0, c1, c2], its support and its image points."""

    coeffs: np.ndarray
    n_points: int
    x_span_m: float
    points_xy: np.ndarray  # (N, 2) vehicle-frame points the fit used

    @property
    def lane(self) -> LanePoly:
        return LanePoly.of(self.coeffs)


def fit_boundary(xy: np.ndarray, rules: LaneRules, camera_x_m: float = 0.0,
                 weighted: bool = True) -> Boundary | None:
    """Least-squares y(x): a parabola over long spans, a line over short ones.

    `weighted`: each point weighed by 1 / its distance from the camera, for a pixel's lateral
    uncertainty grows with distance (the per-pixel image binarisations). The bird's-eye
    models give one point per 0.1 m of paint wherever it is and fit unweighted: weighted, a
    near, partial dash beside the hood outweighed two whole dashes further on (27-33 cm off
    at 10 m on clear_straight), and on the tuning sets the two weightings score the same.
    Points further than `rules.inlier_m` from the fit (a vehicle's edge or a shadow's beside
    the paint) are dropped and the rest fitted again, twice at most. None if unfit.
    """
    coeffs = None
    for _ in range(3):
        if len(xy) < 3:
            return None
        x, y = xy[:, 0], xy[:, 1]
        span = float(x.max() - x.min())
        if span < rules.min_span_m:
            return None
        degree = 2 if span >= rules.quadratic_span_m else 1
        weights = 1.0 / np.maximum(np.abs(x - camera_x_m), 1.0) if weighted else None
        coeffs = np.zeros(3)
        coeffs[: degree + 1] = _polyfit(x, y, degree, weights)[::-1]
        fitted = coeffs[0] + coeffs[1] * x + coeffs[2] * np.square(x)  # LanePoly.y's sum
        inliers = np.abs(y - fitted) <= rules.inlier_m
        if rules.inlier_m <= 0 or inliers.all() or inliers.sum() < 0.5 * len(xy):
            break
        xy = xy[inliers]
    if abs(2.0 * coeffs[2]) > rules.max_curvature_1pm or not np.all(np.isfinite(coeffs)):
        return None
    return Boundary(coeffs, len(xy), span, xy)


def _polyfit(x: np.ndarray, y: np.ndarray, degree: int, w: np.ndarray | None) -> np.ndarray:
    """np.polyfit(x, y, degree, w=w) for 1-D float arrays, its arithmetic step for step
    (the same coefficients to the bit) without its argument checks: a frame fits a dozen
    boundaries and the checks cost a third of each fit."""
    lhs = np.vander(x, degree + 1)
    rhs = y + 0.0
    if w is not None:
        lhs *= w[:, np.newaxis]
        rhs *= w
    scale = np.sqrt((lhs * lhs).sum(axis=0))
    lhs /= scale
    c = np.linalg.lstsq(lhs, rhs, len(x) * np.finfo(x.dtype).eps)[0]
    return c / scale


def take_direction(short: Boundary, long: Boundary, camera_x_m: float = 0.0) -> Boundary:
    """`short` with the direction and curvature of `long` and only its own lateral position
    (weighted to its points nearest the camera, where a pixel is most precise)."""
    x, y = short.points_xy[:, 0], short.points_xy[:, 1]
    c = long.coeffs
    w = 1.0 / np.maximum(np.abs(x - camera_x_m), 1.0) ** 2
    c0 = float(np.sum(w * (y - c[1] * x - c[2] * x * x)) / np.sum(w))
    return replace(short, coeffs=np.array([c0, c[1], c[2]]))


def parallel(
    left: Boundary | None, right: Boundary | None, rules: LaneRules, camera_x_m: float = 0.0
) -> tuple[Boundary | None, Boundary | None]:
    """Lane boundaries are parallel: a short boundary (a single dash, say) takes the direction
    and curvature of a long one and keeps only its own lateral position."""
    if left is None or right is None:
        return left, right
    if left.x_span_m < rules.quadratic_span_m and right.x_span_m >= 2.0 * left.x_span_m:
        left = take_direction(left, right, camera_x_m)
    elif right.x_span_m < rules.quadratic_span_m and left.x_span_m >= 2.0 * right.x_span_m:
        right = take_direction(right, left, camera_x_m)
    return left, right


def plausible(b: Boundary | None, x_ref: float, rules: LaneRules,
              other: Boundary | None = None) -> bool:
    """A lane boundary runs along the road, and a short one alone says little far from itself.

    Thin features of other vehicles, warped to the ground, run away from the camera at steep
    angles: a boundary whose direction at `x_ref` is further than `max_heading_deg` from the
    car's is not one. A short fit with no partner (`parallel` gives a short one its partner's
    direction) is dropped when `x_ref` lies more than `max_extrapolation` times its span
    beyond its points: a one-metre piece of paint beside a vehicle fixes no direction.
    """
    if b is None:
        return False
    if abs(b.lane.slope(x_ref)) > math.tan(math.radians(rules.max_heading_deg)):
        return False
    if other is not None or b.x_span_m >= rules.quadratic_span_m:
        return True
    gap = float(np.min(np.abs(b.points_xy[:, 0] - x_ref)))
    return gap <= rules.max_extrapolation * b.x_span_m


def assemble(
    left: Boundary | None,
    right: Boundary | None,
    x_ref: float,
    rules: LaneRules,
    camera: CameraModel,
    confidence: float,
    lane_width_m: float | None = None,
    others: tuple[Boundary, ...] = (),
) -> LaneEstimate:
    """Offset at `x_ref` from the two boundaries, or from one and the lane width; `others`
    (the other lanes' lines found, `lane_lines.choose_lanes`) are passed on as they are."""
    width = lane_width_m or rules.lane_width_m
    left, right = (b if plausible(b, x_ref, rules, other) else None
                   for b, other in ((left, right), (right, left)))
    if left is not None and right is not None:
        measured = float(left.lane.y(x_ref) - right.lane.y(x_ref))
        lanes = round(measured / width)
        if lanes >= 2 and abs(measured - lanes * width) <= rules.width_tolerance_m * lanes:
            # Two (or more) lanes apart: both are real lines and the ego lane's line between
            # them is in a dash gap. The car's own lane lies against the nearer one.
            if abs(left.lane.y(x_ref)) <= abs(right.lane.y(x_ref)):
                right = None
            else:
                left = None
            confidence *= 0.5
        elif abs(measured - width) > rules.width_tolerance_m:
            # Inconsistent pair: keep the side with more support.
            if left.n_points * left.x_span_m >= right.n_points * right.x_span_m:
                right = None
            else:
                left = None
            confidence *= 0.5
    if left is None and right is None:
        return LaneEstimate.invalid("no lane boundary found", x_m=x_ref)
    if left is not None and right is not None:
        centre = (left.lane.y(x_ref) + right.lane.y(x_ref)) / 2.0
    elif left is not None:
        centre = left.lane.y(x_ref) - width / 2.0
        confidence *= 0.6
    else:
        centre = right.lane.y(x_ref) + width / 2.0
        confidence *= 0.6
    offset = -float(centre)
    if not math.isfinite(offset) or abs(offset) > width:
        return LaneEstimate.invalid("lane centre out of reach", x_m=x_ref)
    image_points = {}
    for side, b in (("left", left), ("right", right)):
        if b is not None:
            uv, ok = camera.project_ground(b.points_xy)
            image_points[side] = uv[ok]
    return LaneEstimate(
        valid=True,
        offset_m=offset,
        x_m=float(x_ref),
        left=None if left is None else left.coeffs.copy(),
        right=None if right is None else right.coeffs.copy(),
        confidence=float(np.clip(confidence, 0.0, 1.0)),
        image_points=image_points,
        others=tuple(b.coeffs.copy() for b in others),
    )


def support_confidence(left: Boundary | None, right: Boundary | None, view: BirdsEye) -> float:
    """Share of the ground window's depth the found boundaries cover (both sides summed, <= 1)."""
    support = sum(b.x_span_m for b in (left, right) if b is not None)
    span = abs(view.window.x_far_m - view.window.x_near_m)
    return min(1.0, support / span)
