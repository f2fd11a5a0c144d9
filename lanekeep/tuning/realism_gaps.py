"""The statistics of issue #59's four gaps between our frames and real ones: tone (dark
share, darkest percentile), vegetation (saturated green's share, brightness, texture), layout
(open sky above the horizon) and road structure (edges in the road area that are not paint).

Like `lanekeep.tuning.realism`, each is a small pure function of an RGB uint8 image (and a
horizon row, a paint mask), the same definition for renders and photos, defined in its
docstring; `gap_stats` measures them at the work width. They are for SEEING the gaps, not a
target to fit.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from lanekeep.tuning.realism import (
    MIN_PIXELS,
    canny_edges,
    luma,
    road_area_mask,
    split_row,
    to_work_size,
)

# Tone: "dark" is luma below 40 DN (deep shade, tyres, dark cars, the underside of things);
# the darkest end is the luma's 1st percentile.
DARK_DN, DARK_PERCENTILE = 40.0, 1.0

# Saturated green, in OpenCV's 8-bit HSV (H 0..180 = 0..360 deg, S and V 0..255): hue 70 to
# 170 deg (yellow-green to cyan-green; dry grass at ~45 deg is not green), saturation at
# least 0.25, value at least 20 (below, hue and saturation are noise). Measured on the frame
# shrunk to 320 px wide (INTER_AREA), the scale of a contact-sheet tile, at which the texture
# is that of leaf clumps and grass tufts rather than of the lens blur.
GREEN_HUE_LO, GREEN_HUE_HI, GREEN_MIN_SAT, GREEN_MIN_V = 35, 85, 0.25 * 255, 20
GREEN_WIDTH = 320

# Open sky, on the frame after a 5x5 median filter (it erases wires and lines up to 2 px
# thick, which would otherwise cut the sky in two): smooth (local std of the sigma-1.5 luma in
# a 9x9 window below 6 DN), bright (luma at least 100: a night sky does not count) and
# blue-ish (B >= R + 15 and B >= G) or grey (HSV saturation at most 0.20: overcast, fog); a
# 5x5 closing bridges what is left of thin poles; the parts touching the frame's top edge are
# kept and the holes they enclose (clouds, whose edges are not smooth) filled.
SKY_MEDIAN_PX, SKY_SMOOTH_STD, SKY_WINDOW, SKY_MIN_LUMA = 5, 6.0, 9, 100.0
SKY_BLUE_MARGIN, SKY_GREY_MAX_SAT, SKY_CLOSE_PX = 15, 0.20, 5

# Road structure: Canny edges at lower thresholds than the edge statistics' 50/150, so that
# the low-contrast seams and tar lines of real roads count; paint and PAINT_MARGIN_PX +
# PAINT_MARGIN_PER_ROW * (rows below the horizon) px around it are left out. On flat ground a
# row d rows below the horizon spans about d / h px per metre across (h: camera height, m), so
# at h = 1.5 m the margin is about 0.09 m of road plus 3 px (label error, blur and Canny's
# own spread) either side of the paint.
# The region is the road area (`realism.road_area_mask`) above 88% of the frame's height: our
# car's hood rises to about 91% at the centre column, Udacity's to about 93%.
ROAD_CANNY_LOW, ROAD_CANNY_HIGH, ROAD_EDGES_BOTTOM_SHARE = 20, 60, 0.88
PAINT_MARGIN_PX, PAINT_MARGIN_PER_ROW = 3.0, 0.06
# Paint guessed where nothing labels it: a ridge brighter than the road on BOTH sides, by at
# least 20 DN over the brighter side, the sides RIDGE_PX + RIDGE_PER_ROW * (rows below the
# horizon) px away along the row (beyond a 0.15 m line's half width plus its blur); or
# yellow (hue 30..70 deg, saturation >= 0.35, value >= 100).
RIDGE_PX, RIDGE_PER_ROW, RIDGE_MIN_DN = 4.0, 0.1, 20.0
YELLOW_HUE_LO, YELLOW_HUE_HI, YELLOW_MIN_SAT, YELLOW_MIN_V = 15, 35, 0.35 * 255, 100


# -- tone --------------------------------------------------------------------------------------
def dark_stats(rgb: np.ndarray) -> dict[str, float]:
    """Dark share: the share of the whole frame's pixels with luma (Rec. 601) below 40 DN;
    dark p1: the luma's 1st percentile (DN). Real photos hold deep shade and black details that
    a render lit by a bright ambient term lacks."""
    y = luma(rgb)
    return {"dark_share": float((y < DARK_DN).mean()),
            "dark_p1": float(np.percentile(y, DARK_PERCENTILE))}


# -- vegetation --------------------------------------------------------------------------------
def hsv(rgb: np.ndarray) -> np.ndarray:
    """OpenCV's 8-bit HSV of an RGB uint8 image: H 0..180 (degrees / 2), S and V 0..255."""
    return cv2.cvtColor(np.ascontiguousarray(rgb, dtype=np.uint8), cv2.COLOR_RGB2HSV)


def green_mask(rgb: np.ndarray) -> np.ndarray:
    """Saturated green pixels: hue 70..170 deg, saturation >= 0.30, value >= 20 (8-bit)."""
    h, s, v = np.moveaxis(hsv(rgb), -1, 0)
    return ((h >= GREEN_HUE_LO) & (h <= GREEN_HUE_HI) & (s >= GREEN_MIN_SAT)
            & (v >= GREEN_MIN_V))


def abs_laplacian(rgb: np.ndarray) -> np.ndarray:
    """|Laplacian| of the luma, 3x3 kernel [[0,1,0],[1,-4,1],[0,1,0]], no blur: fine texture
    (leaves, grass blades) shows as large values, a flat-shaded surface as about 0."""
    return np.abs(cv2.Laplacian(luma(rgb), cv2.CV_32F, ksize=1,
                                borderType=cv2.BORDER_REFLECT))


def green_stats(rgb: np.ndarray) -> dict[str, float]:
    """On the frame shrunk to 320 px wide: green share, the share of its pixels in
    `green_mask`; green V, their mean HSV value (0..255); green texture, their mean
    `abs_laplacian` (DN). V and texture NaN with fewer than 50 green pixels."""
    if rgb.shape[1] > GREEN_WIDTH:
        size = (GREEN_WIDTH, max(1, round(rgb.shape[0] * GREEN_WIDTH / rgb.shape[1])))
        rgb = cv2.resize(rgb, size, interpolation=cv2.INTER_AREA)
    mask = green_mask(rgb)
    n = int(mask.sum())
    if n < MIN_PIXELS:
        return {"green_share": n / mask.size, "green_v": math.nan, "green_texture": math.nan}
    return {"green_share": n / mask.size,
            "green_v": float(hsv(rgb)[..., 2][mask].mean()),
            "green_texture": float(abs_laplacian(rgb)[mask].mean())}


# -- layout ------------------------------------------------------------------------------------
def smooth_mask(rgb: np.ndarray) -> np.ndarray:
    """Pixels whose 9x9 neighbourhood of the sigma-1.5 blurred luma has a std below 6 DN."""
    y = cv2.GaussianBlur(luma(rgb), (0, 0), 1.5)
    k = (SKY_WINDOW, SKY_WINDOW)
    mean = cv2.boxFilter(y, -1, k, borderType=cv2.BORDER_REFLECT)
    mean_sq = cv2.boxFilter(y * y, -1, k, borderType=cv2.BORDER_REFLECT)
    return np.sqrt(np.maximum(mean_sq - mean * mean, 0.0)) < SKY_SMOOTH_STD


def sky_like(rgb: np.ndarray) -> np.ndarray:
    """Pixels that look like sky on their own, after a 5x5 median filter: smooth, luma >= 100,
    and blue-ish (B >= R + 15, B >= G) or grey (HSV saturation <= 0.20)."""
    rgb = cv2.medianBlur(np.ascontiguousarray(rgb, dtype=np.uint8), SKY_MEDIAN_PX)
    r, g, b = (rgb[..., i].astype(np.int16) for i in range(3))
    blueish = (b >= r + SKY_BLUE_MARGIN) & (b >= g)
    grey = hsv(rgb)[..., 1] <= SKY_GREY_MAX_SAT * 255
    return smooth_mask(rgb) & (luma(rgb) >= SKY_MIN_LUMA) & (blueish | grey)


def fill_holes(mask: np.ndarray) -> np.ndarray:
    """`mask` with every region of False it encloses (touching no image border) set True."""
    outside = np.pad(~mask, 1, constant_values=True).astype(np.uint8)
    cv2.floodFill(outside, None, (0, 0), 2)
    return mask | (outside[1:-1, 1:-1] != 2)


def open_sky_mask(rgb: np.ndarray, horizon_row: float) -> np.ndarray:
    """The open sky above the horizon (rows above it only): `sky_like` pixels, closed with a
    5x5 square, in the 8-connected parts that touch the frame's top row, holes filled.

    Connected to the top: a grey wall, a bright truck or a pale road that passes `sky_like`
    lower down is not sky. Holes filled: a cloud's rim is not smooth and its core is white,
    but the whole cloud is sky.
    """
    h = split_row(horizon_row, rgb.shape[0])
    if h == 0:
        return np.zeros((0, rgb.shape[1]), bool)
    kernel = np.ones((SKY_CLOSE_PX, SKY_CLOSE_PX), np.uint8)
    like = cv2.morphologyEx(sky_like(rgb[:h]).astype(np.uint8), cv2.MORPH_CLOSE, kernel,
                            borderType=cv2.BORDER_REPLICATE)
    _, labels = cv2.connectedComponents(like, connectivity=8)
    top = np.unique(labels[0][like[0] > 0])
    return fill_holes(np.isin(labels, top) & (like > 0))


def open_sky_share(rgb: np.ndarray, horizon_row: float) -> float:
    """Share of the pixels above the horizon that are `open_sky_mask`; NaN if none are above."""
    mask = open_sky_mask(rgb, horizon_row)
    return float(mask.mean()) if mask.size else math.nan


# -- road structure ----------------------------------------------------------------------------
def paint_margin_mask(paint: np.ndarray, horizon_row: float) -> np.ndarray:
    """Paint and the road near it: pixels within 3 px + 0.15 px per row below the horizon of a
    paint pixel (Euclidean), so the paint's own edges, blur and label error are left out."""
    if not paint.any():
        return np.zeros(paint.shape, bool)
    dist = cv2.distanceTransform((~paint.astype(bool)).astype(np.uint8), cv2.DIST_L2, 5)
    below = np.maximum(np.arange(paint.shape[0]) - horizon_row, 0.0)[:, None]
    return dist <= PAINT_MARGIN_PX + PAINT_MARGIN_PER_ROW * below


def two_sided_ridge(y: np.ndarray, horizon_row: float) -> np.ndarray:
    """Pixels brighter by >= 20 DN than the brighter of the two pixels 4 px + 0.1 px per row
    below the horizon to their left and right (rows at and below the horizon only): a line
    narrower than that stands out, the edge of a wide light patch does not."""
    h, w = y.shape
    top = split_row(horizon_row, h)
    rows = np.arange(top, h)
    d = np.round(RIDGE_PX + RIDGE_PER_ROW * (rows - horizon_row)).astype(int)[:, None]
    cols = np.arange(w)[None, :]
    part = y[top:]
    left = np.take_along_axis(part, np.clip(cols - d, 0, w - 1), axis=1)
    right = np.take_along_axis(part, np.clip(cols + d, 0, w - 1), axis=1)
    out = np.zeros((h, w), bool)
    out[top:] = part - np.maximum(left, right) >= RIDGE_MIN_DN
    return out


def guess_paint(rgb: np.ndarray, horizon_row: float) -> np.ndarray:
    """Paint where no mask or label gives it: a `two_sided_ridge` of the sigma-1 luma, or
    yellow (hue 30..70 deg, S >= 0.35, V >= 100).

    Approximate: it also takes light seams, glints and lit car parts as paint, and misses
    paint faded below 20 DN; use it to compare sources with each other, not as the truth.
    """
    ridge = two_sided_ridge(cv2.GaussianBlur(luma(rgb), (0, 0), 1.0), horizon_row)
    h, s, v = np.moveaxis(hsv(rgb), -1, 0)
    yellow = ((h >= YELLOW_HUE_LO) & (h <= YELLOW_HUE_HI) & (s >= YELLOW_MIN_SAT)
              & (v >= YELLOW_MIN_V))
    return ridge | yellow


def road_structure_edges(rgb: np.ndarray, paint: np.ndarray | None, horizon_row: float
                         ) -> float:
    """Share of Canny(20, 60) edge pixels (`realism.canny_edges`) in the road area
    (`realism.road_area_mask`, above 88% of the height: no hood) outside `paint_margin_mask`:
    seams, tar lines, sharp tyre stripes, cracks, patches and the road's own edge, i.e. what
    can make a false line. NaN without a paint mask or with fewer than 50 pixels left.
    Vehicles and hard shadows in the road area count too (in photos and renders alike)."""
    if paint is None:
        return math.nan
    region = road_area_mask(rgb.shape[:2], horizon_row) & ~paint_margin_mask(paint, horizon_row)
    region[int(ROAD_EDGES_BOTTOM_SHARE * rgb.shape[0]):] = False
    if region.sum() < MIN_PIXELS:
        return math.nan
    return float(canny_edges(rgb, ROAD_CANNY_LOW, ROAD_CANNY_HIGH)[region].mean())


# -- all of them -------------------------------------------------------------------------------
def gap_stats(rgb: np.ndarray, horizon_row: float, paint: np.ndarray | None
              ) -> dict[str, float]:
    """Every #59 statistic of one frame at the work width. road_edges uses the given paint
    (render: segmentation; TuSimple: labels; NaN without); road_edges_guess uses
    `guess_paint` for every source alike."""
    rgb, horizon_row, paint = to_work_size(rgb, horizon_row, paint)
    return {**dark_stats(rgb), **green_stats(rgb),
            "open_sky_share": open_sky_share(rgb, horizon_row),
            "road_edges": road_structure_edges(rgb, paint, horizon_row),
            "road_edges_guess": road_structure_edges(rgb, guess_paint(rgb, horizon_row),
                                                      horizon_row)}
