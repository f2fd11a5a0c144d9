"""Detectors by name: the episode and the CLI build them here.

    make_detector("sliding_window", camera)            # tuned config from detectors.toml
    make_detector("hough", camera, load_config(path))  # another config file
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from detectors.base import Detector
from detectors.config import DetectorsConfig
from detectors.hough import HoughDetector
from detectors.sliding_window import SlidingWindowDetector
from lanekeep.camera_model import CameraModel

Factory = Callable[..., Detector]

DETECTORS: dict[str, Factory] = {
    "hough": HoughDetector,
    "sliding_window": SlidingWindowDetector,
}


def known_detectors() -> list[str]:
    return sorted(DETECTORS)


def make_detector(
    name: str,
    camera: CameraModel,
    config: DetectorsConfig | None = None,
    distortion: np.ndarray | None = None,
) -> Detector:
    """A detector `name` on `camera` (its ground window is picked by the camera's name:
    "front", "rear", anything else = a real dashcam). Unknown names raise ValueError."""
    try:
        factory = DETECTORS[name]
    except KeyError:
        raise ValueError(
            f"unknown detector {name!r}; known: {', '.join(known_detectors())}"
        ) from None
    return factory(camera, config=config, distortion=distortion)
