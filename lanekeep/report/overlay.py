"""Geometry of what the recording draws: vehicle-frame lanes into world and map coordinates,
lane polynomials into pixels (clipped to the image), the car's footprint."""

from __future__ import annotations

import math

import numpy as np

from lanekeep.geometry.lane_poly import LanePoly

LANE_RANGE_M = (3.0, 30.0)  # |x| of the lane polylines drawn from each camera
MAX_POINTS_PER_SIDE = 400
LINE_Z_M = 0.05  # lifted above the road in the 3D view


# -- geometry -----------------------------------------------------------------------------------
def vehicle_to_world(xy: np.ndarray, pose: tuple[float, float, float]) -> np.ndarray:
    """Vehicle-frame XY (..., 2) of `pose` into world XY."""
    x, y, yaw = pose
    v = np.asarray(xy, dtype=float)
    c, s = math.cos(yaw), math.sin(yaw)
    return np.stack([x + v[..., 0] * c - v[..., 1] * s, y + v[..., 0] * s + v[..., 1] * c], -1)


def camera_x_range(camera) -> tuple[float, float]:
    """Vehicle-frame x interval of the ground that a camera looks at (front: +, rear: -)."""
    forward = -camera.rotation[0, 2]
    lo, hi = LANE_RANGE_M
    return (lo, hi) if forward >= 0 else (-hi, -lo)


def poly_points(coeffs, x_range: tuple[float, float], n: int = 28) -> np.ndarray:
    xs = np.linspace(*x_range, n)
    return np.column_stack([xs, LanePoly.of(coeffs).y(xs)])


def clip_segment(p: np.ndarray, q: np.ndarray, w: float, h: float):
    """Liang-Barsky: the part of segment p-q inside [0, w] x [0, h], or None."""
    d = q - p
    t0, t1 = 0.0, 1.0
    for num, den in ((p[0], -d[0]), (w - p[0], d[0]), (p[1], -d[1]), (h - p[1], d[1])):
        if den == 0:
            if num < 0:
                return None
            continue
        t = num / den
        if den < 0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
    return None if t0 > t1 else (p + t0 * d, p + t1 * d)


def clip_polyline(uv: np.ndarray, w: float, h: float) -> list[np.ndarray]:
    """A pixel polyline cut to the image: the runs of it inside [0, w] x [0, h], so that an
    overlay never draws outside its camera image. A polyline wholly inside is itself (the
    common case, and the recorder's writer ran this segment by segment for ~20 ms a step)."""
    uv = np.asarray(uv, dtype=float)
    if len(uv) >= 2 and np.all((uv >= 0.0) & (uv <= (w, h))):
        return [uv.copy()]
    runs: list[list[np.ndarray]] = []
    current: list[np.ndarray] = []
    for p, q in zip(uv[:-1], uv[1:], strict=True):
        part = clip_segment(np.asarray(p, float), np.asarray(q, float), w, h)
        if part is None:
            if current:
                runs.append(current)
            current = []
            continue
        a, b = part
        if current and np.allclose(current[-1], a):
            current.append(b)
        else:
            if current:
                runs.append(current)
            current = [a, b]
    if current:
        runs.append(current)
    return [np.asarray(r) for r in runs if len(r) >= 2]


def pixel_strips(camera, ground_xy: np.ndarray) -> list[np.ndarray]:
    """A ground polyline projected into the camera and clipped to its image (points behind the
    camera dropped first)."""
    if len(ground_xy) < 2:
        return []
    uv, in_front = camera.project_ground(ground_xy)
    strips: list[np.ndarray] = []
    start = 0
    for i in range(len(uv) + 1):  # split where the line passes behind the camera
        if i == len(uv) or not in_front[i]:
            if i - start >= 2:
                strips += clip_polyline(uv[start:i], camera.width, camera.height)
            start = i + 1
    return strips


def map_xy(xy: np.ndarray) -> np.ndarray:
    """World XY to the 2D map's coordinates (image axes: y down, so flip y: north up)."""
    xy = np.asarray(xy, dtype=np.float32)
    return np.column_stack([xy[..., 0], -xy[..., 1]])


def car_footprint(pose: tuple[float, float, float], length: float, width: float) -> np.ndarray:
    """Closed polygon (5, 2) of the car's outline at `pose`, world XY (centred on the pose's
    point, the recording's convention for `world/car/body`)."""
    corners = np.array([[length / 2, width / 2], [length / 2, -width / 2],
                        [-length / 2, -width / 2], [-length / 2, width / 2],
                        [length / 2, width / 2]])
    return vehicle_to_world(corners, pose)


def lifted(xy: np.ndarray) -> np.ndarray:
    """Ground polyline (N, 2) to 3D points just above the road."""
    return np.column_stack([xy, np.full(len(xy), LINE_Z_M, dtype=xy.dtype)])
