"""Plug-ins that wrap a built-in detector and change nothing but their `name`: the loop must
run them as it runs the built-in (detectors/registry.py `builtin_family`;
tests/loop/test_plugin_family.py, tests/detectors/test_builtin_family.py)."""

from __future__ import annotations

from lanekeep.detectors.hough import HoughDetector
from lanekeep.detectors.lanenet import LaneNetDetector


class Sham(LaneNetDetector):
    name = "sham"


class ShamHough(HoughDetector):
    name = "sham_hough"


class ShamOfSham(Sham):
    """Two steps from the built-in: the nearest registered ancestor still names it."""

    name = "sham_of_sham"


class OwnDetect(LaneNetDetector):
    """Overrides `detect`: a LaneNet batch (`detect_many`) would skip it, so it runs alone."""

    name = "own_detect"

    def detect(self, frame):
        return super().detect(frame)


class Unrelated:
    """A plug-in that subclasses no built-in: it keeps the pooled defaults."""

    name = "unrelated"
