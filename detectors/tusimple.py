"""TuSimple lane-benchmark output and the benchmark's accuracy rule.

Output: one JSON object per image, {"lanes": [[x per h_sample]...], "h_samples": [...],
"raw_file": ..., "run_time": ms}; x = -2 where a lane is absent. Scoring follows TuSimple's
LaneEval: a predicted point matches a labelled one on the same row when
|x_pred - x_gt| < 20 px / cos(angle), angle the slant of the labelled lane (a line x(y) fitted
to its points); a labelled lane scores the share of its points matched by its best predicted
lane; a frame scores the sum over labelled lanes / max(min(4, n_labelled), 1).

A detector that sees every boundary (LaneNet) reports them all (`boundary_lanes`), each
extended over the visible road, as TuSimple labels are: from the bottom of the image up to near
the horizon.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.lane_poly import LanePoly

PIXEL_THRESHOLD = 20.0
ABSENT = -2


def h_samples_for(height: int) -> list[int]:
    """TuSimple's sample rows (160, 170, ..., 710 at 720 rows), scaled to other heights."""
    return [int(round(v * height / 720.0)) for v in range(160, 720, 10)]


def boundary_xs(
    coeffs: np.ndarray, camera: CameraModel, h_samples: list[int], x_range: tuple[float, float]
) -> list[int]:
    """Image column of the ground curve y(x) = coeffs on each sample row; -2 outside x_range."""
    lo, hi = min(x_range), max(x_range)
    out = []
    for v in h_samples:
        ground, ok = camera.pixels_to_ground(np.array([camera.cx, float(v)]))
        if not ok:
            out.append(ABSENT)
            continue
        x = float(ground[0])
        u = None
        for _ in range(3):  # a row is a line of constant x only for a camera without yaw
            if not lo <= x <= hi:
                u = None
                break
            uv, front = camera.project_ground(np.array([x, float(LanePoly.of(coeffs).y(x))]))
            if not front:
                u = None
                break
            u = float(uv[0])
            ground, ok = camera.pixels_to_ground(np.array([u, float(v)]))
            if not ok:
                u = None
                break
            x = float(ground[0])
        out.append(int(round(u)) if u is not None and 0 <= u < camera.width else ABSENT)
    return out


def estimate_lanes(
    estimate: LaneEstimate, camera: CameraModel, h_samples: list[int],
    x_range: tuple[float, float],
) -> list[list[int]]:
    """The estimate's boundaries (left, right: those found; then the other lanes' lines it
    found, `LaneEstimate.others`) as TuSimple lanes."""
    if not estimate.valid:
        return []
    lanes = []
    for coeffs in (estimate.left, estimate.right, *estimate.others):
        if coeffs is not None:
            xs = boundary_xs(np.asarray(coeffs), camera, h_samples, x_range)
            if any(x != ABSENT for x in xs):
                lanes.append(xs)
    return lanes


class DrawableBoundary(Protocol):
    """A fitted boundary that can say its image x on given rows (detectors.lanenet_decode)."""

    name: str
    score: float

    def x_at_rows(self, rows_px: np.ndarray, camera: CameraModel | None = None,
                  extend_rows: tuple[float, float] | None = None) -> np.ndarray: ...


@dataclass(frozen=True)
class NamedLane:
    """One reported boundary: its slot name, x per h_sample (-2 = absent), its confidence."""

    name: str
    xs: list[int]
    score: float


# Rows this share of the image height below the horizon are the top of the "visible range":
# nearer the horizon a row spans tens of metres of road, and the extended curve's x there is
# a guess (TuSimple's labels also stop a little below it).
HORIZON_MARGIN = 0.03


def boundary_lanes(
    boundaries: list[DrawableBoundary], camera: CameraModel | None, h_samples: list[int],
    size: tuple[int, int], horizon_row: float,
) -> list[NamedLane]:
    """Every boundary as a TuSimple lane: x at each h_sample from the image's bottom row up to
    HORIZON_MARGIN below the horizon, ordered left to right by where each meets the bottom
    row (extrapolated: a boundary leaving through the side still sorts by its position).
    Boundaries with no sample in the image are left out. `size` is the image's (width,
    height), `horizon_row` its horizon."""
    width, height = size
    rows = np.asarray(h_samples, dtype=float)
    bottom = float(height - 1)
    top = horizon_row + HORIZON_MARGIN * height
    keyed = []
    for b in boundaries:
        x = b.x_at_rows(rows, camera, extend_rows=(top, bottom))
        ok = np.isfinite(x) & (x >= 0) & (x <= width - 1)
        if not ok.any():
            continue
        xs = [int(round(v)) if good else ABSENT for v, good in zip(x, ok, strict=True)]
        at_bottom = b.x_at_rows(np.array([bottom]), camera, extend_rows=(top, bottom))[0]
        if not np.isfinite(at_bottom):  # the lowest sample it has instead
            at_bottom = float(x[np.flatnonzero(np.isfinite(x))[-1]])
        keyed.append((float(at_bottom), NamedLane(b.name, xs, float(b.score))))
    return [lane for _, lane in sorted(keyed, key=lambda k: k[0])]


def every_lane(detector, camera: CameraModel, camera_known: bool, h_samples: list[int],
               size: tuple[int, int], horizon_row: float) -> list[NamedLane] | None:
    """All boundaries of a detector that sees them (its `last.boundaries`), as TuSimple lanes;
    None for a detector that reports only its ego pair. Without a known camera (a photo with no
    camera file) a detector that can refit in the image (`boundaries_in_image`) does, with the
    horizon its boundaries meet at, rather than project through a guessed camera."""
    boundaries = getattr(getattr(detector, "last", None), "boundaries", None)
    if boundaries is None:
        return None
    if not camera_known and hasattr(detector, "boundaries_in_image"):
        boundaries = detector.boundaries_in_image()
        horizons = [b.horizon_row for b in boundaries if b.horizon_row is not None]
        return boundary_lanes(boundaries, None, h_samples, size,
                              horizons[0] if horizons else horizon_row)
    return boundary_lanes(boundaries, camera, h_samples, size, horizon_row)


def record(raw_file: str, lanes: list[list[int]], h_samples: list[int], run_time_ms: float
           ) -> dict:
    return {"lanes": lanes, "h_samples": list(h_samples), "raw_file": raw_file,
            "run_time": round(float(run_time_ms), 2)}


def lane_angle(xs: np.ndarray, h_samples: np.ndarray) -> float:
    """Slant of a labelled lane: arctan of dx/dy of a line fitted to its points."""
    ok = xs >= 0
    if ok.sum() < 2:
        return 0.0
    k = np.polyfit(h_samples[ok].astype(float), xs[ok].astype(float), 1)[0]
    return math.atan(k)


def lane_accuracy(pred: np.ndarray, gt: np.ndarray, threshold: float) -> float:
    """Share of the labelled points of `gt` that `pred` matches."""
    labelled = gt >= 0
    if not labelled.any():
        return 0.0
    hit = labelled & (pred >= 0) & (np.abs(pred - gt) < threshold)
    return float(hit.sum() / labelled.sum())


def score_frame(
    pred_lanes: list[list[int]], gt_lanes: list[list[int]], h_samples: list[int]
) -> tuple[float, list[float]]:
    """(frame accuracy, accuracy of each labelled lane) by TuSimple's rule."""
    ys = np.asarray(h_samples)
    preds = [np.asarray(p, dtype=float) for p in pred_lanes]
    per_lane = []
    for gt in gt_lanes:
        gt = np.asarray(gt, dtype=float)
        threshold = PIXEL_THRESHOLD / math.cos(lane_angle(gt, ys))
        per_lane.append(max((lane_accuracy(p, gt, threshold) for p in preds), default=0.0))
    accuracy = sum(per_lane) / max(min(4, len(gt_lanes)), 1)
    return accuracy, per_lane
