"""Fixtures of the detector tests."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def searched_view(monkeypatch):
    """A function (detector, bev) -> the binary bird's-eye view the classical `detector`'s
    boundary search is given when its image stage yields `bev`: what the steps between the
    two (blob test, dots joined) made of it."""
    def run(detector, bev: np.ndarray) -> np.ndarray:
        seen: list[np.ndarray] = []
        original = detector.find_boundaries
        monkeypatch.setattr(detector, "bird_eye", lambda frame: (bev, ""))
        monkeypatch.setattr(detector, "find_boundaries",
                            lambda view: seen.append(view.copy()) or original(view))
        camera = detector.camera
        detector.detect(np.zeros((camera.height, camera.width, 3), np.uint8))
        return seen[0]
    return run
