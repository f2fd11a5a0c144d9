"""What a detection's own confidence says about its noise, measured against the truth.

A classical detector's confidence (the share of its ground window its boundaries cover,
detectors/boundaries.py `support_confidence`) rises with its chance of being right, but the
trackers gave every detection of a detector the same R. Measured in the closed loop on the
tuning scenarios (`python -m lanekeep.tuning.detector_noise`, which prints these bands), the
robust core of hough's and sliding_window's coefficient errors is several times wider in their
lowest-confidence band than in their highest, so each band gets its own multiple of the
detector's R: the tracker's gate, its gain and the MMAE's residual density (eq. 8's C P C')
then see the spread such a detection has, not the detector's average.
"""

from __future__ import annotations

import bisect
import itertools
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ConfidenceBands:
    """A detector's confidence cut into bands at `edges` (ascending; len(edges) + 1 bands),
    each with the factor its detections' R is its detector's R times."""

    edges: tuple[float, ...]
    scales: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.scales) != len(self.edges) + 1:
            raise ValueError(f"{len(self.edges)} edges need {len(self.edges) + 1} scales, "
                             f"got {len(self.scales)}")
        if any(b <= a for a, b in itertools.pairwise(self.edges)):
            raise ValueError(f"edges must ascend, got {list(self.edges)}")
        if not all(np.isfinite(s) and s > 0.0 for s in self.scales):
            raise ValueError(f"scales must be positive numbers, got {list(self.scales)}")

    def band(self, confidence: float) -> int:
        """The band a confidence falls in (a value on an edge belongs to the band above)."""
        return bisect.bisect_right(self.edges, confidence)

    def scale(self, confidence: float) -> float:
        """The factor of R for a detection with this confidence."""
        return self.scales[self.band(confidence)]
