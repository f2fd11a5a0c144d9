"""The paper's own binarisations (paper 001 §2.2, Fig. 3): fixed thresholds on the frame's
grey levels, as the paper's models read it, kept apart from the default mode's tuned ones.

The paper names the cues, not their values: model #1 binarises the region of interest before
its bird's-eye view and Hough transform; model #2 thresholds "Sobel, Saturation, and Hue" and
is "similar to" Gaskey (2023). The values below are the ones in the authors' public code
(github.com/imanf94/LaneDetection-MMAE, read 2026-11-29; nothing of it is copied here),
except the white level, which is this world's (detectors/config.py `PaperThresholds`):

* model #1, `lane.py`'s markings: HLS lightness at least the white level (theirs 200), or HLS
  saturation at least 80 on a red channel at least 120 (yellow). Its Sobel step runs on the
  lightness mask itself and only keeps that mask's edges, so it is left out: the mask is the
  paint the edges bound.
* model #2, `adv_lane.py` (Gaskey's thresholds): |Sobel-x| of the grey image at least 30/255
  of the image's largest, or grey at least the white level (theirs above 200), or HLS
  saturation above 90, or OpenCV hue in (10, 25] (yellow).

All are absolute levels of an 8-bit frame, not shares of the local light: shaded paint that
falls below them is lost, and a bright patch of road that rises above them is taken for
paint. That is the weakness the paper reports for model #1 in hard shadows (its §3); the
default mode's models compare paint with the road beside it instead (detectors/hough.py,
detectors/sliding_window.py).
"""

from __future__ import annotations

import cv2
import numpy as np

from lanekeep.detectors.config import PaperThresholds

PAPER_THRESHOLDS = PaperThresholds()


def model1_paint(rgb: np.ndarray, t: PaperThresholds = PAPER_THRESHOLDS) -> np.ndarray:
    """Model #1's binary image (0/255) of an RGB region of interest."""
    _, light, sat = cv2.split(cv2.cvtColor(rgb, cv2.COLOR_RGB2HLS))
    red = rgb[..., 0]
    paint = (light >= t.white_level) | ((sat >= t.model1_saturation) & (red >= t.model1_red))
    return paint.view(np.uint8) * np.uint8(255)


def model2_paint(rgb: np.ndarray, t: PaperThresholds = PAPER_THRESHOLDS) -> np.ndarray:
    """Model #2's binary image (0/255) of an RGB region of interest."""
    grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    hue, _, sat = cv2.split(cv2.cvtColor(rgb, cv2.COLOR_RGB2HLS))
    sobel = np.abs(cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3))
    largest = float(sobel.max())
    paint = (sobel >= t.model2_sobel_share * largest) if largest > 0 else np.zeros_like(grey, bool)
    paint |= grey >= t.white_level
    paint |= sat > t.model2_saturation
    lo, hi = t.model2_hue
    paint |= (hue > lo) & (hue <= hi)
    return paint.view(np.uint8) * np.uint8(255)
