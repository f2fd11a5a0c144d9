"""A user's own detector and controller, written as a user outside the package would: plain
classes with the constructor contracts of lanekeep.detectors.registry and lanekeep.control.registry,
no registration. tests/core/test_plugins_api.py copies this file under another module name into a
temporary folder and names the classes by import path or through an entry point.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from lanekeep.control.pid import SpeedController
from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.hough import HoughDetector


class MedianHough:
    """The Hough detector with a temporal median of its last three valid lanes: a filter a
    user might try against single-frame outliers (a worn dash, a shadow edge)."""

    name = "median_hough"

    def __init__(self, camera, config=None, distortion=None) -> None:
        self.inner = HoughDetector(camera, config=config, distortion=distortion)
        self.x_ref = self.inner.x_ref
        self.history: deque[tuple[np.ndarray, np.ndarray]] = deque(maxlen=3)

    @property
    def window(self):
        return self.inner.window

    def reset(self) -> None:
        self.inner.reset()
        self.history.clear()

    def detect(self, frame: np.ndarray) -> LaneEstimate:
        raw = self.inner.detect(frame)
        if not raw.valid or raw.left is None or raw.right is None:
            return raw
        self.history.append((np.asarray(raw.left, float), np.asarray(raw.right, float)))
        left = np.median([h[0] for h in self.history], axis=0)
        right = np.median([h[1] for h in self.history], axis=0)
        x = raw.x_m
        centre = (left + right) / 2.0
        offset = -float(centre[0] + centre[1] * x + centre[2] * x * x)
        return LaneEstimate(valid=True, offset_m=offset, x_m=x, left=left, right=right,
                            confidence=raw.confidence)


class PurePursuit:
    """Pure pursuit (Coulter, CMU-RI-TR-92-01, 1992): steer the arc through the lane centre
    `lookahead_s` seconds ahead, delta = atan(2 L y / l_d^2) with y its lateral position."""

    def __init__(self, context, lookahead_s: float = 0.8, min_lookahead_m: float = 6.0) -> None:
        self.context = context
        self.lookahead_s, self.min_lookahead_m = lookahead_s, min_lookahead_m
        self.speed = SpeedController(context.target_speed_mps, context.dt_s)

    def reset(self) -> None:
        self.speed.reset()

    def control(self, estimate, signals) -> tuple[float, float]:
        throttle = self.speed(signals.speed_mps)
        if estimate.centre is None:
            return 0.0, throttle
        ld = max(self.lookahead_s * signals.speed_mps, self.min_lookahead_m)
        c = estimate.centre
        y = float(c[0] + c[1] * ld + c[2] * ld * ld)
        delta = math.atan(2.0 * self.context.wheelbase_m * y / (ld * ld + y * y))
        return max(-1.0, min(1.0, delta / self.context.max_steer_rad)), throttle


class NotADetector:
    """Builds, but has no `detect`: make_detector must say so."""

    def __init__(self, camera, config=None, distortion=None) -> None:
        self.camera = camera


NOT_CALLABLE = 42
