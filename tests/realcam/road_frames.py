"""Small synthetic road frames and videos for the sequence tests (tests/realcam/test_frames.py,
tests/cli/test_detect_sequence.py)."""

from __future__ import annotations

import cv2
import numpy as np

W, H = 320, 180


def road(shift_m: float = 0.0, size: tuple[int, int] = (W, H)) -> np.ndarray:
    """A flat road (BGR) seen by the default dashcam (60 deg hfov, 1.5 m, level), lanes 3.7 m
    apart, the car `shift_m` left of the lane's middle."""
    w, h = size
    image = np.full((h, w, 3), (95, 95, 95), np.uint8)
    image[: h // 2] = (200, 170, 120)
    f = (w / 2.0) / np.tan(np.radians(30.0))
    for y_lane in (1.85, -1.85):
        for x in np.arange(4.0, 80.0, 0.1):
            v = (h - 1) / 2.0 + f * 1.5 / x
            u = (w - 1) / 2.0 - f * (y_lane - shift_m) / x
            if 0 <= u < w and v < h:
                cv2.circle(image, (int(u), int(v)), max(1, int(f * 0.075 / x)), (240,) * 3, -1)
    return image


def write_video(path, frames: list[np.ndarray], fps: float = 10.0, fourcc: str = "MJPG") -> str:
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
    assert writer.isOpened()
    for frame in frames:
        writer.write(frame)
    writer.release()
    return str(path)


def read_back(path) -> tuple[list[np.ndarray], float]:
    capture = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = capture.read()
        if not ok:
            break
        frames.append(frame)
    fps = capture.get(cv2.CAP_PROP_FPS)
    capture.release()
    return frames, fps
