"""Bird's-eye (inverse perspective) view derived from the camera model.

The ground plane z = 0 of the vehicle frame maps to the image by the homography
    p ~ K [r1 r2 t] (x, y, 1)^T,  with [r1 r2 r3 | t] the vehicle-to-camera (OpenCV) transform,
so the warp follows from intrinsics, mounting height and pitch alone; no hand-picked pixels.
The bird's-eye image looks along the camera's own driving direction: row 0 is the far edge of
the ground window, the last row the edge nearest the car, column 0 the camera's left. So the
same detector code runs on the rear camera, whose view is the road behind (x < 0); points are
converted back to the vehicle frame before any fit, so results are in one frame for all cameras.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

from lanekeep.detectors.config import GroundWindow
from lanekeep.geometry.camera_model import CameraModel


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
