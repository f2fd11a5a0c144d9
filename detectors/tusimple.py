"""TuSimple lane-benchmark output and the benchmark's accuracy rule.

Output: one JSON object per image, {"lanes": [[x per h_sample]...], "h_samples": [...],
"raw_file": ..., "run_time": ms}; x = -2 where a lane is absent. Scoring follows TuSimple's
LaneEval: a predicted point matches a labelled one on the same row when
|x_pred - x_gt| < 20 px / cos(angle), angle the slant of the labelled lane (a line x(y) fitted
to its points); a labelled lane scores the share of its points matched by its best predicted
lane; a frame scores the sum over labelled lanes / max(min(4, n_labelled), 1).
"""

from __future__ import annotations

import math

import numpy as np

from detectors.base import LaneEstimate, poly_eval
from lanekeep.camera_model import CameraModel

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
            uv, front = camera.project_ground(np.array([x, float(poly_eval(coeffs, x))]))
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
    """The estimate's boundaries (left, right; those found) as TuSimple lanes."""
    if not estimate.valid:
        return []
    lanes = []
    for coeffs in (estimate.left, estimate.right):
        if coeffs is not None:
            xs = boundary_xs(np.asarray(coeffs), camera, h_samples, x_range)
            if any(x != ABSENT for x in xs):
                lanes.append(xs)
    return lanes


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
