"""Image statistics for renders and real photos alike: each a small pure function of an RGB
uint8 image and a horizon row, defined in its docstring.

They are for SEEING the gap between renders and photos, not a target to fit: a renderer tuned
to match these few numbers on a handful of photos would be overfitted to them.
`lanekeep.tuning.realism_report` puts them side by side.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

# All statistics are computed at this frame width (the shipped cameras and both real sets are
# 1280x720): edge density and the noise estimate depend on scale, so frames of another size
# are resized to it first (aspect kept, horizon and masks scaled with them).
WORK_WIDTH = 1280

# Canny on the luma after a 5x5 Gaussian (sigma 1): the blur keeps sensor noise from counting
# as edges (it would otherwise dominate the noisy renders); 50/150 are the common textbook
# thresholds on 8-bit luma, with the L2 gradient norm.
CANNY_LOW, CANNY_HIGH, CANNY_BLUR_SIGMA = 50, 150, 1.0

# Sky: smooth (local std of the lightly blurred luma in a 9x9 window below this, in DN) and
# either blue-ish (B >= R + 15 and B >= G) or bright (luma >= 160, overcast or fog).
SKY_SMOOTH_STD, SKY_BLUE_MARGIN, SKY_BRIGHT_LUMA, SKY_WINDOW = 6.0, 15, 160.0, 9

# Noise: 8x8 blocks below the horizon, the 20% with the least structure.
NOISE_BLOCK, NOISE_FLAT_SHARE, NOISE_STRUCTURE_SIGMA = 8, 0.2, 2.0
# Immerkaer's mask: zero on constant and linear patches, std 6*sigma on white noise of sigma.
IMMERKAER = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)

# Paint contrast: road = pixels 15..30 px to the side (horizontally) of the paint, not paint;
# only rows at least 20 px below the horizon, where markings are more than a pixel wide.
ROAD_INNER_PX, ROAD_OUTER_PX, PAINT_MIN_ROWS_BELOW_HORIZON = 15, 30, 20
LABEL_PAINT_RADIUS_PX = 2  # TuSimple label polylines widened to 2*2+1 = 5 px
MIN_PIXELS = 50  # fewer paint or road pixels than this: no contrast ("-")

# Shade/sun: the road area is a trapezoid below the horizon (ROAD_TOP_SHARE of the way down
# from the horizon to ROAD_BOTTOM_SHARE of the frame's height, ROAD_HALF_WIDTH_TOP..BOTTOM of
# the width either side of the centre); its luma is split in two by Otsu's threshold.
ROAD_TOP_SHARE, ROAD_BOTTOM_SHARE = 0.15, 0.92
ROAD_HALF_WIDTH_TOP, ROAD_HALF_WIDTH_BOTTOM = 0.08, 0.40
MIN_SHADE_SHARE = 0.10  # the darker class must cover this much of the road area
# Paint edges: profiles along image rows through each paint run's centre, every EDGE_ROW_STEP
# rows from PAINT_MIN_ROWS_BELOW_HORIZON below the horizon; the paint's peak within
# EDGE_PEAK_PX of the centre, the road level the median of the outer EDGE_ROAD_PX of a
# +-EDGE_WINDOW_PX window; an edge counts when the paint stands EDGE_MIN_STEP_DN above it.
EDGE_ROW_STEP, EDGE_PEAK_PX, EDGE_WINDOW_PX, EDGE_ROAD_PX = 2, 6, 30, 8
EDGE_MIN_STEP_DN = 20.0
MIN_EDGES = 20


# -- basic images --------------------------------------------------------------------------------
def luma(rgb: np.ndarray) -> np.ndarray:
    """Rec. 601 luma Y = 0.299 R + 0.587 G + 0.114 B as float32 (0..255), the JPEG/BT.601 one."""
    rgb = rgb.astype(np.float32)
    return 0.299 * rgb[..., 0] + 0.587 * rgb[..., 1] + 0.114 * rgb[..., 2]


def split_row(horizon_row: float, height: int) -> int:
    """First image row counted as below the horizon: the horizon rounded, clipped to the image."""
    return int(np.clip(round(horizon_row), 0, height))


def camera_horizon_row(camera) -> float:
    """Horizon row of a simulated camera (`lanekeep.geometry.camera_model.CameraModel`) on
    flat ground.

    The vanishing line of the ground plane: where a ground point infinitely far straight ahead
    projects (`horizon_row()`; a point 10 km ahead lands within a fraction of a pixel of it).
    """
    return float(camera.horizon_row())


# -- statistics ------------------------------------------------------------------------------
def canny_edges(rgb: np.ndarray, low: float = CANNY_LOW, high: float = CANNY_HIGH
                ) -> np.ndarray:
    """Canny(low, high, L2 norm) edge pixels of the luma after a 5x5 Gaussian of sigma 1 (by
    default 50/150, the edge statistics' thresholds)."""
    y = np.clip(luma(rgb), 0, 255).astype(np.uint8)
    y = cv2.GaussianBlur(y, (5, 5), CANNY_BLUR_SIGMA)
    return cv2.Canny(y, low, high, L2gradient=True) > 0


def road_area_mask(shape: tuple[int, int], horizon_row: float) -> np.ndarray:
    """The road area below the horizon, the same for renders and photos (like for like).

    A trapezoid from 15% of the way down from the horizon to 92% of the frame's height (clear
    of a hood), 8% of the width either side of the centre at its top and 40% at its bottom.
    """
    h, w = shape
    top = split_row(horizon_row, h)
    top = int(top + ROAD_TOP_SHARE * (h - top))
    bottom = int(ROAD_BOTTOM_SHARE * h)
    mask = np.zeros((h, w), bool)
    if bottom - top < 2:
        return mask
    t = (np.arange(top, bottom) - top) / max(bottom - top - 1, 1)
    half = w * (ROAD_HALF_WIDTH_TOP + (ROAD_HALF_WIDTH_BOTTOM - ROAD_HALF_WIDTH_TOP) * t)
    mask[top:bottom] = np.abs(np.arange(w)[None, :] - 0.5 * (w - 1)) <= half[:, None]
    return mask


def edge_density(rgb: np.ndarray, horizon_row: float) -> tuple[float, float]:
    """(above, below): share of Canny edge pixels in the rows above / at-and-below the horizon.

    Canny(50, 150, L2 norm) on the luma after a 5x5 Gaussian of sigma 1 (so that sensor noise
    is not counted as structure); NaN for an empty region. Texture-poor renders show up as a
    low density below the horizon (road) and above it (roadside, sky).
    """
    edges = canny_edges(rgb)
    h = split_row(horizon_row, edges.shape[0])
    above = float(edges[:h].mean()) if h > 0 else math.nan
    below = float(edges[h:].mean()) if h < edges.shape[0] else math.nan
    return above, below


def sky_mask(rgb: np.ndarray) -> np.ndarray:
    """Pixels that look like sky: smooth and (blue-ish or bright).

    Smooth: the local standard deviation, in a 9x9 window, of the luma blurred with a Gaussian
    of sigma 1.5 is below 6 DN (the blur keeps sensor noise of up to ~20 DN from breaking it,
    and with it texture finer than ~3 px: foliage and buildings are coarser than that).
    Blue-ish: B >= R + 15 and B >= G. Bright: luma >= 160 (overcast sky, fog). A dark night sky
    is not counted: the statistic is about what the camera sees.
    """
    y = cv2.GaussianBlur(luma(rgb), (0, 0), 1.5)
    k = (SKY_WINDOW, SKY_WINDOW)
    mean = cv2.boxFilter(y, -1, k, borderType=cv2.BORDER_REFLECT)
    mean_sq = cv2.boxFilter(y * y, -1, k, borderType=cv2.BORDER_REFLECT)
    smooth = np.sqrt(np.maximum(mean_sq - mean * mean, 0.0)) < SKY_SMOOTH_STD
    r, g, b = (rgb[..., i].astype(np.int16) for i in range(3))
    blueish = (b >= r + SKY_BLUE_MARGIN) & (b >= g)
    bright = luma(rgb) >= SKY_BRIGHT_LUMA
    return smooth & (blueish | bright)


def sky_share(rgb: np.ndarray, horizon_row: float) -> float:
    """Share of the pixels above the horizon that are sky (`sky_mask`); NaN if none are above."""
    h = split_row(horizon_row, rgb.shape[0])
    return float(sky_mask(rgb[:h]).mean()) if h > 0 else math.nan


def luma_stats(rgb: np.ndarray, horizon_row: float) -> dict[str, float]:
    """Brightness below the horizon (the road scene): mean, p5, p50, p95 of the luma, in DN."""
    below = luma(rgb)[split_row(horizon_row, rgb.shape[0]):]
    if below.size == 0:
        return dict.fromkeys(("luma_mean", "luma_p5", "luma_p50", "luma_p95"), math.nan)
    p5, p50, p95 = np.percentile(below, [5, 50, 95])
    return {"luma_mean": float(below.mean()), "luma_p5": float(p5), "luma_p50": float(p50),
            "luma_p95": float(p95)}


def colourfulness(rgb: np.ndarray) -> float:
    """Hasler & Suesstrunk (2003) colourfulness of the whole frame, on 0..255 values.

    With rg = R - G and yb = (R + G)/2 - B: M = sqrt(sd(rg)^2 + sd(yb)^2)
    + 0.3 sqrt(mean(rg)^2 + mean(yb)^2). About 0 for grey images, 15-35 for "slightly"
    to "moderately" colourful photos, above 45 for "quite" colourful ones.
    """
    x = rgb.reshape(-1, 3).astype(np.float64)
    rg = x[:, 0] - x[:, 1]
    yb = 0.5 * (x[:, 0] + x[:, 1]) - x[:, 2]
    return float(math.hypot(rg.std(), yb.std()) + 0.3 * math.hypot(rg.mean(), yb.mean()))


def colour_stats(rgb: np.ndarray) -> dict[str, float]:
    """Colour of the whole frame: mean of R, G, B (DN), mean HSV saturation (0..1), colourfulness.

    Saturation is (max - min) / max of the three channels, 0 where max is 0.
    """
    x = rgb.reshape(-1, 3).astype(np.float32)
    hi, lo = x.max(axis=1), x.min(axis=1)
    sat = np.where(hi > 0, (hi - lo) / np.maximum(hi, 1.0), 0.0)
    means = x.mean(axis=0)
    return {"mean_r": float(means[0]), "mean_g": float(means[1]), "mean_b": float(means[2]),
            "saturation": float(sat.mean()), "colourfulness": colourfulness(rgb)}


def noise_sigma(rgb: np.ndarray, horizon_row: float) -> float:
    """Noise level: a robust sigma (DN) of the luma's high-pass in the flattest regions below
    the horizon.

    The luma below the horizon is cut into 8x8 blocks; each block's structure is its mean
    gradient magnitude (Sobel) of the luma blurred with a Gaussian of sigma 2, which noise
    barely moves, so picking flat blocks does not pick low-noise ones. In the 20% of blocks
    with the least structure, the luma is filtered with Immerkaer's 3x3 mask
    [[1,-2,1],[-2,4,-2],[1,-2,1]] (zero on constant and linear patches, standard deviation
    6 sigma on white noise of sigma) and, as Immerkaer (1996) does, sigma = sqrt(pi/2) *
    mean|response| / 6 (the mean, not the median, of |response|: in the near-constant flat
    regions of a JPEG the median sticks to whole DN steps). It measures all fine detail left
    in the flattest regions: sensor noise plus texture finer than ~3 px (a render with no noise
    effect still shows its asphalt texture here). On real JPEGs compression smooths flat
    regions, so their value is a lower bound of the sensor's. NaN if there is not one whole
    block below the horizon.
    """
    y = luma(rgb)
    h = split_row(horizon_row, y.shape[0])
    n_r, n_c = (y.shape[0] - h) // NOISE_BLOCK, y.shape[1] // NOISE_BLOCK
    if n_r < 1 or n_c < 1:
        return math.nan
    high = cv2.filter2D(y, cv2.CV_32F, IMMERKAER, borderType=cv2.BORDER_REFLECT)
    smooth = cv2.GaussianBlur(y, (0, 0), NOISE_STRUCTURE_SIGMA)
    grad = np.hypot(cv2.Sobel(smooth, cv2.CV_32F, 1, 0), cv2.Sobel(smooth, cv2.CV_32F, 0, 1))

    def blocks(a: np.ndarray) -> np.ndarray:
        a = a[h:h + n_r * NOISE_BLOCK, :n_c * NOISE_BLOCK]
        return a.reshape(n_r, NOISE_BLOCK, n_c, NOISE_BLOCK).swapaxes(1, 2).reshape(
            n_r * n_c, NOISE_BLOCK * NOISE_BLOCK)

    structure = blocks(grad).mean(axis=1)
    n_flat = max(1, int(round(NOISE_FLAT_SHARE * structure.size)))
    flat = np.argpartition(structure, n_flat - 1)[:n_flat]
    return float(math.sqrt(math.pi / 2.0) * np.abs(blocks(high)[flat]).mean() / 6.0)


def road_ring(paint: np.ndarray, inner_px: int = ROAD_INNER_PX,
              outer_px: int = ROAD_OUTER_PX) -> np.ndarray:
    """Pixels whose horizontal distance to the nearest paint pixel is inner..outer px.

    "Nearby road" for the paint contrast: on the same image row as the paint, so at the same
    distance from the camera and under the same light falloff.
    """
    m = paint.astype(np.uint8)
    outer = cv2.dilate(m, np.ones((1, 2 * outer_px + 1), np.uint8)) > 0
    near = cv2.dilate(m, np.ones((1, 2 * (inner_px - 1) + 1), np.uint8)) > 0
    return outer & ~near


def paint_contrast(rgb: np.ndarray, paint: np.ndarray, horizon_row: float
                   ) -> tuple[float, float, float]:
    """(difference, ratio, p90 difference) of the luma of paint pixels and nearby road pixels.

    Paint: the given mask; road: `road_ring` of it (15..30 px to the side, not paint); both
    only in rows at least 20 px below the horizon. Difference in DN: median paint - median
    road; ratio: median paint / median road; p90 difference: 90th percentile of paint -
    median road, which still sees dashes and dots when a labelled "paint" band runs mostly
    through the gaps between them (as TuSimple's do), where the medians see only road.
    NaN for all three with fewer than 50 pixels of either.
    """
    rows = np.arange(paint.shape[0])[:, None] >= (
        split_row(horizon_row, paint.shape[0]) + PAINT_MIN_ROWS_BELOW_HORIZON)
    paint = paint.astype(bool) & rows
    road = road_ring(paint) & rows
    if paint.sum() < MIN_PIXELS or road.sum() < MIN_PIXELS:
        return math.nan, math.nan, math.nan
    y = luma(rgb)
    p50, p90 = (float(v) for v in np.percentile(y[paint], [50, 90]))
    r = float(np.median(y[road]))
    return p50 - r, (p50 / r if r > 0 else math.nan), p90 - r


def shade_sun_ratio(rgb: np.ndarray, horizon_row: float) -> float:
    """Luma of the shade over that of the sunlit road: the means of the darker and the brighter
    class of an Otsu split of the road area's luma, when the darker covers >= 10% of it.

    Road area: `road_area_mask`, the same for renders and photos. Without shade
    Otsu still splits the asphalt's texture and wheel paths (0.7-0.9); dark cars and their
    shadows count as shade. NaN when the darker class is smaller or the area empty.
    """
    area = luma(rgb)[road_area_mask(rgb.shape[:2], horizon_row)]
    if area.size < MIN_PIXELS:
        return math.nan
    area8 = np.clip(area, 0, 255).astype(np.uint8)
    thresh, _ = cv2.threshold(area8.reshape(-1, 1), 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    dark = area8 <= thresh
    if dark.mean() < MIN_SHADE_SHARE or dark.all():
        return math.nan
    sun = float(area[~dark].mean())
    return float(area[dark].mean()) / sun if sun > 0 else math.nan


def _rise_px(side: np.ndarray, road: float, peak: float) -> float:
    """Distance (px) over which a profile running from the paint's peak (index 0) out to the
    road falls from 90% to 10% of the step; NaN if it does not reach 10% in the window."""
    lo, hi = road + 0.1 * (peak - road), road + 0.9 * (peak - road)

    def crossing(level: float) -> float:
        below = np.flatnonzero(side < level)
        if below.size == 0 or below[0] == 0:
            return math.nan
        k = int(below[0])  # side[k - 1] >= level > side[k]
        return k - 1 + (side[k - 1] - level) / max(side[k - 1] - side[k], 1e-6)

    return crossing(lo) - crossing(hi)


def paint_edge_width(rgb: np.ndarray, paint: np.ndarray, horizon_row: float) -> float:
    """Mean 10-90% rise width (px) of the luma across paint edges, both sides of each line.

    Along every 2nd image row from 20 rows below the horizon, through the centre of each run
    of paint pixels (sim: the segmentation mask; TuSimple: the label polylines widened to
    5 px, so the centre is the polyline): the paint's peak is the luma's maximum within 6 px of
    the centre, the road level on each side the median of the outer 8 px of a +-30 px window;
    walking out from the peak, the width is where the profile falls below 10% of the step less
    where it falls below 90% (interpolated). Edges whose paint stands less than 20 DN above
    the road, or that do not fall to 10% in the window, are left out: faded paint and gaps
    between dashes (which TuSimple's polylines run through) add nothing. NaN with fewer than
    20 edges. A rendered edge drawn in one pixel gives about 1; real frames 2-12 (lens, motion,
    JPEG and the paint's own ragged edge).
    """
    y = luma(rgb)
    h, w = y.shape
    start = split_row(horizon_row, h) + PAINT_MIN_ROWS_BELOW_HORIZON
    widths = []
    win = EDGE_WINDOW_PX
    for row in range(start, h, EDGE_ROW_STEP):
        m = np.r_[False, paint[row].astype(bool), False].astype(np.int8)
        edges = np.flatnonzero(np.diff(m))
        for a, b in zip(edges[0::2], edges[1::2], strict=True):
            c = (a + b - 1) // 2
            if c - win < 0 or c + win >= w:
                continue
            prof = y[row, c - win:c + win + 1]
            p = win - EDGE_PEAK_PX + int(np.argmax(prof[win - EDGE_PEAK_PX:win + EDGE_PEAK_PX + 1]))
            peak = float(prof[p])
            for side, road in ((prof[p::-1], float(np.median(prof[:EDGE_ROAD_PX]))),
                               (prof[p:], float(np.median(prof[-EDGE_ROAD_PX:])))):
                if peak - road >= EDGE_MIN_STEP_DN:
                    width = _rise_px(side, road, peak)
                    if math.isfinite(width):
                        widths.append(width)
    return float(np.mean(widths)) if len(widths) >= MIN_EDGES else math.nan


def label_paint_mask(lanes: list[np.ndarray], shape: tuple[int, int],
                     radius_px: int = LABEL_PAINT_RADIUS_PX) -> np.ndarray:
    """Paint mask from labelled lane polylines ((N, 2) x, y pixel arrays): every pixel within
    about `radius_px` of the polyline through each lane's points.

    TuSimple labels follow the lane through its gaps and over raised dots, so this "paint"
    includes road: a contrast measured with it is a lower bound of the paint's.
    """
    mask = np.zeros(shape, np.uint8)
    for pts in lanes:
        if len(pts):  # a one-pixel polyline (a point for one), widened by a disc of the radius
            cv2.polylines(mask, [np.round(pts).astype(np.int32).reshape(-1, 1, 2)], False, 1)
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius_px + 1, 2 * radius_px + 1))
    return cv2.dilate(mask, disc) > 0


def read_label_lanes(path: Path) -> list[np.ndarray]:
    """Lanes of a TuSimple-style label file: one lane a line, "x y x y ..." pixel pairs."""
    lanes = []
    for line in path.read_text().splitlines():
        values = np.array([float(v) for v in line.split()])
        if values.size >= 2:
            pts = values[: values.size // 2 * 2].reshape(-1, 2)
            lanes.append(pts[(pts[:, 0] >= 0) & (pts[:, 1] >= 0)])
    return lanes


def to_work_size(rgb: np.ndarray, horizon_row: float, paint: np.ndarray | None
                 ) -> tuple[np.ndarray, float, np.ndarray | None]:
    """The frame at WORK_WIDTH (aspect kept), its horizon row and paint mask scaled with it."""
    h, w = rgb.shape[:2]
    if w == WORK_WIDTH:
        return rgb, horizon_row, paint
    scale = WORK_WIDTH / w
    size = (WORK_WIDTH, max(1, int(round(h * scale))))
    interp = cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR
    rgb = cv2.resize(rgb, size, interpolation=interp)
    if paint is not None:
        paint = cv2.resize(paint.astype(np.uint8), size, interpolation=cv2.INTER_NEAREST) > 0
    return rgb, (horizon_row + 0.5) * scale - 0.5, paint


def frame_stats(rgb: np.ndarray, horizon_row: float, paint: np.ndarray | None
                ) -> dict[str, float]:
    """All statistics of one frame (paint contrast NaN without a paint mask)."""
    rgb, horizon_row, paint = to_work_size(rgb, horizon_row, paint)
    above, below = edge_density(rgb, horizon_row)
    diff, ratio, diff90 = (paint_contrast(rgb, paint, horizon_row) if paint is not None
                           else (math.nan, math.nan, math.nan))
    return {"horizon_row": horizon_row, "edges_above": above, "edges_below": below,
            "sky_share": sky_share(rgb, horizon_row), **luma_stats(rgb, horizon_row),
            **colour_stats(rgb), "noise_sigma": noise_sigma(rgb, horizon_row),
            "paint_minus_road": diff, "paint_over_road": ratio, "paint_p90_minus_road": diff90,
            "shade_over_sun": shade_sun_ratio(rgb, horizon_row),
            "paint_edge_px": (paint_edge_width(rgb, paint, horizon_row) if paint is not None
                              else math.nan)}


def mean_stats(rows: list[dict[str, float]]) -> dict[str, float]:
    """Per-statistic mean over frames, ignoring NaN (NaN where every frame has NaN)."""
    out = {}
    for key in rows[0]:
        values = np.array([r[key] for r in rows], dtype=float)
        out[key] = float(np.nanmean(values)) if np.isfinite(values).any() else math.nan
    return out
