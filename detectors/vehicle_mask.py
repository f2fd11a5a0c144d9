"""Where other vehicles hide the road, from the frame alone, and paint-width runs.

Other vehicles fool a paint detector with thin bright features that stand above the road: a
white strip beside a tail light, a number plate, a pillar between dark windows. Warped to the
bird's-eye view they stretch away from the camera like lane lines. Three cues remove them:

- The dark band under a vehicle (tyres, underbody and the shade they make; the classic cue of
  shadow-based vehicle detection): pixels far darker than the road ahead of the car, in a row
  run as wide as a vehicle at that row's distance. Everything above the band's lowest row in
  its columns (and a margin either side) is the vehicle or road it hides, so no paint is
  taken there. Shade from buildings and trees is not dark enough (it leaves 30-50% of the
  light; a vehicle's underside, a few percent) and is wider than a vehicle where it crosses
  the road; an unlit road at night is wider still.
- Paint lies on the road: a bright ridge within a few pixels of something that dark (a hub
  cap in its tyre, trim under a dark window) is not paint.
- Paint is narrow on the ground: in the bird's-eye view a run along a row wider than the widest
  paint (plus the blur a working pixel adds at that distance) is not paint. A plate or a body
  panel projected onto the ground from above it is wider than that.

Row geometry comes from the camera model: pixels per metre across the road at each row of the
working image, computed once per view.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from lanekeep.detectors.birds_eye import BirdsEye


def roi_px_per_m(view: BirdsEye, roi_rows: int) -> np.ndarray:
    """Working pixels per metre across the road on the ground seen at each ROI row (0 where
    the row sees no ground)."""
    cam, s = view.camera, view.scale
    rows = view.crop_top + (np.arange(roi_rows) + 0.5) / s - 0.5
    pixels = np.stack([np.full(roi_rows, cam.cx), rows], axis=1)
    ground, ok = cam.pixels_to_ground(pixels)
    pts = np.c_[ground[:, :2], np.zeros(roi_rows)]
    depth = cam.to_opencv_frame(pts)[:, 2]
    out = np.zeros(roi_rows)
    good = ok & (depth > 0.1)
    out[good] = cam.K[0, 0] * s / depth[good]
    return out


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(row, first col, end col exclusive) of every run of True along the rows.

    One pass finds every change along the padded rows; in row-major order they alternate
    start, end (each row opens and closes on padding), so no second search for the ends."""
    h, w = mask.shape
    padded = np.zeros((h, w + 2), bool)
    padded[:, 1:-1] = mask
    changes = np.flatnonzero(padded[:, 1:] != padded[:, :-1])
    rows, cols = np.divmod(changes, w + 1)
    return rows[0::2], cols[0::2], cols[1::2]


def vehicle_dark(grey: np.ndarray, dark_ratio: float) -> np.ndarray:
    """Pixels as dark as a vehicle's tyres, underside, windows or black paint: below
    `dark_ratio` of the road's level (the median of the lower half of the working ROI)."""
    road = float(np.median(grey[grey.shape[0] // 2 :: 2, ::4]))
    return grey <= dark_ratio * road


def hidden_by_vehicles(dark: np.ndarray, px_per_m: np.ndarray, min_width_m: float,
                       max_width_m: float, margin_m: float) -> np.ndarray | None:
    """Boolean ROI mask of what vehicles cover (None when no vehicle is seen)."""
    h = dark.shape[0]
    dark = dark.copy()
    dark[1:] &= dark[:-1]  # at least two rows tall: not a one-row seam or noise
    rows, starts, ends = _runs(dark)
    if len(rows) == 0:
        return None
    width_m = (ends - starts) / np.maximum(px_per_m[rows], 1e-6)
    keep = (width_m >= min_width_m) & (width_m <= max_width_m) & (px_per_m[rows] > 0)
    if not keep.any():
        return None
    bottom = np.full(dark.shape[1], -1)
    for r, a, b in zip(rows[keep], starts[keep], ends[keep], strict=True):
        m = int(round(margin_m * px_per_m[r]))
        lo, hi = max(0, a - m), min(dark.shape[1], b + m)
        np.maximum(bottom[lo:hi], r, out=bottom[lo:hi])
    # A vehicle stands on the road, with road below its band; a dark band reaching the
    # bottom of the view is the ego car's own hood (or a vehicle too close to tell).
    bottom[bottom >= h - 2] = -1
    return np.arange(h)[:, None] <= bottom[None, :]


def max_run_cols(view: BirdsEye, max_paint_width_m: float, blur_px: float) -> np.ndarray:
    """Per bird's-eye row, the widest run (columns) that can still be paint: the widest paint
    plus `blur_px` working pixels of spread (dilation, interpolation) at that distance."""
    x, _ = view.to_ground(np.zeros(view.rows), np.arange(view.rows))
    depth = np.abs(x - float(view.camera.position_m[0]))
    m_per_px = depth / (view.camera.K[0, 0] * view.scale)
    return np.ceil((max_paint_width_m + blur_px * m_per_px) / view.window.m_per_col)


def drop_wide_runs(bev: np.ndarray, max_cols: np.ndarray) -> np.ndarray:
    """The binary bird's-eye view without row runs wider than `max_cols` of their row."""
    rows, starts, ends = _runs(bev > 0)
    wide = (ends - starts) > max_cols[rows]
    if not wide.any():
        return bev
    marks = np.zeros((bev.shape[0], bev.shape[1] + 1), np.int32)
    np.add.at(marks, (rows[wide], starts[wide]), 1)
    np.add.at(marks, (rows[wide], ends[wide]), -1)
    out = bev.copy()
    out[np.cumsum(marks, axis=1)[:, :-1] > 0] = 0
    return out


@dataclass(frozen=True)
class VehicleFilter:
    """The cues for one detector view, with their per-row geometry computed once."""

    preprocess: object  # detectors.config.Preprocess
    px_per_m: np.ndarray  # per working ROI row
    max_cols: np.ndarray  # per bird's-eye row

    @classmethod
    def of(cls, view: BirdsEye, preprocess) -> VehicleFilter:
        roi_rows = max(1, int(round((view.camera.height - view.crop_top) * view.scale)))
        return cls(preprocess, roi_px_per_m(view, roi_rows),
                   max_run_cols(view, preprocess.max_paint_width_m, preprocess.paint_blur_px))

    def covered(self, grey: np.ndarray) -> np.ndarray | None:
        """Bool mask of the working ROI (its grey levels) where no paint can be: what vehicles
        cover and what lies beside vehicle-dark; None when the cue is off."""
        p = self.preprocess
        if p.vehicle_dark_ratio <= 0.0 or len(self.px_per_m) != grey.shape[0]:
            return None
        dark = vehicle_dark(grey, p.vehicle_dark_ratio)
        hidden = hidden_by_vehicles(dark, self.px_per_m, p.vehicle_min_width_m,
                                    p.vehicle_max_width_m, p.vehicle_margin_m)
        # Paint lies on the road: a bright ridge beside something vehicle-dark (a hub cap in
        # its tyre, a chrome strip under a window) is not paint.
        near = cv2.dilate(dark.view(np.uint8), np.ones((1, 2 * p.vehicle_edge_px + 1), np.uint8))
        out = near > 0
        if hidden is not None:
            out |= hidden
        return out

    def narrow(self, bev: np.ndarray) -> np.ndarray:
        """The binary bird's-eye view without runs wider than paint."""
        if self.preprocess.max_paint_width_m <= 0.0:
            return bev
        return drop_wide_runs(bev, self.max_cols)
