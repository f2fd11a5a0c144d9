"""Bird's-eye (inverse perspective) view derived from the camera model, and lane assembly.

The ground plane z = 0 of the vehicle frame maps to the image by the homography
    p ~ K [r1 r2 t] (x, y, 1)^T,  with [r1 r2 r3 | t] the vehicle-to-camera (OpenCV) transform,
so the warp follows from intrinsics, mounting height and pitch alone; no hand-picked pixels.
The bird's-eye image looks along the camera's own driving direction: row 0 is the far edge of
the ground window, the last row the edge nearest the car, column 0 the camera's left. So the
same detector code runs on the rear camera, whose view is the road behind (x < 0); points are
converted back to the vehicle frame before any fit, so results are in one frame for all cameras.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

from detectors.base import LaneEstimate, poly_eval
from detectors.config import GroundWindow, LaneRules
from lanekeep.camera_model import CameraModel


def check_frame(frame: np.ndarray, camera: CameraModel) -> None:
    """Raise ValueError unless `frame` is an RGB uint8 image of the camera's size."""
    expected = (camera.height, camera.width, 3)
    if not isinstance(frame, np.ndarray) or frame.shape != expected:
        shape = getattr(frame, "shape", type(frame).__name__)
        raise ValueError(f"expected an RGB frame of shape {expected} for camera "
                         f"{camera.name!r}, got {shape}")
    if frame.dtype != np.uint8:
        raise ValueError(f"expected a uint8 frame, got {frame.dtype}")


def ground_homography(camera: CameraModel) -> np.ndarray:
    """3x3 H with pixel ~ H (x, y, 1) for ground points (x, y, 0) in the vehicle frame."""
    # Vehicle -> OpenCV camera: p_cv = D R^T (p - c), D = diag(1, -1, -1).
    rot = np.diag([1.0, -1.0, -1.0]) @ camera.rotation.T
    t = -rot @ camera.position_m
    return camera.K @ np.column_stack([rot[:, 0], rot[:, 1], t])


def visible_window(
    camera: CameraModel, window: GroundWindow, margin_m: float = 0.3
) -> GroundWindow:
    """The window with its near edge moved out to where the ground enters the image."""
    ground, ok = camera.pixels_to_ground(np.array([camera.cx, camera.height - 1.0]))
    if not ok:
        return window
    x_vis = float(ground[0]) + window.direction * margin_m
    if (x_vis - window.x_near_m) * window.direction <= 0:
        return window
    if (window.x_far_m - x_vis) * window.direction < 2.0:
        return window  # nothing left: keep the window and let the detector fail honestly
    return replace(window, x_near_m=x_vis)


@dataclass
class BirdsEye:
    """Warps a (cropped, scaled) camera image into the ground window; pixel <-> metre maps.

    Args:
      camera: the full-resolution camera model.
      window: ground window (vehicle frame).
      scale: the source image is the camera image scaled by this factor ...
      crop_top: ... then cropped to start at this full-resolution row.
      distortion: OpenCV distortion coefficients of the camera (None = pinhole): the warp
        then samples the distorted image directly, which is undistortion and warp in one pass.
    """

    camera: CameraModel
    window: GroundWindow
    scale: float = 1.0
    crop_top: int = 0
    distortion: np.ndarray | None = None

    def __post_init__(self) -> None:
        w = self.window
        self.rows = max(2, int(round(abs(w.x_far_m - w.x_near_m) / w.m_per_row)))
        self.cols = max(2, int(round(2.0 * w.y_half_m / w.m_per_col)))
        # Camera-left in the vehicle frame: +y looking forward, -y looking back.
        self._left = w.direction
        cols, rows = np.meshgrid(np.arange(self.cols, dtype=float),
                                 np.arange(self.rows, dtype=float))
        x, y = self.to_ground(cols, rows)
        ground = np.stack([x, y, np.zeros_like(x)], axis=-1).reshape(-1, 3)
        if self.distortion is not None and np.any(np.asarray(self.distortion) != 0):
            rot = np.diag([1.0, -1.0, -1.0]) @ self.camera.rotation.T
            rvec, _ = cv2.Rodrigues(rot)
            tvec = -rot @ self.camera.position_m
            uv, _ = cv2.projectPoints(ground, rvec, tvec, self.camera.K,
                                      np.asarray(self.distortion, dtype=float))
            uv = uv.reshape(-1, 2)
        else:
            uv, _ = self.camera.project_ground(ground[:, :2])
        _, in_front = self.camera.project(ground)
        uv = np.where(in_front[:, None], uv, -1e4)
        s = self.scale
        map_u = ((uv[:, 0] + 0.5) * s - 0.5).reshape(self.rows, self.cols).astype(np.float32)
        map_v = ((uv[:, 1] - self.crop_top + 0.5) * s - 0.5).reshape(self.rows, self.cols)
        map_v = map_v.astype(np.float32)
        self._maps = cv2.convertMaps(map_u, map_v, cv2.CV_16SC2)

    def to_ground(self, cols, rows) -> tuple[np.ndarray, np.ndarray]:
        """Bird's-eye pixel (col, row) centres -> vehicle-frame (x, y) metres."""
        w = self.window
        rows = np.asarray(rows, dtype=float)
        cols = np.asarray(cols, dtype=float)
        x = w.x_far_m + (w.x_near_m - w.x_far_m) * (rows + 0.5) / self.rows
        y = self._left * (w.y_half_m - (cols + 0.5) * w.m_per_col)
        return x, y

    def to_pixels(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """Vehicle-frame (x, y) metres -> bird's-eye (col, row), fractional."""
        w = self.window
        rows = (np.asarray(x, dtype=float) - w.x_far_m) / (w.x_near_m - w.x_far_m) * self.rows - 0.5
        cols = (w.y_half_m - self._left * np.asarray(y, dtype=float)) / w.m_per_col - 0.5
        return cols, rows

    def warp(self, image: np.ndarray) -> np.ndarray:
        """The bird's-eye view of the source image (outside the image: 0)."""
        return cv2.remap(image, self._maps[0], self._maps[1], cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0)


def roi_crop(camera: CameraModel, window: GroundWindow, margin_px: float) -> int:
    """First full-resolution row of the region of interest: just below the window's far edge."""
    far, ok = camera.project_ground(np.array([[window.x_far_m, 0.0]]))
    horizon = camera.horizon_row()
    row = float(far[0, 1]) if ok[0] else horizon
    row = max(row, horizon) if math.isfinite(horizon) else row
    return int(np.clip(math.floor(row - margin_px), 0, camera.height - 2))


@dataclass(frozen=True)
class Boundary:
    """A fitted boundary: y(x) coefficients [c0, c1, c2], its support and its image points."""

    coeffs: np.ndarray
    n_points: int
    x_span_m: float
    points_xy: np.ndarray  # (N, 2) vehicle-frame points the fit used


def fit_boundary(xy: np.ndarray, rules: LaneRules, camera_x_m: float = 0.0) -> Boundary | None:
    """Weighted least-squares y(x): a parabola over long spans, a line over short ones.

    A pixel's lateral uncertainty grows with its distance from the camera, so each point is
    weighted by 1 / distance (polyfit weights multiply the residuals). None if unfit.
    """
    if len(xy) < 3:
        return None
    x, y = xy[:, 0], xy[:, 1]
    weights = 1.0 / np.maximum(np.abs(x - camera_x_m), 1.0)
    span = float(x.max() - x.min())
    if span < rules.min_span_m:
        return None
    degree = 2 if span >= rules.quadratic_span_m else 1
    c = np.polyfit(x, y, degree, w=weights)[::-1]
    coeffs = np.zeros(3)
    coeffs[: degree + 1] = c
    if abs(2.0 * coeffs[2]) > rules.max_curvature_1pm or not np.all(np.isfinite(coeffs)):
        return None
    return Boundary(coeffs, len(xy), span, xy)


def parallel(
    left: Boundary | None, right: Boundary | None, rules: LaneRules, camera_x_m: float = 0.0
) -> tuple[Boundary | None, Boundary | None]:
    """Lane boundaries are parallel: a short boundary (a single dash, say) takes the direction
    and curvature of a long one and keeps only its own lateral position."""
    if left is None or right is None:
        return left, right

    def refit(short: Boundary, long: Boundary) -> Boundary:
        x, y = short.points_xy[:, 0], short.points_xy[:, 1]
        c = long.coeffs
        w = 1.0 / np.maximum(np.abs(x - camera_x_m), 1.0) ** 2
        c0 = float(np.sum(w * (y - c[1] * x - c[2] * x * x)) / np.sum(w))
        return replace(short, coeffs=np.array([c0, c[1], c[2]]))

    if left.x_span_m < rules.quadratic_span_m and right.x_span_m >= 2.0 * left.x_span_m:
        left = refit(left, right)
    elif right.x_span_m < rules.quadratic_span_m and left.x_span_m >= 2.0 * right.x_span_m:
        right = refit(right, left)
    return left, right


def assemble(
    left: Boundary | None,
    right: Boundary | None,
    x_ref: float,
    rules: LaneRules,
    camera: CameraModel,
    confidence: float,
    lane_width_m: float | None = None,
) -> LaneEstimate:
    """Offset at `x_ref` from the two boundaries, or from one and the lane width."""
    width = lane_width_m or rules.lane_width_m
    if left is not None and right is not None:
        measured = float(poly_eval(left.coeffs, x_ref) - poly_eval(right.coeffs, x_ref))
        if abs(measured - width) > rules.width_tolerance_m:
            # Inconsistent pair: keep the side with more support.
            if left.n_points * left.x_span_m >= right.n_points * right.x_span_m:
                right = None
            else:
                left = None
            confidence *= 0.5
    if left is None and right is None:
        return LaneEstimate.invalid("no lane boundary found", x_m=x_ref)
    if left is not None and right is not None:
        centre = (poly_eval(left.coeffs, x_ref) + poly_eval(right.coeffs, x_ref)) / 2.0
    elif left is not None:
        centre = poly_eval(left.coeffs, x_ref) - width / 2.0
        confidence *= 0.6
    else:
        centre = poly_eval(right.coeffs, x_ref) + width / 2.0
        confidence *= 0.6
    offset = -float(centre)
    if not math.isfinite(offset) or abs(offset) > width:
        return LaneEstimate.invalid("lane centre out of reach", x_m=x_ref)
    image_points = {}
    for side, b in (("left", left), ("right", right)):
        if b is not None:
            uv, ok = camera.project_ground(b.points_xy)
            image_points[side] = uv[ok]
    return LaneEstimate(
        valid=True,
        offset_m=offset,
        x_m=float(x_ref),
        left=None if left is None else left.coeffs.copy(),
        right=None if right is None else right.coeffs.copy(),
        confidence=float(np.clip(confidence, 0.0, 1.0)),
        image_points=image_points,
    )


def crop_and_scale(frame: np.ndarray, top: int, scale: float) -> np.ndarray:
    """The region of interest (rows from `top` down) at the working resolution."""
    roi = frame[top:]
    if scale == 1.0:
        return roi
    h, w = roi.shape[:2]
    size = (max(1, int(round(w * scale))), max(1, int(round(h * scale))))
    return cv2.resize(roi, size, interpolation=cv2.INTER_AREA)


def remove_streaks(mask: np.ndarray, min_rows: int, max_tilt_deg: float,
                   max_width: int = 5) -> np.ndarray:
    """The binary ROI without rain streaks: thin runs within `max_tilt_deg` of vertical.

    Falling rain renders as near-vertical bright lines. Lane paint is never that steep in the
    image: a boundary leans from vertical by atan(|y| / camera height), over 25 deg even 0.7 m
    from the car, so a line-shaped opening tilted a few degrees either way finds the streaks
    and nothing else. Streaks are also thin (2-4 px at 720 rows after the binarisation's
    dilation): anything wider than `max_width` is kept, for near paint is thick enough to hold
    tall runs of its own. `min_rows` and `max_width` are working-resolution pixels; see
    `streak_pixels` for their scaling with the camera's size.
    """
    if min_rows <= 0:
        return mask
    streaks = np.zeros_like(mask)
    for kernel in _streak_kernels(min_rows, max_tilt_deg):
        streaks |= cv2.morphologyEx(mask, cv2.MORPH_OPEN, kernel)
    thick = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((1, max_width + 1), np.uint8))
    streaks = cv2.bitwise_and(streaks, cv2.bitwise_not(thick))
    streaks = cv2.dilate(streaks, np.ones((1, 3), np.uint8))
    streaks = cv2.bitwise_and(streaks, cv2.bitwise_not(thick))
    return cv2.bitwise_and(mask, cv2.bitwise_not(streaks))


@functools.lru_cache(maxsize=8)
def _streak_kernels(min_rows: int, max_tilt_deg: float) -> tuple[np.ndarray, ...]:
    """Line kernels `min_rows` tall at five tilts within +-`max_tilt_deg` (built once)."""
    kernels = []
    for tilt in np.linspace(-max_tilt_deg, max_tilt_deg, 5):
        dx = int(round(np.tan(np.radians(tilt)) * (min_rows - 1)))
        kernel = np.zeros((min_rows, abs(dx) + 1), np.uint8)
        cols = np.linspace(0, dx, min_rows).round().astype(int) - min(dx, 0)
        kernel[np.arange(min_rows), cols] = 1
        kernels.append(kernel)
    return tuple(kernels)


STREAK_REFERENCE_ROWS = 720  # streak sizes are given in pixels of a camera this tall
STREAK_MAX_WIDTH_PX = 10  # at the reference size: wider runs are paint, not rain


def streak_pixels(preprocess, frame_rows: int) -> tuple[int, int]:
    """Minimum streak length and maximum streak width in working pixels for this frame size.

    Both are given in full-resolution pixels of a 720-row camera; rain (and paint) shrink with
    the image and the working scale, so both scale with `frame_rows / 720 * scale`. Below 3 rows
    a "streak" is any speck, so the filter switches off; the width never falls below 1 px.
    """
    ratio = _working_ratio(preprocess, frame_rows)
    min_rows = int(round(preprocess.streak_min_rows * ratio))
    max_width = max(1, int(round(STREAK_MAX_WIDTH_PX * ratio)))
    return (min_rows if min_rows >= 3 else 0), max_width


def destreak_pixels(preprocess, frame_rows: int) -> int:
    """Width in working pixels below which a bright feature along a row is taken for rain."""
    return int(round(preprocess.destreak_width_px * _working_ratio(preprocess, frame_rows)))


def _working_ratio(preprocess, frame_rows: int) -> float:
    """Working pixels per full-resolution pixel of a 720-row camera, for this frame."""
    return frame_rows / STREAK_REFERENCE_ROWS * preprocess.scale


def open_along_rows(image: np.ndarray, width_px: int) -> np.ndarray:
    """The image without bright features narrower than `width_px` along a row (grey opening).

    Rain streaks are near vertical, so a row crosses them in 1-2 working pixels. Lane paint
    leans at least ~45 deg from vertical in a forward camera (its image line runs to the
    vanishing point from a boundary 1.5-2 m beside a camera 1.5 m high), so a row crosses even
    the far, thin paint over more pixels than its width: it survives an opening that the
    streaks do not. Width < 2 leaves the image as it is.
    """
    if width_px < 2:
        return image
    return cv2.morphologyEx(image, cv2.MORPH_OPEN, np.ones((1, width_px), np.uint8))


def reject_noise(mask: np.ndarray, max_fill: float, min_coherence: float) -> str:
    """Why a binary ROI looks like noise rather than paint ('' when it does not)."""
    filled = cv2.countNonZero(mask)
    fill = filled / mask.size
    if fill > max_fill:
        return f"binary image too full ({fill:.0%}): noise"
    if filled:
        opened = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((2, 2), np.uint8))
        coherence = cv2.countNonZero(opened) / filled
        if coherence < min_coherence:
            return f"binary image is speckle ({coherence:.0%} survives an opening): noise"
    return ""


def view_for(camera: CameraModel, window: GroundWindow, scale: float, margin_px: float,
             distortion: np.ndarray | None = None) -> BirdsEye:
    """The bird's-eye view a detector uses: visible part of the window, ROI below its far edge."""
    window = visible_window(camera, window)
    top = roi_crop(camera, window, margin_px)
    return BirdsEye(camera, window, scale=scale, crop_top=top, distortion=distortion)


def detector_view(camera: CameraModel, config, distortion: np.ndarray | None = None
                  ) -> tuple[BirdsEye, float]:
    """The bird's-eye view of a camera's ground window and the look-ahead x it reports at."""
    pre = config.preprocess
    window = config.window_for(camera.name)
    view = view_for(camera, window, pre.scale, pre.horizon_margin_px, distortion)
    w = view.window
    return view, (w.lookahead_m if w.lookahead_m is not None else w.x_near_m)


def binary_bird_eye(frame: np.ndarray, camera: CameraModel, view: BirdsEye, preprocess,
                    binarise) -> tuple[np.ndarray | None, str]:
    """A frame's binary bird's-eye view (0/255), or None and why its binary image is noise.

    The image stage both models share; `binarise` is each model's own thresholding of the ROI.
    """
    check_frame(frame, camera)
    roi = crop_and_scale(frame, view.crop_top, preprocess.scale)
    roi = open_along_rows(roi, destreak_pixels(preprocess, frame.shape[0]))
    mask = binarise(roi)
    # Fill first (a flooded mask is noise whatever it holds); the speckle test after the rain
    # streaks are gone, for a 1-px streak fails the opening just as sensor noise does.
    noise = reject_noise(mask, preprocess.max_fill, 0.0)
    if noise:
        return None, noise
    min_rows, max_width = streak_pixels(preprocess, frame.shape[0])
    mask = remove_streaks(mask, min_rows, preprocess.streak_max_tilt_deg, max_width)
    noise = reject_noise(mask, 1.0, preprocess.min_coherence)
    if noise:
        return None, noise
    bev = view.warp(mask)
    return np.where(bev >= 128, 255, 0).astype(np.uint8), ""


def support_confidence(left: Boundary | None, right: Boundary | None, view: BirdsEye) -> float:
    """Share of the ground window's depth the found boundaries cover (both sides summed, <= 1)."""
    support = sum(b.x_span_m for b in (left, right) if b is not None)
    span = abs(view.window.x_far_m - view.window.x_near_m)
    return min(1.0, support / span)
