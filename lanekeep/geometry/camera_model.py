"""The pinhole camera model: intrinsics, mounting, pixel <-> ground-plane projection.

No MuJoCo here: detectors and the calibration tools use this module on real photos, and the
simulated cameras are made from a compiled model by `lanekeep.sensing.cameras.camera_from_model`.
Conventions: the vehicle ground frame has x forward, y left, z up, origin on the ground under
the middle of the wheelbase; the camera rotation's columns are MuJoCo's camera axes (right,
up, back: the camera looks along its -z); pixel centres are at integers (OpenCV).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class CameraModel:
    """Pinhole camera in the vehicle ground frame (OpenCV intrinsics, pixel centres at integers).

    Attributes:
        name: camera name (the MuJoCo camera for simulated ones).
        width, height: image size in pixels.
        fx, fy, cx, cy: intrinsics in pixels.
        position_m: camera centre in the vehicle frame (3,).
        rotation: camera-to-vehicle rotation, columns = MuJoCo camera axes (right, up, back).
    """

    name: str
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    position_m: np.ndarray
    rotation: np.ndarray

    @classmethod
    def from_mounting(
        cls,
        name: str,
        K: np.ndarray,  # noqa: N803 - the textbook symbol
        width: int,
        height: int,
        height_m: float,
        pitch_rad: float,
        x_m: float = 0.0,
        yaw_rad: float = 0.0,
    ) -> CameraModel:
        """A camera from intrinsics and mounting (height, pitch + = up, yaw 0 = forward)."""
        cp, sp, cyaw, syaw = math.cos(pitch_rad), math.sin(pitch_rad), math.cos(yaw_rad), math.sin(
            yaw_rad
        )
        forward = np.array([cp * cyaw, cp * syaw, sp])
        right = np.array([syaw, -cyaw, 0.0])
        up = np.cross(-forward, right)
        rotation = np.stack([right, up, -forward], axis=1)
        K = np.asarray(K, dtype=float)  # noqa: N806
        return cls(
            name=name,
            width=int(width),
            height=int(height),
            fx=float(K[0, 0]),
            fy=float(K[1, 1]),
            cx=float(K[0, 2]),
            cy=float(K[1, 2]),
            position_m=np.array([x_m, 0.0, height_m]),
            rotation=rotation,
        )

    # -- intrinsics --------------------------------------------------------------------------
    @property
    def K(self) -> np.ndarray:  # noqa: N802 - the textbook symbol
        """3x3 intrinsic matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def fovy_deg(self) -> float:
        return math.degrees(2.0 * math.atan(self.height / 2.0 / self.fy))

    @property
    def fovx_deg(self) -> float:
        return math.degrees(2.0 * math.atan(self.width / 2.0 / self.fx))

    @property
    def pitch_rad(self) -> float:
        """Elevation of the optical axis above the vehicle's horizontal plane (+ = up)."""
        forward = -self.rotation[:, 2]
        return math.asin(float(np.clip(forward[2], -1.0, 1.0)))

    @property
    def height_m(self) -> float:
        return float(self.position_m[2])

    def scaled(self, width: int, height: int) -> CameraModel:
        """The same camera rendering at another image size (intrinsics scale with it)."""
        sx, sy = width / self.width, height / self.height
        return replace(
            self,
            width=width,
            height=height,
            fx=self.fx * sx,
            fy=self.fy * sy,
            cx=(self.cx + 0.5) * sx - 0.5,
            cy=(self.cy + 0.5) * sy - 0.5,
        )

    def horizon_row(self) -> float:
        """Image row of the horizon of a flat ground (the vanishing line), at the centre column."""
        return self.cy + self.fy * math.tan(self.pitch_rad)

    # -- projection --------------------------------------------------------------------------
    def to_opencv_frame(self, points_vehicle: np.ndarray) -> np.ndarray:
        """Vehicle-frame points (..., 3) to OpenCV camera coordinates (x right, y down, z fwd)."""
        p = np.asarray(points_vehicle, dtype=float) - self.position_m
        cam = p @ self.rotation  # = R^T p for each row: MuJoCo camera coordinates
        return cam * np.array([1.0, -1.0, -1.0])

    def project(self, points_vehicle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Project vehicle-frame points (..., 3) to pixels (..., 2) and an in-front mask."""
        cv = self.to_opencv_frame(points_vehicle)
        z = cv[..., 2]
        in_front = z > 1e-6
        safe_z = np.where(in_front, z, 1.0)
        u = self.fx * cv[..., 0] / safe_z + self.cx
        v = self.fy * cv[..., 1] / safe_z + self.cy
        return np.stack([u, v], axis=-1), in_front

    def project_ground(self, xy_vehicle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Project ground points (..., 2) (z = 0) in the vehicle frame to pixels."""
        xy = np.asarray(xy_vehicle, dtype=float)
        pts = np.concatenate([xy, np.zeros(xy.shape[:-1] + (1,))], axis=-1)
        return self.project(pts)

    def pixel_rays(self, pixels: np.ndarray) -> np.ndarray:
        """Unit-free ray directions (..., 3) in the vehicle frame through pixel centres."""
        uv = np.asarray(pixels, dtype=float)
        x = (uv[..., 0] - self.cx) / self.fx
        y = (uv[..., 1] - self.cy) / self.fy
        cam_mujoco = np.stack([x, -y, -np.ones_like(x)], axis=-1)
        return cam_mujoco @ self.rotation.T

    def pixels_to_ground(self, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Intersect pixel rays with the ground plane z = 0: (..., 2) metres and a valid mask."""
        rays = self.pixel_rays(pixels)
        dz = rays[..., 2]
        valid = dz < -1e-9
        t = np.where(valid, -self.position_m[2] / np.where(valid, dz, -1.0), np.nan)
        ground = self.position_m[:2] + rays[..., :2] * t[..., None]
        return ground, valid
