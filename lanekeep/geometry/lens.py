"""Lens distortion: the pinhole render bent as a real lens bends it (OpenCV's model).

Why: real cameras are not pinholes. A dashcam's wide lens bows straight lane lines outwards
near the image edges (barrel, k1 < 0), and a detector that ignores its calibration's
distortion fits the wrong curve there. With `[camera] distortion = [k1, k2, p1, p2, k3]` set,
every frame (RGB, segmentation, depth) is resampled from MuJoCo's pinhole render into the
distorted image, and the detectors get the same coefficients, as they get a real camera's from
its camera file (`detect --camera`).

The delivered camera keeps the render's principal point and has its focal length scaled by
`zoom`, the least scale that keeps every delivered pixel inside the render: a barrel lens sees
more of the world at its edges than a pinhole of the same focal length, so the delivered
camera is a little longer (zoom > 1) instead of showing a black rim. `CameraRig.cameras` holds
the delivered camera; the detectors and the labels use it.
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from lanekeep.geometry.camera_model import CameraModel

ZOOM_ITERATIONS = 4  # the fit of zoom: the border's undistorted extent depends on it mildly
SOLVER = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-10)
ROUND_TRIP_PX = 0.05  # a delivered pixel whose undistortion does not distort back this close


def is_distorted(coefficients) -> bool:
    return any(float(c) != 0.0 for c in coefficients)


def _matrix(camera: CameraModel) -> np.ndarray:
    return np.array([[camera.fx, 0.0, camera.cx], [0.0, camera.fy, camera.cy], [0.0, 0.0, 1.0]])


def _undistorted(pixels: np.ndarray, delivered: CameraModel, render: CameraModel,
                 coefficients: np.ndarray) -> np.ndarray:
    """Render (pinhole) pixel coordinates of delivered (distorted) pixels (N, 2).

    Raises ValueError where the lens folds: the polynomial model turns back beyond some
    radius (strong coefficients on a wide camera), and a delivered pixel then has no ray."""
    pts = pixels.reshape(-1, 1, 2).astype(np.float64)
    k_delivered = _matrix(delivered)
    rays = cv2.undistortPoints(pts, k_delivered, coefficients, criteria=SOLVER)
    back, _ = cv2.projectPoints(np.concatenate([rays, np.ones_like(rays[..., :1])], -1),
                                np.zeros(3), np.zeros(3), k_delivered, coefficients)
    worst = float(np.abs(back - pts).max())
    if not worst < ROUND_TRIP_PX:
        fov = 2.0 * np.degrees(np.arctan((render.cx + 0.5) / render.fx))
        key = "camera.distortion" if render.name == "front" else f"camera.{render.name}_distortion"
        raise ValueError(f"{key}: {[round(float(c), 4) for c in coefficients]} "
                         f"folds the image of the {render.name} camera ({fov:.0f} deg wide): "
                         "the lens model turns back before the image's edge; use smaller "
                         "coefficients")
    rays = rays.reshape(-1, 2)
    return np.c_[rays[:, 0] * render.fx + render.cx, rays[:, 1] * render.fy + render.cy]


def _border(width: int, height: int, n: int = 64) -> np.ndarray:
    u, v = np.linspace(-0.5, width - 0.5, n), np.linspace(-0.5, height - 0.5, n)
    return np.concatenate([np.c_[u, np.full(n, -0.5)], np.c_[u, np.full(n, height - 0.5)],
                           np.c_[np.full(n, -0.5), v], np.c_[np.full(n, width - 0.5), v]])


def lens_zoom(render: CameraModel, coefficients) -> float:
    """The delivered camera's focal length over the render's (see the module docstring).

    Raises ValueError (keyed `camera.distortion`) when the lens folds the image."""
    coefficients = np.asarray(coefficients, dtype=np.float64).reshape(-1)
    zoom, border = 1.0, _border(render.width, render.height)
    for _ in range(ZOOM_ITERATIONS):
        delivered = replace(render, fx=render.fx * zoom, fy=render.fy * zoom)
        src = _undistorted(border, delivered, render, coefficients)
        zoom *= max(np.abs(src[:, 0] - render.cx).max() / (render.cx + 0.5),
                    np.abs(src[:, 1] - render.cy).max() / (render.cy + 0.5))
    _undistorted(border, replace(render, fx=render.fx * zoom, fy=render.fy * zoom), render,
                 coefficients)  # the final zoom's border must have rays too
    return zoom


class Lens:
    """Resamples one camera's pinhole renders into the distorted image (maps built once)."""

    def __init__(self, render: CameraModel, coefficients) -> None:
        self.coefficients = np.asarray(coefficients, dtype=np.float64).reshape(-1)
        self.render = render
        w, h = render.width, render.height
        self.zoom = zoom = lens_zoom(render, self.coefficients)
        self.camera = replace(render, fx=render.fx * zoom, fy=render.fy * zoom)
        grid = np.stack(np.meshgrid(np.arange(w, dtype=np.float64),
                                    np.arange(h, dtype=np.float64)), axis=-1)
        src = _undistorted(grid.reshape(-1, 2), self.camera, render, self.coefficients)
        self.map_x, self.map_y = cv2.convertMaps(
            src[:, 0].reshape(h, w).astype(np.float32), src[:, 1].reshape(h, w).astype(np.float32),
            cv2.CV_16SC2)

    def __call__(self, image: np.ndarray, nearest: bool = False) -> np.ndarray:
        """The delivered image of a render (colour: bilinear; ids or depth: `nearest`)."""
        return cv2.remap(image, self.map_x, self.map_y,
                         cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE)
