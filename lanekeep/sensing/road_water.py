"""Where the wet road's water lies in a camera's frame: the paved surface and the puddles.

A water film mirrors only where it is smooth: on the asphalt and, fully, in the puddles. Grass
and gravel are wet too but rough, so they mirror nothing. The screen-space reflection
(lanekeep/sensing/weather.py) used to mirror onto every pixel of the flat ground, grass
included: trees stood mirrored in the meadow beside the road. `RoadWater` knows the paved strip
and the puddles in world coordinates (what lanekeep/world/build.py laid and
lanekeep/world/roadside.py `add_wet` put on it) and rasterises them, for the car's pose, onto
the grid of the depth map (every DEPTH_STEP_PX-th pixel): the paved strip as quads along the
road, sampled finely near the car, each puddle as its polygon, clipped at the camera's near
plane. The camera is the mounting's (no body pitch or roll, like the flat-ground depth test it
is combined with).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.road import Road

NEAR_M, NEAR_STEP_M = 30.0, 1.0  # the strip sampled every metre within 30 m of the car ...
REACH_M, FAR_STEP_M = 300.0, 4.0  # ... and every 4 m out to 300 m (the horizon's rows)
CLIP_Z_M = 0.05  # near plane the polygons are clipped at
SHIFT = 4  # fixed-point bits of the rasterised corners


@dataclass(frozen=True)
class RoadWater:
    """The paved surface (offsets `paved_r` from the road's reference line, over arc lengths
    `s_range`) and the puddles (convex polygons, world xy (k, 2)) of a wet world."""

    road: Road
    paved_r: tuple[float, float]
    s_range: tuple[float, float]
    puddles: tuple[np.ndarray, ...] = ()

    def masks(self, camera: CameraModel, pose: tuple[float, float, float],
              shape: tuple[int, int], step: int) -> tuple[np.ndarray, np.ndarray]:
        """uint8 (rows, cols) masks (255 inside) of the paved surface and of the puddles on
        the grid of pixels (step // 2 + step i, step // 2 + step j), the car at `pose`
        (world x, y, yaw)."""
        x, y, yaw = pose
        s_car, _ = self.road.local_coordinates(np.array([x, y]))
        s = np.unique(np.concatenate([
            np.arange(-REACH_M, -NEAR_M, FAR_STEP_M), np.arange(-NEAR_M, NEAR_M, NEAR_STEP_M),
            np.arange(NEAR_M, REACH_M + FAR_STEP_M, FAR_STEP_M)]) + s_car)
        s = s[(s >= self.s_range[0]) & (s <= self.s_range[1])]
        paved = np.zeros(shape, np.uint8)
        if len(s) >= 2:
            right = self.road.position(s, np.full(len(s), self.paved_r[0]))
            left = self.road.position(s, np.full(len(s), self.paved_r[1]))
            quads = np.stack([right[:-1], right[1:], left[1:], left[:-1]], 1)
            _fill(paved, _camera_points(quads, camera, pose), camera, step)
        puddles = np.zeros(shape, np.uint8)
        near = [p for p in self.puddles if np.hypot(*(p.mean(0) - (x, y))) < REACH_M]
        if near:
            for k in sorted({len(p) for p in near}):  # polygons of one size at a time
                same = [p for p in near if len(p) == k]
                _fill(puddles, _camera_points(same, camera, pose), camera, step)
        return paved, puddles


def _camera_points(polygons, camera: CameraModel, pose) -> np.ndarray:
    """World ground polygons (n, k, 2) -> OpenCV camera coordinates (n, k, 3), all at once."""
    x, y, yaw = pose
    c, s = np.cos(yaw), np.sin(yaw)
    d = np.asarray(polygons, float) - (x, y)
    vehicle = np.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1],
                        np.zeros(d.shape[:-1])], -1)
    return camera.to_opencv_frame(vehicle)


def _clip_near(poly: np.ndarray) -> np.ndarray:
    """The part of a polygon (k, 3) in front of the near plane z = CLIP_Z_M (Sutherland-
    Hodgman against one plane)."""
    out = []
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        a_in, b_in = a[2] >= CLIP_Z_M, b[2] >= CLIP_Z_M
        if a_in:
            out.append(a)
        if a_in != b_in:
            t = (CLIP_Z_M - a[2]) / (b[2] - a[2])
            out.append(a + t * (b - a))
    return np.array(out).reshape(-1, 3)


def _grid_corners(poly: np.ndarray, camera: CameraModel, step: int) -> np.ndarray:
    """Camera-frame points (..., 3) in front of the near plane -> fixed-point grid corners."""
    u = camera.fx * poly[..., 0] / poly[..., 2] + camera.cx
    v = camera.fy * poly[..., 1] / poly[..., 2] + camera.cy
    grid = np.stack([(u - step // 2) / step, (v - step // 2) / step], -1)
    grid = np.clip(grid, -1e5, 1e5)  # a corner just past the near plane lies far out
    return np.round(grid * (1 << SHIFT)).astype(np.int32)


def _fill(mask: np.ndarray, polygons: np.ndarray, camera: CameraModel, step: int) -> None:
    """Rasterise convex camera-frame polygons (n, k, 3) onto the grid (255 inside); those
    wholly behind the near plane or beside the frame are left out, those across the near
    plane clipped."""
    behind = polygons[..., 2] < CLIP_Z_M
    keep = ~behind.all(1)
    polygons, across = polygons[keep], behind[keep].any(1)
    whole = _grid_corners(polygons[~across], camera, step)
    rows, cols = mask.shape
    limit = np.array([cols, rows]) << SHIFT
    outside = ((whole < 0).all(1) | (whole >= limit).all(1)).any(-1)
    corners = list(whole[~outside])
    for poly in polygons[across]:
        piece = _clip_near(poly)
        if len(piece) >= 3:
            corners.append(_grid_corners(piece, camera, step))
    for c in corners:
        cv2.fillConvexPoly(mask, c, 255, cv2.LINE_8, SHIFT)  # each convex: no even-odd
