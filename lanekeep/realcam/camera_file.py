"""Real cameras for `lanekeep detect`: a camera TOML file, or defaults for an unknown dashcam.

A camera file (written by `lanekeep calibrate`, mounting added by hand):

    [camera]
    width = 1280
    height = 720
    fx = 1156.9
    fy = 1152.2
    cx = 665.9
    cy = 388.8
    distortion = [-0.24, -0.05, -0.001, 0.0, 0.02]   # OpenCV k1 k2 p1 p2 k3
    height_m = 1.5                                    # mounting height above the road
    pitch_deg = -2.0                                  # optional, + = up; absent = per image

Without a file (an unknown dashcam, e.g. TuSimple or Udacity highway frames at 1280x720) the
camera is a pinhole with a 60 deg horizontal field of view, centred principal point, mounted
1.5 m high, and its pitch follows from the horizon row found in each image: the vanishing
point of its lane lines (lanekeep/realcam/horizon.py), taken as
pitch = atan((v_horizon - cy) / fy). When no vanishing point is found, the horizon is assumed
at the image middle (a level camera). Numbers: detectors/config.py DashcamDefaults. A sequence
of frames (`lanekeep detect --sequence`) gets one camera, its horizon the median over its first
frames (`camera_for_frames`), so that the camera does not jump from frame to frame.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lanekeep.core.config_io import InvalidValue, from_dict
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.realcam.horizon import horizon_row


@dataclass(frozen=True)
class CameraFile:
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)
    height_m: float = 1.5
    pitch_deg: float | None = None

    def __post_init__(self) -> None:
        if self.width < 16 or self.height < 16:
            raise InvalidValue("width", f"image size {self.width}x{self.height} is too small")
        if not (self.fx > 0 and self.fy > 0):
            raise InvalidValue("fx", "focal lengths must be > 0")
        if not self.height_m > 0:
            raise InvalidValue("height_m", f"must be > 0, got {self.height_m}")

    @property
    def K(self) -> np.ndarray:  # noqa: N802 - the textbook symbol
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def model(self, pitch_rad: float, name: str = "dashcam") -> CameraModel:
        return CameraModel.from_mounting(name, self.K, self.width, self.height, self.height_m,
                                         pitch_rad)

    def scaled(self, width: int, height: int) -> CameraFile:
        """The same camera at another image size (intrinsics scale with it)."""
        sx, sy = width / self.width, height / self.height
        return CameraFile(width, height, self.fx * sx, self.fy * sy, (self.cx + 0.5) * sx - 0.5,
                          (self.cy + 0.5) * sy - 0.5, self.distortion, self.height_m,
                          self.pitch_deg)


def read_camera_file(path: str | Path) -> CameraFile:
    data = tomllib.loads(Path(path).read_text())
    if "camera" not in data:
        raise ValueError(f"{path}: no [camera] table")
    return from_dict(CameraFile, data["camera"], path="camera", source=str(path))


def write_camera_file(path: str | Path, cam: CameraFile, comment: str = "") -> None:
    lines = [f"# {line}" for line in comment.splitlines()]
    lines += [
        "[camera]",
        f"width = {cam.width}",
        f"height = {cam.height}",
        f"fx = {cam.fx:.4f}",
        f"fy = {cam.fy:.4f}",
        f"cx = {cam.cx:.4f}",
        f"cy = {cam.cy:.4f}",
        "distortion = [" + ", ".join(f"{d:.6g}" for d in cam.distortion) + "]",
        f"height_m = {cam.height_m}  # mounting height: measure it",
    ]
    if cam.pitch_deg is not None:
        lines.append(f"pitch_deg = {cam.pitch_deg}")
    else:
        lines.append("# pitch_deg = 0.0  # + = up; absent: estimated from each image's horizon")
    Path(path).write_text("\n".join(lines) + "\n")


def default_camera(width: int, height: int, hfov_deg: float = 60.0, height_m: float = 1.5
                   ) -> CameraFile:
    """An unknown dashcam: pinhole, `hfov_deg` wide, principal point in the middle."""
    f = (width / 2.0) / math.tan(math.radians(hfov_deg) / 2.0)
    return CameraFile(width, height, f, f, (width - 1) / 2.0, (height - 1) / 2.0,
                      height_m=height_m)


def camera_for_image(
    image: np.ndarray,
    camera_file: CameraFile | None,
    hfov_deg: float = 60.0,
    height_m: float = 1.5,
    horizon_fraction: float = 0.5,
    min_fraction: float = 0.2,
    max_fraction: float = 0.75,
) -> tuple[CameraModel, CameraFile, float]:
    """The camera model for one real image: (model, intrinsics file, horizon row used)."""
    return camera_for_frames([image], camera_file, hfov_deg, height_m, horizon_fraction,
                             min_fraction, max_fraction)


def camera_for_frames(
    images: Sequence[np.ndarray],
    camera_file: CameraFile | None,
    hfov_deg: float = 60.0,
    height_m: float = 1.5,
    horizon_fraction: float = 0.5,
    min_fraction: float = 0.2,
    max_fraction: float = 0.75,
) -> tuple[CameraModel, CameraFile, float]:
    """One camera model for frames of one size (a video's first frames): (model, intrinsics
    file, horizon row used). Without a pitch in the camera file the horizon is the median of
    the vanishing points found in `images` (the image middle, `horizon_fraction`, when none
    is), so that one frame whose lines mislead the vanishing point does not tilt the camera."""
    h, w = images[0].shape[:2]
    cam = camera_file or default_camera(w, h, hfov_deg, height_m)
    if (cam.width, cam.height) != (w, h):
        cam = cam.scaled(w, h)
    if cam.pitch_deg is not None:
        pitch = math.radians(cam.pitch_deg)
        horizon = cam.cy + cam.fy * math.tan(pitch)
    else:
        found = [row for row in (horizon_row(image, min_fraction, max_fraction)
                                 for image in images) if row is not None]
        horizon = float(np.median(found)) if found else horizon_fraction * h
        pitch = math.atan((horizon - cam.cy) / cam.fy)
    return cam.model(pitch), cam, horizon
