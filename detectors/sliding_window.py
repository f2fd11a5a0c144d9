"""Paper 001 model #2: Sobel-x + saturation + hue thresholds, histogram, sliding windows.

Pipeline per frame: (undistortion folded into the bird's-eye warp when the camera has a
distortion model) ROI below the ground window's far edge at reduced resolution; binary =
(Sobel-x of HLS lightness) | (white: high lightness) | (yellow: hue in range and saturated),
all on a bright ridge; what other vehicles cover dropped (detectors/vehicle_mask.py);
bird's-eye warp; a column histogram of the near part of the view gives the starts (every
peak across the view, the strongest first, skipping those on a line already found); windows
slide from the near edge outwards, re-centring on their pixels; a 2nd-order y(x) per line in
the vehicle frame; the car's pair and the other lanes' lines among them by lane geometry
(detectors/lane_lines.py); the offset at the look-ahead. With a previous fit, the car's
boundaries are first looked for in a band around it (`reset()` forgets it). Fixed-size
windows lose a boundary that bends out of them faster than they can follow, which is this
model's weakness in sharp turns.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.boundaries import Boundary, fit_boundary
from lanekeep.detectors.classical import ClassicalDetector
from lanekeep.detectors.edge_pairs import edge_pair_paint
from lanekeep.detectors.image_stage import RegionOfInterest
from lanekeep.detectors.lane_lines import LaneLines, aligned, choose_lanes
from lanekeep.detectors.paper_thresholds import model2_paint
from lanekeep.geometry.lane_poly import LanePoly

_KERNEL_3X3 = np.ones((3, 3), np.uint8)  # the ridge's dilation


@dataclass(frozen=True)
class _Windows:
    """One frame's sliding windows over its bird's-eye pixels (in row order): each window's
    first and past-the-last pixel, the window of each pixel (n_windows for a pixel in none),
    and each window's pixel count and column sum cumulated over the columns (k, cols + 1)."""

    firsts: np.ndarray
    ends: np.ndarray
    of_pixel: np.ndarray
    counts: np.ndarray
    col_sums: np.ndarray


class SlidingWindowDetector(ClassicalDetector):
    """Model #2 on one camera; remembers the last good fit to search around it."""

    default_name = "sliding_window"
    settings_table = "sliding_window"
    bird_eye_binarisation = "edges"

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._previous: list[np.ndarray | None] = [None, None]
        # Ground x (m) of each row the histogram sums (the near part of the view): fixed by
        # the view, read for every peak `_explained` tests.
        n = self.view.rows - int(round(self.view.rows * self.config.sliding_window
                                       .histogram_fraction))
        rows = np.arange(n, self.view.rows)
        self._histogram_x, _ = self.view.to_ground(np.zeros(len(rows)), rows)
        # This frame's found lines' histogram columns, by the line's id (`_histogram_cols`);
        # emptied at each frame's line search, while those lines are alive.
        self._line_cols: dict[int, np.ndarray] = {}

    def reset(self) -> None:
        """Forget the previous frame's fit and the measured width."""
        super().reset()
        self._previous = [None, None]

    # -- stages -------------------------------------------------------------------------------
    def bird_eye_mask(self, roi: RegionOfInterest, seen: np.ndarray) -> np.ndarray:
        """The cues read in the bird's-eye view (`binarisation = "edges"`,
        detectors/edge_pairs.py); `"image"` (the default) uses `binarise` below instead."""
        hls = self.view.warp(cv2.cvtColor(roi.rgb, cv2.COLOR_RGB2HLS))
        w = self.view.window
        return edge_pair_paint(hls, seen, w.m_per_col, w.m_per_row, self.config.sliding_window)

    def binarise(self, roi: RegionOfInterest) -> np.ndarray:
        """Sobel-x on lightness | white lightness (both on a bright ridge) | yellow hue+sat;
        with `binarisation = "paper"` (paper mode) the paper's fixed thresholds instead
        (detectors/paper_thresholds.py)."""
        cfg = self.config.sliding_window
        if cfg.binarisation == "paper":
            return model2_paint(roi.rgb, self.config.paper)
        # Contiguous planes: every test below reads them, and a strided view costs each one.
        hue, raw, sat = cv2.split(cv2.cvtColor(roi.rgb, cv2.COLOR_RGB2HLS))
        row = np.ones((1, cfg.local_block_px), np.uint8)
        # A ridge is brighter than the darker of its row neighbours a block away (white
        # top-hat along the row): paint narrower than the block is, the lit edge of anything
        # wider (a snowy verge, the sunny side of a shadow's edge) is not. Measured on the
        # raw lightness and then scaled by the shade gain: the gain itself changes across a
        # shadow's edge and would make a bright halo on its dark side (a ridge along every
        # long straight edge of a vehicle's shadow, parallel to the lane).
        tophat = cv2.morphologyEx(raw, cv2.MORPH_TOPHAT, row)
        light = raw
        if cfg.illumination_max_gain > 1.0 or cfg.illumination_min_gain < 1.0:
            light, gain = self._compensate_shade(raw)
            ridge = tophat.astype(np.float32) * gain >= cfg.min_lightness_gain
        else:
            ridge = tophat >= cfg.min_lightness_gain
        grad = np.abs(cv2.Sobel(light, cv2.CV_16S, 1, 0, ksize=cfg.sobel_kernel))
        norm = {1: 1.0, 3: 4.0, 5: 48.0 / 4.0, 7: 640.0 / 10.0}[cfg.sobel_kernel]
        ridge = cv2.dilate(ridge.view(np.uint8), _KERNEL_3X3).view(bool)
        # Each cue must sit on the ridge: one test of the ridge for all three.
        paint = grad >= cfg.sobel_min * norm
        # White paint is a bright ridge too: a snowy verge or a sunlit kerb is as light as
        # paint but as wide as the local block, so it reads as the background, not a stripe.
        paint |= (light >= cfg.white_lightness) & (sat <= cfg.white_saturation_max)
        lo, hi = cfg.yellow_hue
        # Yellow paint is a ridge as well: a yellow car's body is as yellow but wider.
        paint |= ((hue >= lo) & (hue <= hi) & (sat >= cfg.yellow_saturation)
                  & (light >= cfg.yellow_lightness))
        paint &= ridge
        return paint.view(np.uint8) * np.uint8(255)

    def _compensate_shade(self, light: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lightness scaled so the local background reads the configured target level, and
        the gain per pixel. A gain below 1 dims a bright road too, so that the white and
        gradient thresholds are shares of the local light in sun and shade alike."""
        cfg = self.config.sliding_window
        block = (cfg.illumination_block_px, cfg.illumination_block_px)
        gain = cv2.blur(light, block).astype(np.float32)  # the background, then its gain
        np.maximum(gain, 1.0, out=gain)
        np.divide(cfg.illumination_target, gain, out=gain)
        np.clip(gain, cfg.illumination_min_gain, cfg.illumination_max_gain, out=gain)
        scaled = light.astype(np.float32)
        scaled *= gain
        np.clip(scaled, 0, 255, out=scaled)
        return scaled.astype(np.uint8), gain

    def _starts(self, ys: np.ndarray, xs: np.ndarray) -> list[float]:
        """Histogram peak columns across the view, the strongest first.

        The histogram sums the near part of the view; the whole view's peaks are added where
        the near part has none within a cluster's width (a dashed line in its gap there).
        """
        cfg, w = self.config.sliding_window, self.view.window
        rows = int(round(self.view.rows * cfg.histogram_fraction))
        near = np.searchsorted(ys, self.view.rows - rows)  # pixels in row order
        out = self._peaks(np.bincount(xs[near:], minlength=self.view.cols))
        gap = self.config.hough.cluster_m / w.m_per_col
        for col, count in self._peaks(np.bincount(xs, minlength=self.view.cols)):
            if all(abs(col - c) > gap for c, _ in out):
                out.append((col, count))
        return [c for c, _ in sorted(out, key=lambda p: -p[1])]

    def _peaks(self, counts: np.ndarray) -> list[tuple[float, float]]:
        """(column, smoothed count) of the local maxima, with `min_peak_pixels` or more, of
        a histogram of paint pixels per column."""
        cfg, w = self.config.sliding_window, self.view.window
        hist = counts.astype(float)
        k = max(1, int(round(0.3 / w.m_per_col)))
        hist = np.convolve(hist, np.ones(k), mode="same")
        # The largest count within k columns either side of each column (the view's edges
        # cut the reach short): a column at least that high is a local maximum. A grey
        # dilation along the row (float32 holds these whole counts exactly).
        local_max = cv2.dilate(hist.astype(np.float32)[None, :], np.ones((1, 2 * k + 1), np.uint8),
                               borderType=cv2.BORDER_CONSTANT, borderValue=-1.0)[0]
        peaks = np.flatnonzero((hist >= cfg.min_peak_pixels) & (hist >= local_max))
        if len(peaks) == 0:
            return []
        # A flat top is one peak: keep the first column of each run of adjacent ones.
        peaks = peaks[np.concatenate([[True], np.diff(peaks) > k])]
        return [(float(c), float(hist[c])) for c in peaks]

    def _explained(self, col: float, lines: list[Boundary]) -> bool:
        """Whether a histogram peak at `col` lies on a line already found: within a cluster's
        width of it on some row the histogram summed (a line slanting across the view, in a
        turn or at a heading, piles up peaks all along its way)."""
        if not lines:
            return False
        gap = self.config.hough.cluster_m / self.view.window.m_per_col
        return any(np.min(np.abs(self._histogram_cols(b) - col)) <= gap for b in lines)

    def _histogram_cols(self, line: Boundary) -> np.ndarray:
        """The bird's-eye column of `line` on each row the histogram sums (kept per line: every
        later peak asks again)."""
        cols = self._line_cols.get(id(line))
        if cols is None:
            x = self._histogram_x
            cols, _ = self.view.to_pixels(x, line.lane.y(x))
            self._line_cols[id(line)] = cols
        return cols

    def _windows(self, ys: np.ndarray, xs: np.ndarray) -> _Windows:
        """The sliding windows' rows, the pixels in each and their counts per column: once a
        frame, for every slide (`_slide`)."""
        n_windows = self.config.sliding_window.n_windows
        height = self.view.rows / n_windows
        bottoms = self.view.rows - np.arange(n_windows) * height
        firsts = np.searchsorted(ys, bottoms - height)  # each window's first pixel (row >= top)
        ends = np.searchsorted(ys, bottoms)  # and the first past it (row >= bottom)
        cols = self.view.cols
        of_pixel = np.full(len(xs), n_windows)
        for k, (first, end) in enumerate(zip(firsts, ends, strict=True)):
            of_pixel[first:end] = k
        # Each pixel counted in its window's row of columns (a leading empty column; the
        # pixels in no window in a last row, dropped).
        counts = np.bincount(of_pixel * (cols + 1) + xs + 1, minlength=(n_windows + 1) * (cols + 1))
        counts = counts.reshape(n_windows + 1, cols + 1)[:n_windows]
        # Cumulated along the row after a leading 0: a band of columns' count and column sum
        # are two differences.
        col_sums = np.cumsum(counts * np.arange(-1, cols), axis=1)
        return _Windows(firsts, ends, of_pixel, np.cumsum(counts, axis=1), col_sums)

    def _slide(self, start_col: float, windows: _Windows, xs: np.ndarray) -> np.ndarray:
        """Indices of the bird's-eye pixels (columns `xs`) the sliding windows collect, the
        near window's first: from the near edge outwards, each window takes the pixels within
        the margin of its centre and re-centres on their mean column when there are enough
        of them, else keeps drifting the way the line was going."""
        cfg, w = self.config.sliding_window, self.view.window
        margin = cfg.margin_m / w.m_per_col
        n_windows, last = len(windows.firsts), windows.counts.shape[1] - 2
        lows = np.ones(n_windows + 1, np.int64)  # each window's columns lows..highs; none
        highs = np.zeros(n_windows + 1, np.int64)  # for the pixels in no window
        centre, step = start_col, 0.0
        for k in range(n_windows):
            lo = max(math.ceil(centre - margin), 0)
            hi = min(math.floor(centre + margin), last)
            n = int(windows.counts[k, hi + 1] - windows.counts[k, lo]) if hi >= lo else 0
            lows[k], highs[k] = lo, hi
            if n >= cfg.min_pixels:
                new = float(windows.col_sums[k, hi + 1] - windows.col_sums[k, lo]) / n
                step, centre = new - centre, new
            else:
                centre += step
        inside = np.flatnonzero((xs >= lows[windows.of_pixel]) & (xs <= highs[windows.of_pixel]))
        # Rows ascend, so the far window's pixels come first: put the near window's first.
        cuts_first = np.searchsorted(inside, windows.firsts)
        cuts_end = np.searchsorted(inside, windows.ends)
        return np.concatenate([inside[a:b] for a, b in zip(cuts_first, cuts_end, strict=True)])

    def boundaries(self, bev: np.ndarray) -> LaneLines:
        """The car's lane and the other lane lines: each remembered boundary looked for in a
        band around its last fit, every other line from a histogram peak by sliding windows."""
        cfg, rules, w = self.config.sliding_window, self.config.lane, self.view.window
        ys, xs = np.nonzero(bev)
        gx, gy = self.view.to_ground(xs, ys)
        x_cam = float(self.camera.position_m[0])
        weighted = not self.bird_eye_paint
        found: list[Boundary] = []
        for prev in self._previous:
            if prev is None:
                continue
            band = np.abs(gy - LanePoly.of(prev).y(gx)) <= cfg.search_margin_m
            if band.sum() >= cfg.min_fit_pixels:
                fit = fit_boundary(np.stack([gx[band], gy[band]], 1), rules, x_cam, weighted)
                if fit is not None:
                    found.append(fit)
        gap = self.config.hough.cluster_m
        windows = self._windows(ys, xs)
        self._line_cols.clear()
        for start in self._starts(ys, xs):
            if self._explained(start, found):
                continue  # that line is found already
            idx = self._slide(start, windows, xs)
            if len(idx) >= cfg.min_fit_pixels:
                fit = fit_boundary(np.stack([gx[idx], gy[idx]], 1), rules, x_cam, weighted)
                if fit is not None:
                    found.append(fit)
        chosen = choose_lanes(found, w.x_near_m, rules, self.lane_width_m, gap)
        return aligned(chosen, rules, x_cam)

    def find_boundaries(self, bev: np.ndarray) -> LaneLines:
        return self.boundaries(bev)

    def remember(self, estimate: LaneEstimate) -> None:
        """A valid fit is where the next frame's pixels are looked for; else search afresh."""
        if estimate.valid:
            self._previous = [estimate.left, estimate.right]
        else:
            self._previous = [None, None]
