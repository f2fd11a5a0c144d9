"""Ground truth of the lane from the road geometry, in the vehicle ground frame.

The vehicle ground frame has its origin on the ground under the vehicle reference point given by
(x, y, yaw), x forward and y left. A line of the road at constant Frenet r is cut by the vertical
plane x_vehicle = x at one point for each x (while the car points along the road); that point is
found exactly by Newton's method on the road geometry, so offsets are exact and the fitted
polynomials are least-squares fits of exact points.

Scoring uses the exact points (`lane_offsets`, `lane_centre_at`), never a fit: a quadratic
cannot follow a tight arc (on case2_sharp_turn's 40 m radius a 0-30 m fit is off by ~10 cm at
4-20 m and ~30 cm at 30 m), so a fitted truth would charge its own error to every estimate.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from lanekeep.geometry.road import Road

FIT_STEP_M = 0.5  # spacing of the points a boundary polynomial is fitted to


@dataclass(frozen=True)
class LaneTruth:
    """The true lane as a detector should report it (same conventions as LaneEstimate)."""

    offset_m: float  # car's lateral offset from the lane centre at x = lookahead_m, + = car left
    heading_error_rad: float  # car yaw minus road heading at the car's s, + = car points left
    lookahead_m: float
    left: np.ndarray  # [c0, c1, c2] of y(x) = c0 + c1 x + c2 x^2, vehicle ground frame
    right: np.ndarray
    center: np.ndarray
    s_m: float  # car's Frenet s
    r_m: float  # car's Frenet r


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def frenet(road: Road, xy) -> tuple[np.ndarray | float, np.ndarray | float]:
    """`road.local_coordinates(xy)` (Frenet s, r of world points), remembered for the last
    few points asked: scoring asks for the same ones twice (the pose after a control period
    is the pose the next period's frames are taken from; the tyres are judged both for a
    lane departure and for leaving the road), and each answer is a nearest-point search and
    a Newton solve. The arrays it returns are shared: read-only."""
    xy = np.ascontiguousarray(xy, dtype=float)
    s, r = _remembered_frenet(road, xy.tobytes(), xy.shape)
    return (float(s), float(r)) if xy.ndim == 1 else (s, r)


@functools.lru_cache(maxsize=8)
def _remembered_frenet(road: Road, xy: bytes, shape: tuple[int, ...]
                       ) -> tuple[np.ndarray, np.ndarray]:
    s, r = (np.array(v, dtype=float)
            for v in road.local_coordinates(np.frombuffer(xy).reshape(shape)))
    s.flags.writeable = r.flags.writeable = False
    return s, r


def line_points(
    road: Road, x: float, y: float, yaw: float, r_line: float, xs, s_car: float | None = None
) -> np.ndarray:
    """Points (N, 2) of the road line at Frenet r = `r_line` at vehicle-frame forward distances xs.

    `s_car` (the car's Frenet s, computed if not given) seeds the search.

    Solves g(s) = (P(s, r_line) - p) . f - x = 0 for s by Newton's method, with
    g'(s) = (1 - kappa r_line) cos(theta(s) - yaw).
    """
    xs = np.atleast_1d(np.asarray(xs, dtype=float))
    p = np.array([x, y], dtype=float)
    f = np.array([math.cos(yaw), math.sin(yaw)])
    left = np.array([-f[1], f[0]])
    if s_car is None:
        s_car, _ = frenet(road, p)
    s = s_car + xs
    for _ in range(30):
        xy, heading, curvature = road.geometry_at(s, r_line)  # one table search for all three
        d = xy - p
        g = d @ f - xs
        slope = (1.0 - curvature * r_line) * np.cos(heading - yaw)
        ds = g / np.maximum(slope, 0.1)
        s = s - ds
        if np.all(np.abs(ds) < 1e-10):
            break
    d = road.position(s, r_line) - p
    return np.stack([d @ f, d @ left], axis=-1)


def lane_boundary_points(
    road: Road, x: float, y: float, yaw: float, boundary: int, xs
) -> np.ndarray:
    """Points (N, 2) of lane boundary `boundary` (0 = rightmost) in the vehicle frame at xs."""
    return line_points(road, x, y, yaw, road.boundary_r(boundary), xs)


def _fit(points: np.ndarray) -> np.ndarray:
    return np.polyfit(points[:, 0], points[:, 1], 2)[::-1].copy()


def lane_truth(
    road: Road,
    x: float,
    y: float,
    yaw: float,
    lane: int,
    lookahead_m: float = 0.0,
    fit_range_m: tuple[float, float] = (0.0, 30.0),
) -> LaneTruth:
    """The true lane `lane` (0 = rightmost) seen from the car pose (x, y, yaw) in world coordinates.

    Args:
      road: the road.
      x, y, yaw: vehicle reference point (m) and yaw (rad) in the world frame.
      lane: lane index.
      lookahead_m: forward distance at which the offset is measured (negative = behind).
      fit_range_m: (x_min, x_max) of the polynomial fits; (-15, 0) for the rear camera.

    The offset is exact: -y of the lane centre line at x = lookahead_m (equal to
    -center(lookahead_m) up to the fit residual).
    """
    lo, hi = fit_range_m
    if not hi > lo:
        raise ValueError(f"fit_range_m must be increasing, got {fit_range_m}")
    s_car, r_car = frenet(road, (x, y))
    xs = np.linspace(lo, hi, max(3, math.ceil((hi - lo) / FIT_STEP_M) + 1))
    centre_r = road.lane_center_r(lane)

    def points(r_line: float, at) -> np.ndarray:
        return line_points(road, x, y, yaw, r_line, at, s_car=s_car)

    offset = -float(points(centre_r, [lookahead_m])[0, 1])
    return LaneTruth(
        offset_m=offset,
        heading_error_rad=_wrap(yaw - road.heading_at(s_car)),
        lookahead_m=float(lookahead_m),
        left=_fit(points(road.boundary_r(lane + 1), xs)),
        right=_fit(points(road.boundary_r(lane), xs)),
        center=_fit(points(centre_r, xs)),
        s_m=float(s_car),
        r_m=float(r_car),
    )


def lane_centre_fit(road: Road, x: float, y: float, yaw: float, lane: int,
                    fit_range_m: tuple[float, float] = (0.0, 30.0)) -> tuple[np.ndarray, float]:
    """`lane_truth(...).center` and `.s_m` alone: the centre line's fit and the car's Frenet s,
    without the two boundary fits (the same numbers, a third of the work).

    For drawing and for the step record only; ADE/FDE score against `lane_centre_at`."""
    lo, hi = fit_range_m
    s_car, _ = frenet(road, (x, y))
    xs = np.linspace(lo, hi, max(3, math.ceil((hi - lo) / FIT_STEP_M) + 1))
    points = line_points(road, x, y, yaw, road.lane_center_r(lane), xs, s_car=s_car)
    return _fit(points), float(s_car)


def lane_centre_at(road: Road, x: float, y: float, yaw: float, lane: int, xs,
                   s_car: float | None = None) -> np.ndarray:
    """True y (m, + = left) of lane `lane`'s centre line at vehicle-frame forward distances xs.

    Exact road geometry at each x (one Newton solve for all of them): the truth ADE/FDE
    compare a lane estimate with (`Metrics.add_lane`), so that the metric measures the
    estimate's error and not a fitted truth's. `s_car` (the car's Frenet s) seeds the search.
    """
    return line_points(road, x, y, yaw, road.lane_center_r(lane), xs, s_car=s_car)[:, 1]


def lane_offsets(road: Road, x: float, y: float, yaw: float, lane: int, lookaheads_m,
                 s_car: float | None = None) -> np.ndarray:
    """The car's true offsets from lane `lane`'s centre at several look-aheads at once.

    The same numbers as `lane_truth(...).offset_m` for each look-ahead, from one Newton
    solve instead of a full truth (three boundary fits) per look-ahead. Remembered for the
    last few poses: the car's offset at x = 0 after a control period is the offset at x = 0
    that the next period draws, from the same pose.
    """
    xs = np.atleast_1d(np.asarray(lookaheads_m, dtype=float))
    if s_car is None:
        s_car, _ = frenet(road, (x, y))
    return _remembered_offsets(road, float(x), float(y), float(yaw), lane, xs.tobytes(),
                               xs.shape, float(s_car)).copy()


@functools.lru_cache(maxsize=8)
def _remembered_offsets(road: Road, x: float, y: float, yaw: float, lane: int, xs: bytes,
                        shape: tuple[int, ...], s_car: float) -> np.ndarray:
    at = np.frombuffer(xs).reshape(shape)
    return -line_points(road, x, y, yaw, road.lane_center_r(lane), at, s_car=s_car)[:, 1]


class LanePolylines:
    """The lane's boundaries and centre as dense polylines around one pose, in its vehicle
    frame: exact points of the road geometry at Frenet s from `behind_m` to `ahead_m` of the
    car, for drawing (the recorder's overlays); offsets for scoring come from `lane_offsets`."""

    def __init__(self, road: Road, lane: int, pose: tuple[float, float, float],
                 behind_m: float = 25.0, ahead_m: float = 45.0, step_m: float = 0.5,
                 s_car: float | None = None) -> None:
        x, y, yaw = pose
        if s_car is None:
            s_car, _ = frenet(road, (x, y))
        s = s_car + np.arange(-behind_m, ahead_m + step_m, step_m)
        r = np.array([road.boundary_r(lane + 1), road.boundary_r(lane), road.lane_center_r(lane)])
        d = road.position(s[None, :], r[:, None]) - (x, y)
        c, sn = math.cos(yaw), math.sin(yaw)
        local = np.stack([d[..., 0] * c + d[..., 1] * sn, -d[..., 0] * sn + d[..., 1] * c], -1)
        self.left, self.right, self.centre = local

    def boundaries(self, x_lo: float, x_hi: float) -> list[np.ndarray]:
        """Left and right boundary points with vehicle-frame x in [x_lo, x_hi]."""
        return [b[(b[:, 0] >= x_lo) & (b[:, 0] <= x_hi)] for b in (self.left, self.right)]
