"""What each world of a LaneNet dataset contains, for asking which content the real frames need
(issue #56 part 3): the paint's contrast as the network sees it, traffic, cast shade and the
camera's pose, per training world.

Paint contrast is measured on the stored frames (what the network was taught from), not read
from the recipe: the median luma of the labelled paint pixels minus that of the road in a thin
band around them, over a world's front frames. The other factors are the world's drawn
scenario (`random_scenario` of the shard's seed), which is exact and costs no render.

`held_out` picks the worlds a leave-content-out fine-tune drops: the `count` worlds with the
most of a factor (or, for `paint_contrast`, the least: the faint paint that real roads show),
or `count` worlds drawn at random as the control of the same size.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np

from lanekeep.evaluation.dataset import LABEL_ROWS, camera_from_vector
from lanekeep.evaluation.dataset_world import ROAD_LENGTH_M, random_scenario

FACTORS = ("paint_contrast", "traffic", "shade", "dashcam", "random")
MIN_PAINT_PIXELS = 20  # a frame with less visible paint says nothing about its contrast


@dataclass(frozen=True)
class WorldContent:
    """One world's content (see the module docstring for how each is measured)."""

    index: int
    world_seed: int
    tag: str
    paint_contrast_dn: float  # NaN when no front frame shows enough paint
    label_contrast_dn: float  # the same read at the labels, as on real frames (NaN: none)
    vehicles_per_lane_km: float
    shade_share: float  # share of the road's length inside a cast-shadow zone
    dashcam: bool
    horizon_row: float  # front camera, at 720 rows
    camera_height_m: float


def paint_contrast(frames: np.ndarray, paint: np.ndarray) -> float:
    """Median over frames of (paint luma - nearby road luma), in 8-bit DN."""
    ring = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (9, 9))
    core = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
    values = []
    for rgb, ids in zip(frames, paint, strict=True):
        on = ids > 0
        if on.sum() < MIN_PAINT_PIXELS:
            continue
        mask = on.astype(np.uint8)
        band = (cv2.dilate(mask, ring) > 0) & ~(cv2.dilate(mask, core) > 0)
        if band.sum() < MIN_PAINT_PIXELS:
            continue
        luma = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32)
        values.append(float(np.median(luma[on]) - np.median(luma[band])))
    return float(np.median(values)) if values else math.nan


def label_contrast(frame: np.ndarray, lines: list[np.ndarray], full: tuple[int, int] = (1280, 720),
                   near_share: float = 0.4) -> float:
    """Paint contrast read at labelled lane lines, the same way for our frames and real ones
    (whose paint has no mask): per labelled point in the lowest `near_share` of the rows, the
    brightest luma within 1 px of the line minus the median luma 3-6 px to either side, at the
    frame's size (`frame`: RGB, e.g. the network's 320x176; `lines`: (N, 2) arrays of x, y in
    `full`-size pixels). The 90th percentile over points, in DN; NaN without labelled near
    points."""
    luma = cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY).astype(np.float32)
    h, w = luma.shape
    sx, sy = w / full[0], h / full[1]
    values = []
    for line in lines:
        for x, y in np.asarray(line, dtype=float).reshape(-1, 2):
            u, v = int(round(x * sx)), int(round(y * sy))
            if not (v >= h * (1.0 - near_share) and v < h and 7 <= u < w - 7):
                continue
            row = luma[v]
            side = np.concatenate([row[u - 6:u - 2], row[u + 3:u + 7]])
            values.append(float(row[u - 1:u + 2].max() - np.median(side)))
    # Labels run on through dash gaps (TuSimple's and ours), so most points of a dashed line
    # see road: the 90th percentile reads the paint where there is any.
    return float(np.percentile(values, 90)) if values else math.nan


def stored_lines(xs: np.ndarray) -> list[np.ndarray]:
    """A stored frame's labelled boundaries (xs: (boundaries, LABEL_ROWS)) as (N, 2) x, y."""
    return [np.stack([x[ok], LABEL_ROWS[ok]], 1) for x in xs
            if (ok := np.isfinite(x)).sum() >= 2]


def horizon_row(camera_vector: np.ndarray) -> float:
    """The row (at 720) where the ground far ahead meets the sky in this camera."""
    camera = camera_from_vector(camera_vector)
    far = np.array([[1.0e4, 0.0, 0.0]])
    uv, _ = camera.project(far)
    return float(uv[0, 1])


def world_content(shard: Path, index: int) -> WorldContent:
    with np.load(shard) as z:
        front = ~z["is_rear"]
        frames = z["frames"][front].reshape(-1, *z["frames"].shape[2:])
        paint = z["paint"][front].reshape(-1, *z["paint"].shape[2:])
        seed = int(z["world_seed"])
        cameras = z["camera"][front]
        xs = z["xs"][front].reshape(-1, *z["xs"].shape[2:])
    at_labels = [label_contrast(f, stored_lines(x)) for f, x in zip(frames, xs, strict=True)]
    at_labels = [v for v in at_labels if math.isfinite(v)]
    scenario = random_scenario(seed)
    n_lanes = scenario.road.n_lanes
    shaded = sum(max(0.0, min(z.s_end_m, ROAD_LENGTH_M) - max(z.s_start_m, 0.0))
                 for z in scenario.conditions.shadows)
    return WorldContent(
        index=index, world_seed=seed, tag=scenario.name.rsplit("_", 1)[1],
        paint_contrast_dn=paint_contrast(frames, paint),
        label_contrast_dn=float(np.median(at_labels)) if at_labels else math.nan,
        vehicles_per_lane_km=len(scenario.conditions.vehicles) / n_lanes / (ROAD_LENGTH_M / 1000),
        shade_share=shaded / ROAD_LENGTH_M,
        dashcam=scenario.camera.preset == "dashcam",
        horizon_row=horizon_row(cameras[0]),
        camera_height_m=float(cameras[0][6]),
    )


def split_content(root: Path, split: str = "train") -> list[WorldContent]:
    """Every world of a split, in index order."""
    paths = sorted((Path(root) / split).glob("world_*.npz"))
    if not paths:
        raise FileNotFoundError(f"{Path(root) / split}: no shards")
    return [world_content(p, int(p.stem.split("_")[1])) for p in paths]


def held_out(content: list[WorldContent], factor: str, count: int, seed: int = 0) -> list[int]:
    """The indices of the `count` worlds a leave-`factor`-out run drops (see module docstring)."""
    if factor not in FACTORS:
        raise ValueError(f"factor must be one of {FACTORS}, got {factor!r}")
    if not 0 < count < len(content):
        raise ValueError(f"count must be between 1 and {len(content) - 1}, got {count}")
    if factor == "random":
        picked = np.random.default_rng(seed).choice(len(content), count, replace=False)
        return sorted(content[i].index for i in picked)
    score = {
        # the faintest paint first; a world without measurable paint is not "faint"
        "paint_contrast": lambda w: -w.paint_contrast_dn if math.isfinite(w.paint_contrast_dn)
        else -math.inf,
        "traffic": lambda w: w.vehicles_per_lane_km,
        "shade": lambda w: w.shade_share,
        "dashcam": lambda w: float(w.dashcam),
    }[factor]
    # most of the factor first; ties (e.g. the non-dashcam worlds) in index order
    ranked = sorted(content, key=lambda w: (-score(w), w.index))
    return sorted(w.index for w in ranked[:count])


def content_rows(content: list[WorldContent]) -> list[dict]:
    return [asdict(w) for w in content]
