"""Sabotaged detectors: the built-in ones with every lane they see moved 5 cm to the left.

A regression that the pass/fail criteria must catch (the shipped scenarios' `[criteria]`,
calibrated by tools/calibrate_criteria.py): perception that is a little wrong, everywhere, all
the time, while the loop still drives and never leaves the lane. Each class wraps a built-in
detector (detectors/registry.py) and adds BIAS_M to what it reports (`biased`), so the
lane's centre line, and the MMAE output that follows it, is off by 5 cm. On 5 s of
case4_half_shade_straight the fused RMSE goes from 0.6 cm to 4.4 cm, the car still within 6 cm
of the centre: the old limit, "twice one measured run" (5 cm there), let it pass; a limit
calibrated on tuning seeds (a prediction bound above the tuning seeds' RMSE) fails it.

Run from the repository root, with it on the import path (`examples/` is no installed package:
a plain `lanekeep` does not see it, `python -m lanekeep.cli` puts the working directory first on
sys.path, and PYTHONPATH=. does the same for the `lanekeep` command):

    S=examples.sabotage
    PYTHONPATH=. lanekeep bench case1_building_shadows \\
        --front-detectors $S:BiasedHough,$S:BiasedSlidingWindow,$S:BiasedLaneNet \\
        --reference-detector $S:BiasedLaneNet   # exit 1 under calibrated criteria

    python -m lanekeep.cli run case4_half_shade_straight --seconds 5 \\
        --front-detectors $S:BiasedHough,$S:BiasedSlidingWindow,$S:BiasedLaneNet \\
        --reference-detector $S:BiasedLaneNet

The reference (LaneNet on the rear camera) is biased the same way: with an honest reference
the MMAE would see the front models disagree with it and could tell; a bias shared by every
sensor cannot be seen from inside the loop, only against the truth, which is what the criteria
score. Each class declares the built-in it wraps (`family`), so its track gets that
detector's own tracker noise (detectors/registry.py builtin_family): the loop is the built-in's
but for the bias. `ShiftedLaneNet` (2 cm, the front model only) and `ShamLaneNet` (no bias:
the same loop as the built-in, to the bit) are the regression gate's checks
(docs/statistics.md#the-regression-gate-against-a-baseline):

    PYTHONPATH=. lanekeep bench --baseline base.json \
        --front-detectors hough,sliding_window,examples.sabotage:ShiftedLaneNet   # exit 1
"""

from __future__ import annotations

import dataclasses

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.registry import make_detector

BIAS_M = 0.05  # + = the lane seen to the left of where it is (vehicle frame: y left)


def biased(estimate: LaneEstimate, bias_m: float = BIAS_M) -> LaneEstimate:
    """`estimate` with its lane moved `bias_m` to the left (+y): both boundaries' constant
    term + bias_m, so the centre line is bias_m further left, and the offset - bias_m (the
    offset is + when the car is left of the centre: the centre lies at y = -offset_m, so the
    car is bias_m further right of a lane moved left). An invalid estimate is left alone.
    The image points stay: they are where the paint was seen, the bias is in what it meant."""
    if not estimate.valid:
        return estimate

    def moved(side: np.ndarray | None) -> np.ndarray | None:
        if side is None:
            return None
        coeffs = np.array(side, dtype=float, copy=True)
        coeffs[0] += bias_m
        return coeffs

    return dataclasses.replace(estimate, offset_m=estimate.offset_m - bias_m,
                               left=moved(estimate.left), right=moved(estimate.right))


class Biased:
    """A built-in detector (by its registry name) whose every estimate goes through `biased`;
    built like any plug-in, `Class(camera, config=None, distortion=None)`, on either camera."""

    inner_name = ""  # the built-in detector it wraps
    bias_m = BIAS_M

    def __init__(self, camera, config=None, distortion=None) -> None:
        self.wrap(make_detector(self.inner_name, camera, config, distortion))

    def wrap(self, inner) -> None:
        self.inner = inner
        self.name = f"biased_{inner.name}"
        self.x_ref = inner.x_ref

    @property
    def window(self):
        return self.inner.window

    def reset(self) -> None:
        self.inner.reset()

    def detect(self, frame: np.ndarray) -> LaneEstimate:
        return biased(self.inner.detect(frame), self.bias_m)


class BiasedHough(Biased):
    inner_name = family = "hough"


class BiasedSlidingWindow(Biased):
    inner_name = family = "sliding_window"


class BiasedLaneNet(Biased):
    """LaneNet, biased; takes `weights=` as LaneNet does, so `--weights` reaches it."""

    inner_name = family = "lanenet"

    def __init__(self, camera, config=None, distortion=None, weights: str | None = None
                 ) -> None:
        self.wrap(make_detector(self.inner_name, camera, config, distortion, weights=weights))


class ShiftedLaneNet(BiasedLaneNet):
    """LaneNet's boundaries 2 cm to the left: a small regression of one front model."""

    bias_m = 0.02


class ShamLaneNet(BiasedLaneNet):
    """LaneNet through the wrapper with no bias: the built-in's loop, to the bit."""

    bias_m = 0.0
