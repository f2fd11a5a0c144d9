"""Paper 001 model #2: Sobel-x + saturation + hue thresholds, histogram, sliding windows.

Pipeline per frame: (undistortion folded into the bird's-eye warp when the camera has a
distortion model) ROI below the ground window's far edge at reduced resolution; binary =
(Sobel-x of HLS lightness) | (white: high lightness) | (yellow: hue in range and saturated),
all on a bright ridge; what other vehicles cover dropped (detectors/vehicle_mask.py);
bird's-eye warp; a column histogram of the near part of the view gives one start per side
(the peak nearest the car within the expected lane half-width); windows slide from the near
edge outwards, re-centring on their pixels; a 2nd-order y(x) per boundary in the
vehicle frame; the offset at the look-ahead. With a previous fit, pixels are taken in a band
around it instead (`reset()` forgets it). Fixed-size windows lose a boundary that bends out of
them faster than they can follow, which is this model's weakness in sharp turns.
"""

from __future__ import annotations

import cv2
import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.boundaries import Boundary, fit_boundary, parallel
from lanekeep.detectors.classical import ClassicalDetector
from lanekeep.detectors.edge_pairs import edge_pair_paint
from lanekeep.detectors.image_stage import RegionOfInterest
from lanekeep.detectors.paper_thresholds import model2_paint
from lanekeep.geometry.lane_poly import LanePoly

_KERNEL_3X3 = np.ones((3, 3), np.uint8)  # the ridge's dilation


class SlidingWindowDetector(ClassicalDetector):
    """Model #2 on one camera; remembers the last good fit to search around it."""

    default_name = "sliding_window"

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._previous: list[np.ndarray | None] = [None, None]
        # Lateral position (m) at the near edge of each bird's-eye column (the camera's left
        # is +): fixed by the view, read by every histogram search.
        cols = np.arange(self.view.cols)
        _, self._near_y = self.view.to_ground(cols, np.full(len(cols), self.view.rows - 1))

    def reset(self) -> None:
        """Forget the previous frame's fit and the measured width."""
        super().reset()
        self._previous = [None, None]

    @property
    def bird_eye_paint(self) -> bool:
        return self.config.sliding_window.binarisation == "edges"

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

    def _starts(self, bev: np.ndarray) -> list[float | None]:
        """Histogram peak column per side (left, right) nearest the car, or None.

        The histogram sums the near part of the view; a side without a peak there (a dashed
        line in its gap) is looked for again over the whole view.
        """
        cfg = self.config.sliding_window
        rows = int(round(self.view.rows * cfg.histogram_fraction))
        out = self._peaks(bev[-rows:])
        if None in out:
            again = self._peaks(bev)
            out = [a if a is not None else b for a, b in zip(out, again, strict=True)]
        return out

    def _peaks(self, part: np.ndarray) -> list[float | None]:
        cfg, rules, w = self.config.sliding_window, self.config.lane, self.view.window
        hist = (part > 0).sum(axis=0).astype(float)
        k = max(1, int(round(0.3 / w.m_per_col)))
        hist = np.convolve(hist, np.ones(k), mode="same")
        # The largest count within k columns either side of each column (the view's edges
        # cut the reach short): a column at least that high is a local maximum.
        padded = np.pad(hist, k, constant_values=-np.inf)
        local_max = np.lib.stride_tricks.sliding_window_view(padded, 2 * k + 1).max(axis=1)
        out: list[float | None] = []
        for side in (1.0, -1.0):
            lateral = side * self._near_y
            ok = ((lateral >= rules.min_half_width * rules.lane_width_m)
                  & (lateral <= rules.max_half_width * rules.lane_width_m)
                  & (hist >= cfg.min_peak_pixels))
            idx = np.flatnonzero(ok)
            if len(idx) == 0:
                out.append(None)
                continue
            # Local maxima among the allowed columns; take the nearest to the car.
            peaks = idx[hist[idx] >= local_max[idx]]
            if len(peaks) == 0:
                peaks = idx[[np.argmax(hist[idx])]]
            out.append(float(peaks[np.argmin(lateral[peaks])]))
        return out

    def _slide(self, start_col: float, ys: np.ndarray, xs: np.ndarray) -> np.ndarray:
        """Indices of the bird's-eye pixels (ys rows, xs cols) the sliding windows collect.

        `ys` ascend (np.nonzero's row-major order), so a window's rows are one slice of them.
        """
        cfg, w = self.config.sliding_window, self.view.window
        margin = cfg.margin_m / w.m_per_col
        height = self.view.rows / cfg.n_windows
        bottoms = self.view.rows - np.arange(cfg.n_windows) * height
        firsts = np.searchsorted(ys, bottoms - height)  # each window's first pixel (row >= top)
        ends = np.searchsorted(ys, bottoms)  # and the first past it (row >= bottom)
        centre, step = start_col, 0.0
        taken = []
        for first, end in zip(firsts, ends, strict=True):
            inside = first + np.flatnonzero(np.abs(xs[first:end] - centre) <= margin)
            taken.append(inside)
            if len(inside) >= cfg.min_pixels:
                new = float(xs[inside].mean())
                step, centre = new - centre, new
            else:
                centre += step  # keep drifting the way the line was going
        return np.concatenate(taken) if taken else np.zeros(0, int)

    def boundaries(self, bev: np.ndarray) -> tuple[Boundary | None, Boundary | None]:
        cfg, rules = self.config.sliding_window, self.config.lane
        ys, xs = np.nonzero(bev)
        gx, gy = self.view.to_ground(xs, ys)
        x_cam = float(self.camera.position_m[0])
        weighted = not self.bird_eye_paint
        fits: list[Boundary | None] = [None, None]
        starts = None
        for k, side in enumerate((1.0, -1.0)):
            prev = self._previous[k]
            if prev is not None:
                band = np.abs(gy - LanePoly.of(prev).y(gx)) <= cfg.search_margin_m
                if band.sum() >= cfg.min_fit_pixels:
                    fits[k] = fit_boundary(np.stack([gx[band], gy[band]], 1), rules, x_cam,
                                           weighted)
                    if fits[k] is not None:
                        continue
            if starts is None:
                starts = self._starts(bev)
            if starts[k] is None:
                continue
            idx = self._slide(starts[k], ys, xs)
            if len(idx) >= cfg.min_fit_pixels:
                fit = fit_boundary(np.stack([gx[idx], gy[idx]], 1), rules, x_cam, weighted)
                ok = fit is not None and side * fit.lane.y(self.view.window.x_near_m) > 0
                fits[k] = fit if ok else None
        return parallel(fits[0], fits[1], rules, x_cam)

    def find_boundaries(self, bev: np.ndarray) -> tuple[Boundary | None, Boundary | None]:
        return self.boundaries(bev)

    def remember(self, estimate: LaneEstimate) -> None:
        """A valid fit is where the next frame's pixels are looked for; else search afresh."""
        if estimate.valid:
            self._previous = [estimate.left, estimate.right]
        else:
            self._previous = [None, None]
