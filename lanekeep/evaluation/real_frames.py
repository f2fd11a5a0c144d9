"""Lane detection on real frames (`lanekeep detect`): one photo, or a sequence with one detector.

A photo gets its own camera (its horizon from its own vanishing point) and a new detector: a
learned detector's memory of another photo would mislead it. A sequence (a video, or frames in
order: lanekeep/realcam/frames.py) gets one camera for all its frames, its horizon the median of
the vanishing points of its first SEQUENCE_HORIZON_FRAMES frames (realcam.camera_file.
camera_for_frames), so that the camera does not jump from frame to frame, and one detector that
keeps its state across them: LaneNet's GRU memory, the spatiotemporal part of paper 000 (LaneNet
drops it itself at a scene change); the classical detectors keep whatever state they have.

Per frame (`FrameDetector`): the detection, the plausibility verdict (detectors/plausibility.py,
reporting only: the detection is unchanged), the lanes at TuSimple's sample rows (every boundary
of a detector that sees them all, `detector.last.boundaries`; else the ego pair), its output
line (`FrameResult.line`) and its overlay (`FrameResult.overlay`).
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import dataclass
from itertools import islice
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the CLI imports this module at start-up: its imports wait for their use
    from lanekeep.detectors.base import LaneEstimate
    from lanekeep.detectors.config import DetectorsConfig
    from lanekeep.detectors.plausibility import Plausibility
    from lanekeep.detectors.tusimple import NamedLane
    from lanekeep.geometry.camera_model import CameraModel
    from lanekeep.realcam.camera_file import CameraFile
    from lanekeep.realcam.frames import Frame

SEQUENCE_HORIZON_FRAMES = 5  # a sequence's horizon: the median over its first frames

# Overlay colours (BGR): the ego pair green / red, the next boundaries orange / magenta, the
# "other" ones (up to three) cyan, blue and pink; unnamed lanes (classical) alternate.
SLOT_COLOURS = {"ego-left": (0, 255, 0), "ego-right": (0, 0, 255), "next-left": (0, 165, 255),
                "next-right": (255, 0, 255)}
OTHER_COLOURS = [(255, 255, 0), (255, 128, 0), (180, 130, 255)]
UNNAMED_COLOURS = [(0, 255, 0), (255, 0, 0)]


def _lane_colour(name: str | None, k: int, n_other: int) -> tuple[int, int, int]:
    if name is None:
        return UNNAMED_COLOURS[k % 2]
    return SLOT_COLOURS.get(name, OTHER_COLOURS[n_other % len(OTHER_COLOURS)])


def draw_overlay(image: np.ndarray, estimate: LaneEstimate,
                 lanes: list[tuple[str | None, list[int]]], h_samples: list[int],
                 horizon: float, verdict: Plausibility | None = None) -> np.ndarray:
    """The RGB `image` as BGR with each lane (name or None, x per h_sample) drawn, named at its
    bottom, the horizon, the offset and the plausibility verdict."""
    import cv2

    out = image[..., ::-1].copy()
    n_other, labels = 0, []
    for k, (name, xs) in enumerate(lanes):
        colour = _lane_colour(name, k, n_other)
        n_other += name is not None and name not in SLOT_COLOURS
        pts = [(x, v) for x, v in zip(xs, h_samples, strict=True) if x >= 0]
        for a, b in zip(pts, pts[1:], strict=False):
            cv2.line(out, a, b, colour, 3)
        if name is not None and pts:
            x, v = pts[-1]  # the lowest row it reaches
            x, v = min(max(x - 40, 5), out.shape[1] - 140), max(v - 12, 20)
            while any(abs(x - lx) < 130 and abs(v - lv) < 26 for lx, lv in labels):
                v -= 26  # above a neighbour's name rather than over it
            labels.append((x, v))
            cv2.putText(out, name, (x, v), cv2.FONT_HERSHEY_SIMPLEX, 0.8, colour, 2)
    cv2.line(out, (0, int(horizon)), (out.shape[1] - 1, int(horizon)), (0, 255, 255), 1)
    text = (f"offset {estimate.offset_m:+.2f} m at x={estimate.x_m:.1f} m" if estimate.valid
            else f"no lane: {estimate.reason}")
    cv2.putText(out, text, (20, 40), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (255, 255, 255), 2)
    if verdict is not None and estimate.valid:  # the geometry's word on it (plausibility)
        words = "plausible" if verdict.valid else "implausible"
        note = f"{words}, confidence {verdict.confidence:.2f}"
        for k, line in enumerate([note, *verdict.reasons[:3]]):
            cv2.putText(out, line, (20, 80 + 34 * k), cv2.FONT_HERSHEY_SIMPLEX, 0.8,
                        (0, 255, 255) if verdict.valid else (0, 0, 255), 2)
    return out


@dataclass(frozen=True)
class FrameResult:
    """One frame's detection and what `detect` reports of it."""

    estimate: LaneEstimate
    verdict: Plausibility
    h_samples: list[int]
    lanes: list[list[int]]  # x per h_sample (-2 = absent), left to right where named
    named: list[NamedLane] | None  # every boundary with its slot (LaneNet); None: ego pair only
    horizon: float  # image row
    ms: float  # the detector's time on the frame

    def line(self, raw_file: str, fmt: str = "json") -> dict:
        """The frame's output line: TuSimple's record, or the detection with its verdict."""
        from lanekeep.detectors.tusimple import record

        if fmt == "tusimple":
            return record(raw_file, self.lanes, self.h_samples, self.ms)
        estimate = self.estimate
        line = {
            "raw_file": raw_file, **self.verdict.to_dict(),
            "detector_valid": estimate.valid, "detector_confidence": estimate.confidence,
            "offset_m": estimate.offset_m, "x_m": estimate.x_m,
            "left": None if estimate.left is None else [float(c) for c in estimate.left],
            "right": None if estimate.right is None else [float(c) for c in estimate.right],
            "others": [[float(c) for c in coeffs] for coeffs in estimate.others],
            "reason": estimate.reason,
            "horizon_row": self.horizon, "run_time_ms": round(self.ms, 2),
        }
        if self.named is not None:
            line["h_samples"] = list(self.h_samples)
            line["boundaries"] = [{"slot": lane.name, "xs": lane.xs,
                                   "score": round(lane.score, 4)} for lane in self.named]
        return line

    def overlay(self, image: np.ndarray) -> np.ndarray:
        """The RGB `image` with this result drawn (BGR, for OpenCV's writers)."""
        drawn = ([(lane.name, lane.xs) for lane in self.named] if self.named is not None
                 else [(None, xs) for xs in self.lanes])
        return draw_overlay(image, self.estimate, drawn, self.h_samples, self.horizon,
                            self.verdict)


class FrameDetector:
    """One detector on frames of one camera: call it on each frame, in order (a detector with
    state keeps it from call to call)."""

    def __init__(self, detector_name: str, camera: CameraModel, camera_file: CameraFile,
                 camera_known: bool, horizon: float, config: DetectorsConfig,
                 weights: str | None = None) -> None:
        """ValueError (a WeightsError naming the file) when the detector cannot be made."""
        from lanekeep.detectors.registry import make_detector

        distortion = camera_file.distortion if camera_known else None
        self.detector = make_detector(detector_name, camera, config, distortion, weights)
        self.camera, self.camera_file, self.camera_known = camera, camera_file, camera_known
        self.horizon, self.config = horizon, config

    def _verdict(self, estimate: LaneEstimate, image: np.ndarray) -> Plausibility:
        from lanekeep.detectors.plausibility import check, support_share, vehicle_cover

        window = self.detector.window
        covered = (vehicle_cover(image, self.camera, self.config.preprocess) if estimate.valid
                   else None)
        return check(estimate, (window.x_near_m, window.x_far_m), support_share(estimate, covered))

    def __call__(self, image: np.ndarray) -> FrameResult:
        from lanekeep.detectors.tusimple import estimate_lanes, every_lane, h_samples_for

        h, w = image.shape[:2]
        start = time.perf_counter()
        estimate = self.detector.detect(image)
        ms = (time.perf_counter() - start) * 1000.0
        verdict = self._verdict(estimate, image)
        h_samples = h_samples_for(h)
        # Detectors that see every boundary keep them with the frame's other outputs.
        named = every_lane(self.detector, self.camera, self.camera_known, h_samples, (w, h),
                           self.horizon)
        if named is not None:
            lanes = [lane.xs for lane in named]
        else:
            x_range = (float(self.camera.position_m[0]) + 1.0, self.detector.window.x_far_m * 1.3)
            lanes = estimate_lanes(estimate, self.camera, h_samples, x_range)
        return FrameResult(estimate, verdict, h_samples, lanes, named, self.horizon, ms)


def frame_detector(images: Iterable[np.ndarray], detector_name: str, config: DetectorsConfig,
                   camera_file: CameraFile | None = None, weights: str | None = None
                   ) -> FrameDetector:
    """The detector for frames of one size seen by one camera: the camera file's, or the
    unknown dashcam (config.dashcam) whose horizon is the median vanishing point of the first
    SEQUENCE_HORIZON_FRAMES of `images` (one photo: its own). ValueError when the detector
    cannot be made (its weights)."""
    from lanekeep.realcam.camera_file import camera_for_frames

    dash = config.dashcam
    first = list(islice(images, SEQUENCE_HORIZON_FRAMES))
    camera, cam_file, horizon = camera_for_frames(
        first, camera_file, dash.hfov_deg, dash.height_m, dash.horizon_fraction,
        dash.min_horizon_fraction, dash.max_horizon_fraction)
    return FrameDetector(detector_name, camera, cam_file, camera_file is not None, horizon,
                         config, weights)


def sequence_detector(frames: Iterable[Frame], detector_name: str, config: DetectorsConfig,
                      camera_file: CameraFile | None = None, weights: str | None = None
                      ) -> FrameDetector:
    """`frame_detector` for a sequence (`frames`: its frames from the first; only the first
    SEQUENCE_HORIZON_FRAMES are read, and the iterator is closed)."""
    try:
        return frame_detector((frame.image for frame in frames), detector_name, config,
                              camera_file, weights)
    finally:
        close = getattr(frames, "close", None)
        if close is not None:
            close()
