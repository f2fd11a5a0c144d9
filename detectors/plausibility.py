"""Is a detected lane a lane at all? Geometry checks on a `LaneEstimate`, for `lanekeep detect`.

A detector fits whatever bright lines it was given; on a real photo those can be a car's edges,
a tree's shadow or a kerb, and the fit still says "valid". Roads are built to limits that such
fits break, so the checks ask of the ego pair over the ground the detector looks at:

- the boundaries must not cross (nor touch) within it;
- the lane must be 2.5-5 m wide (low confidence outside; invalid below 2 m or above 6 m);
- it must not widen or narrow by more than 1.5 m across that range (boundaries of one lane
  are parallel; a fit to a car or a shadow rarely is);
- neither boundary may bend tighter than a 30 m radius (below the design minimum of the roads
  a dashcam shows; a highway's is hundreds of metres);
- its supporting pixels must not lie mostly on a vehicle (when the caller gives the mask of
  what vehicles cover: `vehicle_cover`, from detectors/vehicle_mask.py's cues).

Pure reporting: the closed loop's detectors are not changed by this (their numbers stay put);
`detect` adds "valid", "confidence" and "reasons" from it to each photo's output.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.geometry.lane_poly import LanePoly


@dataclass(frozen=True)
class Limits:
    """Road design limits that a real lane keeps (metres)."""

    width_m: tuple[float, float] = (2.5, 5.0)  # usual lane widths: low confidence outside
    hard_width_m: tuple[float, float] = (2.0, 6.0)  # no lane is this narrow or wide: invalid
    max_width_change_m: float = 1.5  # over the checked range
    min_radius_m: float = 30.0
    max_vehicle_share: float = 0.3  # of the supporting pixels
    low_confidence_factor: float = 0.5  # applied per soft problem


@dataclass(frozen=True)
class Plausibility:
    """The verdict: `valid` (the detector's and the geometry's), a 0..1 confidence, reasons."""

    valid: bool
    confidence: float
    reasons: tuple[str, ...]

    def to_dict(self) -> dict:
        return {"valid": self.valid, "confidence": round(self.confidence, 3),
                "reasons": list(self.reasons)}


def curvature_radius_m(coeffs, xs: np.ndarray) -> np.ndarray:
    """|radius| of y(x) at each x: (1 + y'^2)^1.5 / |y''| (inf where straight)."""
    lane = LanePoly.of(coeffs)
    slope = lane.slope(xs)
    bend = abs(2.0 * lane.c2)
    return np.full_like(xs, np.inf) if bend == 0 else (1.0 + slope ** 2) ** 1.5 / bend


def check(estimate: LaneEstimate, x_range_m: tuple[float, float],
          vehicle_share: float | None = None, limits: Limits = Limits()) -> Plausibility:
    """Judge an estimate over the ground it was fitted to (`x_range_m`, vehicle frame x).

    `vehicle_share`: the share of its supporting pixels on a vehicle (None: not known)."""
    if not estimate.valid:
        return Plausibility(False, 0.0, (f"detector: {estimate.reason or 'no lane'}",))
    hard: list[str] = []
    soft: list[str] = []
    xs = np.linspace(*x_range_m, 50)
    for side, coeffs in (("left", estimate.left), ("right", estimate.right)):
        if coeffs is None:
            continue
        radius = float(np.min(curvature_radius_m(coeffs, xs)))
        if radius < limits.min_radius_m:
            hard.append(f"{side} boundary bends to a {radius:.0f} m radius "
                        f"(< {limits.min_radius_m:g} m)")
    if estimate.left is not None and estimate.right is not None:
        width = LanePoly.of(estimate.left).y(xs) - LanePoly.of(estimate.right).y(xs)
        if np.any(width <= 0.0):
            x_cross = float(xs[np.argmax(width <= 0.0)])
            hard.append(f"boundaries cross at x = {x_cross:.1f} m")
        else:
            lo, hi = float(width.min()), float(width.max())
            if lo < limits.hard_width_m[0] or hi > limits.hard_width_m[1]:
                hard.append(f"lane {lo:.1f}-{hi:.1f} m wide (no lane is outside "
                            f"{limits.hard_width_m[0]:g}-{limits.hard_width_m[1]:g} m)")
            elif lo < limits.width_m[0] or hi > limits.width_m[1]:
                soft.append(f"lane {lo:.1f}-{hi:.1f} m wide (usual: "
                            f"{limits.width_m[0]:g}-{limits.width_m[1]:g} m)")
            if hi - lo > limits.max_width_change_m:
                hard.append(f"boundaries not parallel: width changes by {hi - lo:.1f} m "
                            f"over x = {x_range_m[0]:g}-{x_range_m[1]:g} m")
    else:
        soft.append("one boundary only")
    if vehicle_share is not None and vehicle_share > limits.max_vehicle_share:
        hard.append(f"{vehicle_share:.0%} of its support lies on a vehicle")
    confidence = float(np.clip(estimate.confidence, 0.0, 1.0))
    confidence *= limits.low_confidence_factor ** len(soft)
    if hard:
        confidence = 0.0
    return Plausibility(not hard, confidence, tuple(hard + soft))


def support_share(estimate: LaneEstimate, covered: np.ndarray | None) -> float | None:
    """Share of the estimate's supporting pixels (`image_points`) inside `covered` (a bool
    image mask); None when there is no mask or no pixels."""
    if covered is None:
        return None
    points = [np.asarray(p, dtype=float).reshape(-1, 2) for p in estimate.image_points.values()]
    points = [p for p in points if len(p)]
    if not points:
        return None
    uv = np.rint(np.concatenate(points)).astype(int)
    h, w = covered.shape
    inside = (uv[:, 0] >= 0) & (uv[:, 0] < w) & (uv[:, 1] >= 0) & (uv[:, 1] < h)
    if not inside.any():
        return None
    uv = uv[inside]
    return float(np.mean(covered[uv[:, 1], uv[:, 0]]))


def vehicle_cover(image: np.ndarray, camera, preprocess) -> np.ndarray | None:
    """Bool mask (H, W) of what vehicles cover in a full frame, by the closed loop's own cues
    (detectors/vehicle_mask.py: the dark band under a vehicle, as wide as one at that row's
    distance); None when none is seen. Rows above the horizon see no ground and are skipped."""
    import cv2

    from lanekeep.detectors.vehicle_mask import hidden_by_vehicles, vehicle_dark

    if preprocess.vehicle_dark_ratio <= 0.0:
        return None
    h, w = image.shape[:2]
    rows = np.arange(h, dtype=float)
    left = np.column_stack([np.full(h, camera.cx - 0.5), rows])
    right = np.column_stack([np.full(h, camera.cx + 0.5), rows])
    g_left, ok_left = camera.pixels_to_ground(left)
    g_right, ok_right = camera.pixels_to_ground(right)
    metres = np.linalg.norm(np.asarray(g_left) - np.asarray(g_right), axis=1)
    ok = np.asarray(ok_left) & np.asarray(ok_right) & (metres > 0)
    px_per_m = np.where(ok, 1.0 / np.where(ok, metres, 1.0), 0.0)
    if not ok.any():
        return None
    top = int(np.argmax(ok))  # the first row that sees ground
    grey = cv2.cvtColor(image[top:], cv2.COLOR_RGB2GRAY)
    hidden = hidden_by_vehicles(vehicle_dark(grey, preprocess.vehicle_dark_ratio),
                                px_per_m[top:], preprocess.vehicle_min_width_m,
                                preprocess.vehicle_max_width_m, preprocess.vehicle_margin_m)
    if hidden is None:
        return None
    out = np.zeros((h, w), dtype=bool)
    out[top:] = hidden
    return out
