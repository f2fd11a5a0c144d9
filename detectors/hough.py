"""Paper 001 model #1: ROI, binarisation, bird's-eye view, Hough transform, nearest-row centre.

Pipeline per frame: crop the image below the ground window's far edge and work at reduced
resolution; binarise by brightness against the road beside each pixel on both sides (a ridge
test relative to the local light, so that shaded paint passes and a shoulder's edge does not)
and a dark floor; warp to the bird's-eye view of the camera model; find segments with OpenCV's
probabilistic Hough transform; keep segments near the driving direction, seed one line per
cluster of the segments nearest the car (clustered by their lateral position at the near edge,
across the whole view) and grow each line outwards with segments that continue its fit; fit
y(x) per line; the car's pair and the other lanes' lines among them by lane geometry
(detectors/lane_lines.py). The offset is the lane centre at the view's row nearest the car.
Being brightness-based, it takes sunlit gaps between hard shadows for paint, which is the
weakness the paper reports.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from lanekeep.detectors.boundaries import Boundary, fit_boundary
from lanekeep.detectors.classical import ClassicalDetector
from lanekeep.detectors.image_stage import RegionOfInterest
from lanekeep.detectors.lane_lines import LaneLines, aligned, choose_lanes
from lanekeep.detectors.paper_thresholds import model1_paint
from lanekeep.detectors.ridge import paint_ridges
from lanekeep.geometry.lane_poly import LanePoly


class HoughDetector(ClassicalDetector):
    """Model #1 on one camera; stateless between frames."""

    default_name = "hough"
    settings_table = "hough"
    bird_eye_binarisation = "ridge"

    @property
    def bird_eye_max_fill(self) -> float:
        return self.config.ridge.max_fill

    # -- stages -------------------------------------------------------------------------------
    def bird_eye_mask(self, roi: RegionOfInterest, seen: np.ndarray) -> np.ndarray:
        """Ridges found in the bird's-eye view (`binarisation = "ridge"`, detectors/ridge.py);
        `"image"` (the default) and `"paper"` use `binarise` below instead."""
        w = self.view.window
        return paint_ridges(self.view.warp(roi.grey), seen, w.m_per_col, w.m_per_row,
                            self.config.ridge)

    def binarise(self, roi: RegionOfInterest) -> np.ndarray:
        """Paint candidates: narrow bright ridges, brighter than the road on BOTH sides of them
        (a paint width away along the row) by a share of it (adaptive_ratio), by at least
        adaptive_c grey levels, and above min_grey.

        The threshold scales with the local light: paint in shade keeps its contrast ratio to
        the asphalt (about 1.5-1.8) but not its level or its difference (a shaded line can be
        darker than the sunlit road), so a fixed offset or floor loses it. The absolute
        offset only keeps sensor noise on a dark road out. Its reference is the road beside
        the pixel, not a block mean: a mean over the paint and a bright gravel shoulder next
        to it rises above faint sunlit paint, and the sunlit edge of a shoulder (brighter than
        the asphalt on one side only) passes a mean but is no ridge.

        `binarisation = "paper"` (paper mode): the paper's fixed thresholds instead
        (detectors/paper_thresholds.py).
        """
        cfg = self.config.hough
        if cfg.binarisation == "paper":  # paper mode's fixed thresholds
            return model1_paint(roi.rgb, self.config.paper)
        grey = cv2.blur(roi.grey, (3, 3))  # a pixel's neighbours, not single grains
        side = self._ridge_reach(grey.shape[0])
        w = grey.shape[1]
        cols = np.arange(w)[None, :]
        left = np.take_along_axis(grey, np.maximum(cols - side, 0), axis=1)
        right = np.take_along_axis(grey, np.minimum(cols + side, w - 1), axis=1)
        road = np.maximum(left, right).astype(np.float32)
        level = np.maximum(road * (1.0 + cfg.adaptive_ratio), road + cfg.adaptive_c)
        paint = (grey > level) & (grey >= cfg.min_grey)
        return paint.view(np.uint8) * np.uint8(255)

    def _ridge_reach(self, rows: int) -> np.ndarray:
        """(rows, 1) columns from a pixel to the road beside it: the widest paint plus the
        blur at each ROI row, so that from anywhere on a stripe both reach off it."""
        px_per_m = self.vehicles.px_per_m  # per working ROI row, from the camera model
        if len(px_per_m) != rows:
            px_per_m = np.full(rows, float(px_per_m.max(initial=0.0)))
        p = self.config.preprocess
        reach = np.ceil(p.max_paint_width_m * px_per_m + p.paint_blur_px)
        return np.maximum(reach, 2).astype(np.intp)[:, None]

    def segments(self, bev: np.ndarray) -> np.ndarray:
        """Hough segments (N, 4) as vehicle-frame metres x1, y1, x2, y2, end 1 nearer the car."""
        cfg, w = self.config.hough, self.view.window
        lines = cv2.HoughLinesP(
            bev, cfg.rho_px, math.radians(cfg.theta_deg), cfg.votes,
            minLineLength=cfg.min_length_m / w.m_per_row, maxLineGap=cfg.max_gap_m / w.m_per_row,
        )
        if lines is None:
            return np.zeros((0, 4))
        c = lines.reshape(-1, 4).astype(float)
        x1, y1 = self.view.to_ground(c[:, 0], c[:, 1])
        x2, y2 = self.view.to_ground(c[:, 2], c[:, 3])
        seg = np.stack([x1, y1, x2, y2], axis=1)
        swap = (seg[:, 0] - w.x_near_m) * w.direction > (seg[:, 2] - w.x_near_m) * w.direction
        seg[swap] = seg[swap][:, [2, 3, 0, 1]]
        dx, dy = seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]
        keep = np.abs(np.arctan2(np.abs(dy), np.abs(dx))) <= math.radians(cfg.max_angle_deg)
        keep &= np.abs(dx) > 1e-6
        return seg[keep]

    def _samples(self, seg: np.ndarray) -> np.ndarray:
        """Points about every `sample_m` along each segment, both ends included, in order."""
        step = self.config.hough.sample_m
        if len(seg) == 0:
            return np.zeros((0, 2))
        counts = np.array([max(2, int(math.hypot(x2 - x1, y2 - y1) / step) + 1)
                           for x1, y1, x2, y2 in seg])
        # np.linspace(0, 1, n) of every segment in one pass: j * (1 / (n - 1)), the last 1.
        ends = np.cumsum(counts)
        j = np.arange(ends[-1], dtype=float) - np.repeat(ends - counts, counts)
        t = j * np.repeat(1.0 / (counts - 1), counts)
        t[ends - 1] = 1.0
        x1, y1, x2, y2 = np.repeat(seg, counts, axis=0).T
        return np.stack([x1 + t * (x2 - x1), y1 + t * (y2 - y1)], axis=1)

    def lines(self, seg: np.ndarray) -> list[Boundary]:
        """Every line in the view: seed one per cluster of near segments (by their lateral
        position at the near edge), grow each with the segments that continue its fit, fit."""
        cfg, rules, w = self.config.hough, self.config.lane, self.view.window
        near, d = w.x_near_m, w.direction
        if len(seg) == 0:
            return []
        dx, dy = seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]
        slope = dy / dx
        length = np.hypot(dx, dy)
        dist = (seg[:, 0] - near) * d
        # The lane's direction near the car: length-weighted median slope of the near segments
        # (a short segment's own slope is too noisy to extrapolate with).
        near_seg = dist <= cfg.seed_length_m
        pool = near_seg if near_seg.any() else np.ones(len(seg), bool)
        order = np.argsort(slope[pool])
        cum = np.cumsum(length[pool][order])
        heading = float(slope[pool][order][np.searchsorted(cum, cum[-1] / 2.0)])
        y_near = seg[:, 1] + (near - seg[:, 0]) * heading
        used = np.zeros(len(seg), bool)
        points: list[np.ndarray] = []
        cand = np.flatnonzero(near_seg)
        cand = cand[np.argsort(y_near[cand])]
        start = 0
        for i in range(1, len(cand) + 1):
            if i == len(cand) or y_near[cand[i]] - y_near[cand[i - 1]] > cfg.cluster_m:
                group = cand[start:i]
                if length[group].sum() >= 2.0 * cfg.min_length_m:
                    used[group] = True
                    points.append(self._samples(seg[group]))
                start = i
        # Grow outwards: a segment joins the line whose current fit it continues best. A
        # line's fit and reach change only when a segment joins it, so they are kept until
        # then (the fit is the grow loop's cost: one per line per segment otherwise).
        x_cam = float(self.camera.position_m[0])
        weighted = not self.bird_eye_paint
        fits = [fit_boundary(p, rules, x_cam, weighted) for p in points]
        current = [self._provisional(f, p, heading) for f, p in zip(fits, points, strict=True)]
        reached = [float((d * p[:, 0]).max()) for p in points]
        for j in np.argsort(dist):
            if used[j]:
                continue
            best, best_line = np.inf, -1
            x1, y1, x2, y2 = seg[j]
            far = max(d * x1, d * x2)
            for k, coeffs in enumerate(current):
                reach = max(0.0, far - reached[k])
                tol = cfg.grow_tolerance_m + 0.03 * reach
                lane = LanePoly.of(coeffs)
                res = max(abs(y1 - lane.y(x1)), abs(y2 - lane.y(x2)))
                if res < tol and res < best:
                    best, best_line = res, k
            if best_line >= 0:
                used[j] = True
                pts = np.concatenate([points[best_line], self._samples(seg[j : j + 1])])
                points[best_line] = pts
                fits[best_line] = fit_boundary(pts, rules, x_cam, weighted)
                current[best_line] = self._provisional(fits[best_line], pts, heading)
                reached[best_line] = float((d * pts[:, 0]).max())
        return [f for f in fits if f is not None]

    def boundaries(self, seg: np.ndarray) -> LaneLines:
        """The car's lane and the other lane lines among the segments' lines."""
        rules, w = self.config.lane, self.view.window
        chosen = choose_lanes(self.lines(seg), w.x_near_m, rules, self.lane_width_m,
                              self.config.hough.cluster_m)
        return aligned(chosen, rules, float(self.camera.position_m[0]))

    @staticmethod
    def _provisional(fit: Boundary | None, pts: np.ndarray, heading: float) -> np.ndarray:
        """The current guess of a growing boundary: its fit, or the lane direction through it."""
        if fit is not None:
            return fit.coeffs
        x0, y0 = pts.mean(axis=0)
        return np.array([y0 - heading * x0, heading, 0.0])

    def find_boundaries(self, bev: np.ndarray) -> LaneLines:
        return self.boundaries(self.segments(bev))
