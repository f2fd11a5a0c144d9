"""The truth of one control step, computed once (by the episode's scoring) and carried in its
StepResult, so that the metrics, the recorder, the plots and the tools all read the same
numbers instead of solving the road geometry again each.

Truth comes from the road and the car's true pose (lanekeep/scoring/truth.py), never from
images, and reaches nothing but scoring and recording.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.scoring.truth import frenet, lane_centre_at, lane_centre_fit, lane_offsets

Pose = tuple[float, float, float]


def lookahead_key(x_m: float) -> float:
    """Look-aheads are keyed to the millimetre: an estimate's x and the same x computed
    elsewhere meet in one entry."""
    return round(float(x_m), 3)


@dataclass(frozen=True)
class StepTruth:
    """What was true when a step's frames were taken (at `sensed_pose`) and after its period."""

    offsets_m: Mapping[float, float]  # look-ahead (m, `lookahead_key`) -> the car's true offset
    centre_at_ade_m: np.ndarray  # exact centre y at the ADE / FDE points (metrics.ADE_POINTS_M)
    car_offset_m: float  # the car's true offset at its reference point after the period
    # `lane_centre_fit` of the sensed pose, called when `centre` is first read
    centre_fit: Callable[[], tuple[np.ndarray, float]] = field(repr=False, compare=False)

    @functools.cached_property
    def centre(self) -> np.ndarray:
        """The true lane centre (2nd order, vehicle frame of the sensed pose).

        Fitted when first read, then kept: no score reads it (ADE/FDE use `centre_at_ade_m`),
        only what draws or inspects a step, so a step that nothing reads it from does not fit
        61 exact points. The same numbers as fitting it at once (the road and the pose are
        fixed)."""
        return self.centre_fit()[0]

    def offset_at(self, x_m: float) -> float:
        """The true offset of the car from the lane centre at look-ahead x (+ = car left)."""
        return self.offsets_m[lookahead_key(x_m)]


def step_truth(road: Road, lane: int, sensed_pose: Pose, pose_after: Pose,
               scored_lookaheads_m: Iterable[float], ade_points_m: np.ndarray,
               drawn_lookaheads_m: Iterable[float] = ()) -> StepTruth:
    """The step's truth: offsets at every look-ahead an estimate is scored at (one Newton
    solve for all of them) and at those the recorder draws besides (a second solve, so that
    what is scored does not depend on what is drawn), the centre line (when read), and the
    car's offset after the period.
    """
    s_car = float(frenet(road, sensed_pose[:2])[0])  # the car's Frenet s (as lane_centre_fit's)
    centre_at_ade = lane_centre_at(road, *sensed_pose, lane, ade_points_m, s_car=s_car)
    scored = sorted({lookahead_key(x) for x in scored_lookaheads_m})
    offsets = dict(zip(scored, lane_offsets(road, *sensed_pose, lane, scored, s_car=s_car),
                       strict=True))
    drawn = sorted({lookahead_key(x) for x in drawn_lookaheads_m} - set(scored))
    if drawn:
        offsets.update(zip(drawn, lane_offsets(road, *sensed_pose, lane, drawn, s_car=s_car),
                           strict=True))
    car_offset = float(lane_offsets(road, *pose_after, lane, [0.0])[0])
    return StepTruth({x: float(v) for x, v in offsets.items()}, centre_at_ade, car_offset,
                     functools.partial(lane_centre_fit, road, *sensed_pose, lane))
