"""OpenCV chessboard calibration: intrinsics and distortion from photos of a printed board."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from lanekeep.realcam.camera_file import CameraFile


class CalibrationError(ValueError):
    """Too few usable chessboard images, or images of different sizes."""


@dataclass(frozen=True)
class Calibration:
    camera: CameraFile
    rms_px: float  # reprojection RMS over all corners
    used: list[str] = field(default_factory=list)
    rejected: list[tuple[str, str]] = field(default_factory=list)  # (image, why)


def parse_pattern(text: str) -> tuple[int, int]:
    """'9x6' -> (9, 6): inner corners per row and column."""
    try:
        cols, rows = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise ValueError(f"pattern must look like 9x6, got {text!r}") from None
    if cols < 2 or rows < 2:
        raise ValueError(f"pattern needs at least 2x2 inner corners, got {text!r}")
    return cols, rows


def find_corners(grey: np.ndarray, pattern: tuple[int, int]) -> np.ndarray | None:
    found, corners = cv2.findChessboardCorners(
        grey, pattern, cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    )
    if not found:
        return None
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 40, 1e-3)
    return cv2.cornerSubPix(grey, corners, (7, 7), (-1, -1), criteria)


def calibrate(
    images: list[tuple[str, np.ndarray]],
    pattern: tuple[int, int] = (9, 6),
    min_images: int = 5,
    height_m: float = 1.5,
) -> Calibration:
    """Calibrate from (name, image) pairs (RGB or grey, all one size).

    Raises CalibrationError when fewer than `min_images` show the whole pattern.
    """
    cols, rows = pattern
    board = np.zeros((cols * rows, 3), np.float32)
    board[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2)  # unit squares: K needs no scale
    obj, img, used, rejected = [], [], [], []
    size = None
    for name, image in images:
        grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image
        if size is None:
            size = grey.shape[::-1]
        elif grey.shape[::-1] != size:
            rejected.append((name, f"size {grey.shape[1]}x{grey.shape[0]} differs from {size}"))
            continue
        corners = find_corners(grey, pattern)
        if corners is None:
            rejected.append((name, f"no {cols}x{rows} chessboard found"))
            continue
        obj.append(board)
        img.append(corners)
        used.append(name)
    if len(used) < min_images:
        raise CalibrationError(
            f"only {len(used)} of {len(images)} images show a {cols}x{rows} chessboard; "
            f"need at least {min_images}"
        )
    rms, K, dist, _, _ = cv2.calibrateCamera(obj, img, size, None, None)  # noqa: N806
    w, h = size
    camera = CameraFile(
        width=int(w), height=int(h), fx=float(K[0, 0]), fy=float(K[1, 1]),
        cx=float(K[0, 2]), cy=float(K[1, 2]),
        distortion=tuple(float(v) for v in np.ravel(dist)[:5]), height_m=height_m,
    )
    return Calibration(camera, float(rms), used, rejected)


def read_image(path: str | Path) -> np.ndarray:
    """RGB uint8 image; ValueError with a clear message for a missing or unreadable file."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"{path}: no such file")
    image = cv2.imread(str(p), cv2.IMREAD_COLOR)
    if image is None:
        raise ValueError(f"{path}: not an image (OpenCV cannot decode it)")
    return np.ascontiguousarray(image[..., ::-1])
