"""A trivial lane detector, whole in one module: what adding a detector takes.

It reports a straight lane of the configured width centred on the car, whatever the frame
shows. Its settings come from a `[straight_ahead]` table of the detectors TOML file.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.config import DetectorsConfig, GroundWindow
from lanekeep.detectors.registry import register_detector
from lanekeep.geometry.camera_model import CameraModel


@dataclass(frozen=True)
class StraightAheadSettings:
    lane_width_m: float = 3.7
    x_ref_m: float = 5.0


class StraightAheadDetector:
    name = "straight_ahead"

    def __init__(self, camera: CameraModel, config: DetectorsConfig | None = None,
                 distortion: np.ndarray | None = None,
                 settings: StraightAheadSettings = StraightAheadSettings()) -> None:
        self.settings = settings
        self.x_ref = settings.x_ref_m
        self.window = GroundWindow(x_near_m=4.0, x_far_m=20.0)

    def reset(self) -> None:
        """Stateless."""

    def detect(self, frame: np.ndarray) -> LaneEstimate:
        half = self.settings.lane_width_m / 2.0
        return LaneEstimate(valid=True, offset_m=0.0, x_m=self.x_ref,
                            left=np.array([half, 0.0, 0.0]), right=np.array([-half, 0.0, 0.0]),
                            confidence=1.0)


register_detector("straight_ahead", StraightAheadDetector, settings=StraightAheadSettings)
