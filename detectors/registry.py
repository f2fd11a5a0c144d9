"""Detectors by name: the episode and the CLI build them here.

    make_detector("sliding_window", camera)            # tuned config from detectors.toml
    make_detector("hough", camera, load_config(path))  # another config file

A new detector is one module that defines its class (and, if it has settings, a frozen
dataclass of them) and registers both:

    register_detector("my_detector", MyDetector, settings=MySettings)

Its settings then come from a `[my_detector]` table of the detectors TOML file, checked as
strictly as the rest (an unknown key names itself), and reach the detector as `settings=`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from detectors.base import Detector
from detectors.config import DetectorsConfig, load_config, register_table
from detectors.hough import HoughDetector
from detectors.sliding_window import SlidingWindowDetector
from lanekeep.camera_model import CameraModel
from lanekeep.config_io import from_dict

Factory = Callable[..., Detector]

DETECTORS: dict[str, Factory] = {
    "hough": HoughDetector,
    "sliding_window": SlidingWindowDetector,
}
SETTINGS: dict[str, type] = {}  # detector name -> its settings dataclass, if it has one


def register_detector(name: str, factory: Factory, settings: type | None = None) -> None:
    """Make `factory(camera, config=..., distortion=...[, settings=...])` known as `name`."""
    if name in DETECTORS:
        raise ValueError(f"a detector named {name!r} is already registered")
    DETECTORS[name] = factory
    if settings is not None:
        SETTINGS[name] = settings
        register_table(name)


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
    if name not in SETTINGS:
        return factory(camera, config=config, distortion=distortion)
    config = config or load_config()
    settings = from_dict(SETTINGS[name], config.tables.get(name, {}), path=name,
                         source="detectors config")
    return factory(camera, config=config, distortion=distortion, settings=settings)
