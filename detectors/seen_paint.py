"""Is there paint under a point a network placed? A look at the frame around each point.

A row-anchor network places every boundary on every anchor row where it lies, paint or no
paint: across a dash gap it draws the line from whatever is around it, and there it leans into
the lane (docs/observer.md, "Why it leans"). Its placement on painted rows is good. So the
observer asks the frame itself, at each point, whether a stripe brighter than the road on both
sides of it lies there: a paint-wide ridge within the network's placement error. That is a
look at pixels, not a model: nothing is learnt, and it shares no weights or cues' tuning with
the front models.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from lanekeep.geometry.camera_model import CameraModel

REFERENCE_WIDTH_PX = 1280  # pixel sizes below are given at this frame width


@dataclass(frozen=True)
class PaintTest:
    """A stripe counts as paint when its brightest pixel exceeds the road on both sides by a
    share of the road's level and by a few grey levels."""

    paint_width_m: float = 0.15  # the stripe looked for, across the line
    tolerance_px: float = 5.0  # the network's placement error on painted rows (median ~3 px)
    min_ratio: float = 0.10  # peak >= road x (1 + min_ratio) ...
    min_step: float = 8.0  # ... and >= road + min_step grey levels
    # A double line (two stripes this far apart, the point between them on the gap) is paint
    # too: two ridges, one a stripe's width either side of the gap, each brighter than the
    # road outside them. 0 = single stripes only. Why: a row-anchor network places a double
    # line's boundary on its middle, the gap, where a one-stripe test sees road. 0.12 m: the
    # world's double gap (MarkingStyle.double_gap_m), a common one on real roads.
    double_gap_m: float = 0.12
    # The ridge's height read as the brightest run of a stripe's width (its mean) instead of
    # the brightest pixel. Why: on coarse asphalt the brightest of a few dozen pixels stands
    # 10-20 grey levels over the road's median by grain alone, so bare road passes the test;
    # a painted stripe is bright across its width.
    stripe_mean: bool = False

    def __post_init__(self) -> None:
        if not (self.paint_width_m > 0 and self.tolerance_px >= 0 and self.min_ratio >= 0
                and self.min_step >= 0 and self.double_gap_m >= 0):
            raise ValueError("paint_width_m must be > 0 and the tolerances and double_gap_m >= 0")

    def passes(self, peak: float, road: float) -> bool:
        """A peak over this road level counts as paint."""
        return peak >= road * (1.0 + self.min_ratio) and peak - road >= self.min_step


def paint_under_points(frame: np.ndarray, points_px: np.ndarray, camera: CameraModel,
                       test: PaintTest) -> np.ndarray:
    """For each point (N, 2) (column, row) of `frame` (H, W, 3 RGB, the camera's view): 1.0
    where a paint-wide ridge lies within the tolerance of it along its row, or (with
    `double_gap_m`) a double line's two ridges either side of it, else 0.0."""
    pts = np.asarray(points_px, dtype=float).reshape(-1, 2)
    seen = np.zeros(len(pts))
    if not len(pts):
        return seen
    h, w = frame.shape[:2]
    scaled = camera.scaled(w, h) if (camera.width, camera.height) != (w, h) else camera
    half_px = _half_widths_px(pts, scaled, test.paint_width_m)
    gap_px = (_half_widths_px(pts, scaled, test.double_gap_m) if test.double_gap_m > 0
              else np.full(len(pts), np.nan))  # half the gap, in pixels
    tol = test.tolerance_px * w / REFERENCE_WIDTH_PX
    grey_rows: dict[int, np.ndarray] = {}
    for k, ((u, v), half, gap_half) in enumerate(zip(pts, half_px, gap_px, strict=True)):
        row = int(round(v))
        if not (0 <= row < h) or not np.isfinite(half):
            continue
        if row not in grey_rows:
            grey_rows[row] = _grey_row(frame, row)
        grey = grey_rows[row]
        side = max(2.0, 2.0 * half)  # the road beside: a stripe's width or two
        run = max(1, int(round(2.0 * half))) if test.stripe_mean else 1
        stripe = _stripe(grey, u, half + tol, side, run)
        if stripe is not None and test.passes(stripe[0], max(stripe[1], stripe[2])):
            seen[k] = 1.0
        elif np.isfinite(gap_half):
            offset = gap_half + half  # each stripe's centre from the gap's middle
            left, right = _stripe(grey, u - offset, half + tol, side, run), _stripe(
                grey, u + offset, half + tol, side, run)
            if left is not None and right is not None:
                road = max(left[1], right[2])  # outside the pair: the gap is not the road
                seen[k] = float(test.passes(left[0], road) and test.passes(right[0], road))
    return seen


def _stripe(grey: np.ndarray, centre: float, reach: float, side: float, run: int = 1
            ) -> tuple[float, float, float] | None:
    """The brightest mean of `run` neighbouring pixels within `reach` of `centre` along a grey
    row (the brightest pixel for 1) and the road's median level in `side` pixels beyond each
    end; None where a part lies off the row."""
    w = len(grey)
    lo, hi = int(np.floor(centre - reach)), int(np.ceil(centre + reach)) + 1
    left = grey[max(0, int(np.floor(centre - reach - side))):max(0, lo)]
    right = grey[min(w, hi):min(w, int(np.ceil(centre + reach + side)) + 1)]
    middle = grey[max(0, lo):min(w, hi)]
    if not (len(left) and len(right) and len(middle)):
        return None
    if run > 1 and len(middle) > run:
        sums = np.cumsum(np.concatenate([[0.0], middle.astype(np.float64)]))
        peak = float((sums[run:] - sums[:-run]).max() / run)
    else:
        peak = float(middle.max()) if run == 1 else float(middle.mean())
    return peak, _median(left), _median(right)


def _grey_row(frame: np.ndarray, row: int) -> np.ndarray:
    """One row of the frame's grey image after a 3x3 box blur (a pixel's neighbours, not single
    grains), float32: the rows either side and no more are converted, for the blur of the
    middle row reads only those (the image's own border where the row is its first or last)."""
    top = max(0, row - 1)
    strip = cv2.cvtColor(np.ascontiguousarray(frame[top:row + 2]), cv2.COLOR_RGB2GRAY)
    if row - top == 1 and strip.shape[0] == 3:
        return cv2.blur(strip, (3, 3))[1].astype(np.float32)
    return cv2.blur(cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY), (3, 3))[row].astype(np.float32)


def _median(values: np.ndarray) -> float:
    """numpy's median of a short row segment, without its per-call overhead."""
    ordered = np.sort(values)
    n = len(ordered)
    return float((ordered[(n - 1) // 2] + ordered[n // 2]) / np.float32(2.0))


def _half_widths_px(points_px: np.ndarray, camera: CameraModel, width_m: float) -> np.ndarray:
    """Half a stripe's width in pixels at each point: its ground point projected with the
    stripe's two edges across the line (NaN where the point is not on the ground)."""
    ground, ok = camera.pixels_to_ground(points_px)
    half = np.full(len(points_px), np.nan)
    if not ok.any():
        return half
    xy = ground[ok]
    edges = np.concatenate([xy + [0.0, width_m / 2.0], xy - [0.0, width_m / 2.0]])
    px, front = camera.project_ground(edges)
    n = len(xy)
    across = np.abs(px[:n, 0] - px[n:, 0]) / 2.0
    half[np.flatnonzero(ok)] = np.where(front[:n] & front[n:], np.maximum(across, 0.5), np.nan)
    return half
