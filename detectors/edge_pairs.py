"""Model #2's cues in the bird's-eye view: Sobel edge pairs and yellow, averaged along lines.

Paper 001's model #2 marks paint by the Sobel-x gradient of lightness and by saturation and
hue. Per pixel those cues fail where paint is faint (concrete, fog, night: the gradient of a
stripe 10-20% over the road is the size of the texture's), so here they are read in the
bird's-eye view, where a boundary runs along the rows and each cue can be averaged over a
metre or two of its length (along lines leaning up to a heading, the best kept, as in
detectors/ridge.py):

- a stripe is a RISING lightness edge followed, a paint width to the right, by a FALLING
  one: the weaker of the two averaged gradients, divided by the road's lightness (so shade
  keeps the ratio), must pass a threshold; a shadow's or a shoulder's edge is a single edge
  and passes neither way;
- yellow paint: the share of pixels along the line with the hue, saturation and lightness
  of yellow paint.

Unlike model #1's ridge (the stripe against the road bands beside it, thinned to its crest)
the mask keeps the stripe's width: the sliding windows average pixel positions, and a
boundary needs pixels to be fitted. The two models so read paint by different tests, as the
paper's do, and fail in different places.
"""

from __future__ import annotations

import cv2
import numpy as np

from lanekeep.detectors.ridge import along_line, leans


def _shift(image: np.ndarray, cols: int) -> np.ndarray:
    """`image` moved `cols` columns right (negative: left), zeros shifted in."""
    out = np.zeros_like(image)
    if cols > 0:
        out[:, cols:] = image[:, :-cols]
    elif cols < 0:
        out[:, :cols] = image[:, -cols:]
    else:
        out[:] = image
    return out


def edge_pair_paint(hls_bev: np.ndarray, valid: np.ndarray, m_per_col: float,
                    m_per_row: float, config) -> np.ndarray:
    """Binary bird's-eye mask (0/255) of model #2's paint (the module docstring), by
    `config` (detectors.config.SlidingWindowConfig's edge settings)."""
    hue, light, sat = (hls_bev[..., k] for k in range(3))
    lf = light.astype(np.float32)
    ok = cv2.erode(valid.view(np.uint8), np.ones((3, 5), np.uint8)).view(bool)
    grad = cv2.Sobel(lf, cv2.CV_32F, 1, 0, ksize=3) / 4.0  # grey levels per column
    grad[~ok] = 0.0
    level = cv2.blur(np.where(ok, lf, 0.0).astype(np.float32), (31, 1))
    weight = cv2.blur(ok.astype(np.float32), (31, 1))
    level = level / np.maximum(weight, 1e-3)
    half = max(1, int(round(config.edge_half_width_m / m_per_col)))
    length = max(1, int(round(config.edge_length_m / m_per_row)) | 1)
    max_lean = config.edge_max_heading * m_per_row / m_per_col
    lo, hi = config.yellow_hue
    yellow = ((hue >= lo) & (hue <= hi) & (sat >= config.yellow_saturation)
              & (light >= config.yellow_lightness) & ok).astype(np.float32)
    paint = np.zeros(lf.shape, bool)
    needed = np.maximum(np.maximum(level, config.edge_dark_floor) * config.edge_ratio,
                        config.edge_min_step)
    any_yellow = bool(yellow.any())  # most roads have none: half the work then
    cues = np.dstack([grad, yellow]) if any_yellow else grad
    for lean in leans(max_lean, config.edge_leans):
        averaged = along_line(cues, length, lean)
        g = averaged[..., 0] if any_yellow else averaged
        # rising edge `half` columns left of the pixel, falling edge `half` right of it
        pair = np.minimum(_shift(g, half), -_shift(g, -half))
        paint |= pair >= needed
        if any_yellow:
            paint |= averaged[..., 1] >= config.yellow_share
    paint &= ok
    return paint.view(np.uint8) * np.uint8(255)
