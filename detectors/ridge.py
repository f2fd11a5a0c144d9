"""Paint as a faint ridge on the ground: a matched filter in the bird's-eye view.

In the bird's-eye view a lane line is a narrow stripe running along the rows, a little
brighter than the road on both sides of it. On concrete, in fog or at night that step is only
10-20% of the road's brightness, the same size as the road's own texture, so no per-pixel
threshold separates them. What does is that paint keeps its step along the line: averaged
over a metre or two of its length the stripe stands out and the texture averages away. This is
the filter of Aly's Caltech lane detector (IEEE IV 2008: inverse perspective, then a kernel
that is a Gaussian along the road and a second derivative across it, then a quantile
threshold), written here with two changes:

- the step is measured against the BRIGHTER of the two road bands beside the stripe (a paint
  width away on each side), so the sunlit edge of a shoulder, bright on one side only, is no
  ridge; and it is divided by that road level, so a
  stripe in shade keeps its ratio and passes with the same threshold as one in sun;
- the along-line average is taken over a few headings (line kernels leaning up to
  `max_lean` columns per row) and the best one kept, so that boundaries curving or seen at an
  angle (lane changes) are integrated along themselves, not across.

The result is thinned to the crest of each stripe across the row (its brightest column within
a paint width), so that Hough sees one line per stripe.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np


@functools.lru_cache(maxsize=64)
def _shears(rows: int, cols: int, lean: float) -> tuple[tuple, tuple]:
    """cv2.remap maps that shear an image by `lean` columns per row (lines of that lean
    become vertical) and back; columns past the edges repeat the edge."""
    shift = np.round(lean * (np.arange(rows) - (rows - 1) / 2.0))[:, None]
    c = np.arange(cols, dtype=np.float64)[None, :]
    r = np.broadcast_to(np.arange(rows, dtype=np.float32)[:, None], (rows, cols))

    def maps(col: np.ndarray) -> tuple:
        return np.clip(col, 0, cols - 1).astype(np.float32), np.ascontiguousarray(r)

    return maps(c + shift), maps(c - shift)


def leans(max_lean: float, n: int) -> np.ndarray:
    """The `n` leans (columns per row) tried, from -max_lean to +max_lean."""
    return np.linspace(-max_lean, max_lean, n) if n > 1 else np.zeros(1)


def along_line(image: np.ndarray, length_rows: int, lean: float) -> np.ndarray:
    """The mean of `image` (H, W) or (H, W, C) over `length_rows` rows along lines leaning
    `lean` columns per row, centred on each pixel: sheared upright, a vertical box mean (one
    pass, whatever the length), sheared back. Rows past the top and bottom repeat the edge
    row, so a line reaching the view's edge runs on past it."""
    forward, back = _shears(image.shape[0], image.shape[1], float(lean))
    upright = cv2.remap(image, *forward, cv2.INTER_NEAREST)
    mean = cv2.blur(upright, (1, length_rows), borderType=cv2.BORDER_REPLICATE)
    return cv2.remap(mean, *back, cv2.INTER_NEAREST)


def ridge_strength(grey_bev: np.ndarray, valid: np.ndarray, gap_cols: int, band_cols: int,
                   length_rows: int, max_lean: float, n_leans: int, dark_floor: float,
                   own_ratio: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(relative step, step in grey levels, grey level) of the best along-line average at
    each pixel.

    step = grey - brighter road band beside it (each band `band_cols` wide, its centre
    `gap_cols` away); relative = average step / average road level over the same line kernel.
    Pixels whose bands leave the image (`valid` False) get no step.
    """
    g = grey_bev.astype(np.float32)
    side = cv2.blur(g, (band_cols, 1), borderType=cv2.BORDER_REPLICATE)
    left = np.empty_like(side)
    right = np.empty_like(side)
    left[:, gap_cols:] = side[:, :-gap_cols]
    left[:, :gap_cols] = 0.0
    right[:, :-gap_cols] = side[:, gap_cols:]
    right[:, -gap_cols:] = 0.0
    road = np.maximum(left, right)
    reach = gap_cols + band_cols // 2 + 1
    ok = cv2.erode(valid.view(np.uint8), np.ones((1, 2 * reach + 1), np.uint8)).view(bool)
    step = np.where(ok, g - road, 0.0).astype(np.float32)
    road = np.where(ok, road, 0.0).astype(np.float32)
    # The pixel's own step, over a few rows only: the line average runs past a dash's end
    # (and leans to reach the next), so only pixels on the stripe itself may be paint.
    own = cv2.blur(step, (1, 3))
    best_rel = np.zeros_like(g)
    best_step = np.zeros_like(g)
    best_grey = np.zeros_like(g)
    both = np.dstack([step, road])
    for lean in leans(max_lean, n_leans):
        averaged = along_line(both, length_rows, lean)
        s, r = averaged[..., 0], averaged[..., 1]
        rel = s / np.maximum(r, dark_floor)
        better = rel > best_rel
        best_rel[better] = rel[better]
        best_step[better] = s[better]
        best_grey[better] = (s + r)[better]  # the averaged grey level itself
    best_rel[own <= own_ratio * np.maximum(road, dark_floor)] = 0.0
    return best_rel, best_step, best_grey


def grain(grey: np.ndarray) -> float:
    """Median |grey - its 3x3 mean| over the median grey level (10 at least): sensor-noise
    speckle, against which roads, shade and weather stay low (RidgeConfig.max_grain)."""
    g = grey.astype(np.float32)
    fine = np.abs(g - cv2.blur(g, (3, 3)))[::2, ::2]  # every 4th pixel: a median of many
    return float(np.median(fine)) / max(float(np.median(g[::2, ::2])), 10.0)


def crest(strength: np.ndarray, reach_cols: int) -> np.ndarray:
    """Pixels that are the largest within `reach_cols` either side along their row."""
    size = 2 * reach_cols + 1
    peak = cv2.dilate(strength, np.ones((1, size), np.uint8))
    return strength >= peak


def paint_ridges(grey_bev: np.ndarray, valid: np.ndarray, m_per_col: float, m_per_row: float,
                 config) -> np.ndarray:
    """Binary bird's-eye mask (0/255) of paint ridges (the module docstring), by `config`
    (detectors.config.RidgeConfig)."""
    gap = max(1, int(round(config.gap_m / m_per_col)))
    band = max(1, int(round(config.band_m / m_per_col)))
    length = max(1, int(round(config.length_m / m_per_row)) | 1)
    # A heading of h (m across per m along) leans h * m_per_row / m_per_col columns a row.
    lean = config.max_heading * m_per_row / m_per_col
    rel, step, grey = ridge_strength(grey_bev, valid, gap, band, length, lean, config.leans,
                                     config.dark_floor, config.own_ratio)
    paint = (rel >= config.min_ratio) & (step >= config.min_step)
    # The crest of the stripe's own brightness, not of its step: beside a bright shoulder the
    # step peaks where the road band leaves the shoulder, a column or two off the paint.
    paint &= crest(np.where(paint, grey, 0.0).astype(np.float32), max(1, gap // 2))
    return paint.view(np.uint8) * np.uint8(255)
