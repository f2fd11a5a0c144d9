"""The horizon of a real road photo: the vanishing point of its lane lines.

An unknown dashcam's pitch decides where every ground point lands; a wrong horizon bends and
crosses the boundaries a detector fits. Lane lines and road edges are parallel on the ground,
so in the image they meet at one point on the horizon. Found here with OpenCV (Canny edges,
probabilistic Hough segments at 640 px width) and a consensus over pairs: every pair of one
segment leaning right and one leaning left (as the two sides of a lane do) is intersected,
each intersection is scored by the length of the segments that point at it (within
ANGLE_TOL_DEG), and the best one is refined by least squares over its inliers. No consensus
(too few segments, or inliers on one side only) gives None and the caller's fallback.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

WORK_WIDTH = 640  # px: edges and segments at this width (the photos' noise is finer)
SLANT_DEG = (15.0, 75.0)  # from horizontal: lane lines, not the horizon or poles
ANGLE_TOL_DEG = 1.5  # a segment points at a vanishing point when within this angle of it
MAX_PER_SIDE = 40  # the longest segments of each leaning that are paired (40 x 40 pairs)
CENTRE_SHARE = (0.25, 0.75)  # a dashcam looks along its road: the point's column, of the width
MIN_SUPPORT_PX = 60.0  # inlier length each side needs (at WORK_WIDTH) to be a consensus


def _segments(image: np.ndarray, top: int) -> np.ndarray:
    """Hough segments (x1, y1, x2, y2) of `image` (at WORK_WIDTH) below row `top`."""
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image
    edges = cv2.Canny(cv2.GaussianBlur(grey, (5, 5), 0), 40, 120)
    edges[:top] = 0
    lines = cv2.HoughLinesP(edges, 1, math.pi / 180, 30, minLineLength=20, maxLineGap=10)
    return np.zeros((0, 4)) if lines is None else lines.reshape(-1, 4).astype(float)


def _pointing(seg: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(points, segments) angle (deg) between each segment and the ray from its middle to
    each point, folded to 0-90 (a line has no direction)."""
    d = seg[:, 2:] - seg[:, :2]
    mid = (seg[:, :2] + seg[:, 2:]) / 2.0
    ray = points[:, None, :] - mid[None, :, :]
    cross = d[None, :, 0] * ray[..., 1] - d[None, :, 1] * ray[..., 0]
    dot = d[None, :, 0] * ray[..., 0] + d[None, :, 1] * ray[..., 1]
    return np.degrees(np.arctan2(np.abs(cross), np.abs(dot)))


def _intersections(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Every intersection of a line of `a` with a line of `b` (homogeneous cross products)."""
    def homogeneous(s: np.ndarray) -> np.ndarray:
        p = np.c_[s[:, :2], np.ones(len(s))]
        q = np.c_[s[:, 2:], np.ones(len(s))]
        return np.cross(p, q)

    pts = np.cross(homogeneous(a)[:, None, :], homogeneous(b)[None, :, :]).reshape(-1, 3)
    ok = np.abs(pts[:, 2]) > 1e-9
    return pts[ok, :2] / pts[ok, 2:]


def vanishing_point(image: np.ndarray, min_fraction: float = 0.2, max_fraction: float = 0.75
                    ) -> tuple[float, float] | None:
    """(u, v) in `image`'s pixels of its lane lines' vanishing point, or None (no consensus).

    Only a point in the middle half of the image's width and between rows min_fraction and
    max_fraction of its height counts (a dashcam's horizon lies there); edges above
    min_fraction are ignored.
    """
    h, w = image.shape[:2]
    s = WORK_WIDTH / w
    small = cv2.resize(image, (WORK_WIDTH, max(2, round(h * s))), interpolation=cv2.INTER_AREA)
    seg = _segments(small, int(min_fraction * small.shape[0]))
    if len(seg) < 2:
        return None
    d = seg[:, 2:] - seg[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    angle = np.degrees(np.arctan2(np.abs(d[:, 1]), np.abs(d[:, 0])))
    slanted = (angle >= SLANT_DEG[0]) & (angle <= SLANT_DEG[1])
    rising_right = d[:, 0] * d[:, 1] < 0  # v grows downwards
    sides = [np.flatnonzero(slanted & rising_right), np.flatnonzero(slanted & ~rising_right)]
    sides = [idx[np.argsort(-length[idx])][:MAX_PER_SIDE] for idx in sides]
    if min(len(idx) for idx in sides) == 0:
        return None
    cand = _intersections(seg[sides[0]], seg[sides[1]])
    lo, hi = min_fraction * small.shape[0], max_fraction * small.shape[0]
    left, right = CENTRE_SHARE[0] * WORK_WIDTH, CENTRE_SHARE[1] * WORK_WIDTH
    cand = cand[(cand[:, 0] >= left) & (cand[:, 0] <= right) & (cand[:, 1] >= lo)
                & (cand[:, 1] <= hi)]
    if len(cand) == 0:
        return None
    used = np.concatenate(sides)
    # A vanishing point is below every segment's far end: lane lines end at it, not beyond.
    inlier = (_pointing(seg[used], cand) < ANGLE_TOL_DEG) & \
        (cand[:, None, 1] <= np.minimum(seg[used, 1], seg[used, 3])[None, :] + 2.0)
    side_of = np.r_[np.zeros(len(sides[0])), np.ones(len(sides[1]))]
    support = np.stack([(inlier & (side_of == k)) @ length[used] for k in (0, 1)], axis=1)
    score = np.minimum(support[:, 0], support[:, 1])  # both sides must point at it
    best = int(np.argmax(score))
    if score[best] < MIN_SUPPORT_PX:
        return None
    # Least squares over the inliers: the point nearest to their lines (n . p = c).
    chosen = seg[used[inlier[best]]]
    normal = np.stack([chosen[:, 3] - chosen[:, 1], chosen[:, 0] - chosen[:, 2]], axis=1)
    weight = np.hypot(normal[:, 0], normal[:, 1])
    normal /= weight[:, None]
    c = np.sum(normal * chosen[:, :2], axis=1)
    point, *_ = np.linalg.lstsq(normal * np.sqrt(weight)[:, None], c * np.sqrt(weight),
                                rcond=None)
    if not np.all(np.isfinite(point)) or np.hypot(*(point - cand[best])) > 10.0:
        point = cand[best]  # the refinement ran off: keep the consensus point
    return (float(point[0] + 0.5) / s - 0.5, float(point[1] + 0.5) / s - 0.5)


def horizon_row(image: np.ndarray, min_fraction: float = 0.2, max_fraction: float = 0.75
                ) -> float | None:
    """The row of `image`'s horizon (its lane lines' vanishing point), or None."""
    vp = vanishing_point(image, min_fraction, max_fraction)
    return None if vp is None else vp[1]
