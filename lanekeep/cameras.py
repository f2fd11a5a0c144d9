"""The two onboard cameras: pinhole model from MuJoCo's fovy, ground projection, rendering.

MuJoCo cameras look along their local -z with +y up and square pixels; the vertical field of
view `fovy` fixes the focal length: fy = (H/2) / tan(fovy/2) = fx. The principal point is the
image centre, (W-1)/2, (H-1)/2 in OpenCV's pixel-centre convention. Real cameras (for
`lanekeep detect`) are built from calibrated intrinsics and a mounting height and pitch.
Simulated cameras' poses are read from the compiled model relative to the body "car", whose
frame is the vehicle ground frame (origin on the ground under the middle of the wheelbase,
x forward, y left, z up), so the projection here and the render always agree.
"""

from __future__ import annotations

import math
import threading
from contextlib import contextmanager
from dataclasses import dataclass, replace

import mujoco
import numpy as np

# Geom groups (see mjcf/car.xml and lanekeep/world.py).
GROUP_WORLD = 0
GROUP_MARKING = 1
GROUP_CAR_BODY = 2
GROUP_CAR_COLLISION = 3
GROUP_SHADOW = 5  # translucent shadow geoms: hidden from the segmentation render


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
    def from_model(
        cls, model: mujoco.MjModel, name: str, width: int = 1280, height: int = 720
    ) -> CameraModel:
        """Read pose and fovy of camera `name` from a compiled model (car at rest)."""
        cam = model.camera(name)
        quat = np.asarray(model.cam_quat[cam.id], dtype=float)
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, quat)
        parent = int(model.cam_bodyid[cam.id])
        if model.body(parent).name != "car":
            raise ValueError(f"camera {name!r} is not mounted on the body 'car'")
        focal = (height / 2.0) / math.tan(math.radians(float(model.cam_fovy[cam.id])) / 2.0)
        return cls(
            name=name,
            width=width,
            height=height,
            fx=focal,
            fy=focal,
            cx=(width - 1) / 2.0,
            cy=(height - 1) / 2.0,
            position_m=np.asarray(model.cam_pos[cam.id], dtype=float).copy(),
            rotation=rot.reshape(3, 3),
        )

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


def front_and_rear(model: mujoco.MjModel, width: int = 1280, height: int = 720) -> dict:
    """Camera models of both onboard cameras at a given image size."""
    return {n: CameraModel.from_model(model, n, width, height) for n in ("front", "rear")}


@dataclass(frozen=True)
class RenderSettings:
    """What the renderer draws; shadows are opt-in because they double the cost on a CPU."""

    width: int = 1280
    height: int = 720
    shadows: bool = False
    fog: bool = True  # MuJoCo fog; scenes without fog put it beyond the far plane (conditions)


# Set while no MuJoCo render runs in this process. Mesa's llvmpipe rasterises with a thread per
# core and waits for the slowest: a busy background thread (the recorder's writer) made a
# 21 ms render take 56 ms on two cores. Background work waits for this before each piece.
RENDERER_IDLE = threading.Event()
RENDERER_IDLE.set()


@contextmanager
def _rendering():
    RENDERER_IDLE.clear()
    try:
        yield
    finally:
        RENDERER_IDLE.set()


class CameraRig:
    """One reused `mujoco.Renderer` per camera; RGB and segmentation renders.

    The ego car's geoms are hidden (groups 2 and 3) as on AirSim's onboard cameras; the
    segmentation render also hides the translucent shadow geoms so the marking masks are exact.
    Call `close()` (or use as a context manager): EGL teardown at interpreter exit is noisy.
    """

    CAMERA_NAMES = ("front", "rear")

    def __init__(self, model: mujoco.MjModel, settings: RenderSettings | None = None) -> None:
        self.model = model
        self.settings = settings or RenderSettings()
        w, h = self.settings.width, self.settings.height
        if w > model.vis.global_.offwidth or h > model.vis.global_.offheight:
            raise ValueError(
                f"render size {w}x{h} exceeds the model's offscreen buffer "
                f"{model.vis.global_.offwidth}x{model.vis.global_.offheight}"
            )
        self.cameras = {n: CameraModel.from_model(model, n, w, h) for n in self.CAMERA_NAMES}
        try:
            self._renderers = {
                n: mujoco.Renderer(model, height=h, width=w) for n in self.CAMERA_NAMES
            }
        except Exception as exc:  # noqa: BLE001 - any GL failure means the same thing to a user
            raise RuntimeError(
                f"cannot create an offscreen MuJoCo renderer ({exc}); on a headless machine set "
                "MUJOCO_GL=egl and install an EGL driver (e.g. Mesa's libegl1)"
            ) from exc
        self._rgb_option = mujoco.MjvOption()
        self._seg_option = mujoco.MjvOption()
        for option in (self._rgb_option, self._seg_option):
            option.geomgroup[GROUP_CAR_BODY] = 0
            option.geomgroup[GROUP_CAR_COLLISION] = 0
            option.geomgroup[GROUP_SHADOW] = 1
        self._seg_option.geomgroup[GROUP_SHADOW] = 0
        self._closed = False

    def render_rgb(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """RGB uint8 image (H, W, 3) of one camera."""
        renderer = self._renderers[camera]
        renderer.disable_segmentation_rendering()
        renderer.update_scene(data, camera=camera, scene_option=self._rgb_option)
        renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = self.settings.shadows
        renderer.scene.flags[mujoco.mjtRndFlag.mjRND_FOG] = self.settings.fog
        with _rendering():
            return renderer.render()

    def render_segmentation(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """Geom id per pixel (H, W) int32, -1 where no geom (sky)."""
        renderer = self._renderers[camera]
        renderer.enable_segmentation_rendering()
        try:
            renderer.update_scene(data, camera=camera, scene_option=self._seg_option)
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_FOG] = False  # ids must stay exact
            with _rendering():
                seg = renderer.render()
        finally:
            renderer.disable_segmentation_rendering()
        ids = seg[..., 0].astype(np.int32)
        ids[seg[..., 1] != int(mujoco.mjtObj.mjOBJ_GEOM)] = -1
        return ids

    def close(self) -> None:
        if not self._closed:
            for renderer in self._renderers.values():
                renderer.close()
            self._closed = True

    def __enter__(self) -> CameraRig:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
