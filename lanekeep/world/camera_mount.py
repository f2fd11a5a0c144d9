"""The onboard cameras of a compiled model: re-mounted (height, pitch, roll, yaw and field of
view) and read back as pinhole camera models.

The scenario's `[camera]` mounting keys (lanekeep/scenario/schema.py CameraConfig) change the
car's own cameras (mjcf/car.xml) after compilation, in `model.cam_pos`, `cam_quat` and
`cam_fovy`. Everything that projects (`camera_from_model`, so the detectors and the dataset's
labels) reads those fields, so render and projection agree for any mounting.

Rotations compose as q = yaw (about the car's z) * nominal * pitch (about the camera's x,
its image right) * roll (about the camera's z, its optical axis reversed): pitch and roll
are the camera's own, yaw is the car's, as one mounts a camera on a car.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from lanekeep.geometry.camera_model import CameraModel

ONBOARD_CAMERAS = ("front", "rear")


def _axis_quat(axis: tuple[float, float, float], angle_deg: float) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_axisAngle2Quat(q, np.asarray(axis, dtype=float), math.radians(angle_deg))
    return q


def _mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, a, b)
    return out


def is_default(camera) -> bool:
    """True when the scenario keeps the car's own mounting (nothing to change)."""
    return (camera.mount_height_m == 0.0 and camera.pitch_offset_deg == 0.0
            and camera.roll_deg == 0.0 and camera.yaw_offset_deg == 0.0
            and camera.fov_scale == 1.0)


def apply_camera_mount(model: mujoco.MjModel, camera) -> None:
    """Change the onboard cameras of `model` in place by `camera` (a CameraConfig)."""
    if is_default(camera):
        return
    yaw = _axis_quat((0.0, 0.0, 1.0), camera.yaw_offset_deg)
    pitch = _axis_quat((1.0, 0.0, 0.0), camera.pitch_offset_deg)
    roll = _axis_quat((0.0, 0.0, 1.0), camera.roll_deg)
    for name in ONBOARD_CAMERAS:
        cid = model.camera(name).id
        q = _mul(_mul(_mul(yaw, model.cam_quat[cid]), pitch), roll)
        model.cam_quat[cid] = q / np.linalg.norm(q)
        if camera.mount_height_m > 0.0:
            model.cam_pos[cid, 2] = camera.mount_height_m
        half = math.radians(float(model.cam_fovy[cid])) / 2.0
        model.cam_fovy[cid] = math.degrees(2.0 * math.atan(camera.fov_scale * math.tan(half)))


def camera_from_model(model: mujoco.MjModel, name: str, width: int = 1280,
                      height: int = 720) -> CameraModel:
    """The camera `name` of a compiled model (car at rest): pose and fovy read from it."""
    cam = model.camera(name)
    quat = np.asarray(model.cam_quat[cam.id], dtype=float)
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, quat)
    parent = int(model.cam_bodyid[cam.id])
    if model.body(parent).name != "car":
        raise ValueError(f"camera {name!r} is not mounted on the body 'car'")
    focal = (height / 2.0) / math.tan(math.radians(float(model.cam_fovy[cam.id])) / 2.0)
    return CameraModel(
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


def front_and_rear(model: mujoco.MjModel, width: int = 1280, height: int = 720) -> dict:
    """Camera models of both onboard cameras at a given image size."""
    return {n: camera_from_model(model, n, width, height) for n in ("front", "rear")}
