"""Body roll compensation: the cameras' lanes corrected with the car's lateral accelerometer.

In a curve the body rolls (0.71 deg per m/s^2 of lateral acceleration on our car) and both
cameras roll with it. Every detector projects the image onto a ground plane seen from an
unrolled camera, so each lane comes out shifted sideways, the same way for both cameras: on
four tuning curves LaneNet's offset error grew 4.2 cm per degree of roll and the rear
reference's 4.4 cm; without that part their offset RMS falls from 4.27 to 1.17 cm and from
4.34 to 1.66 (tools/measure_roll_coupling.py). Shared by the reference and the front models,
the error also made the MMAE favour the front model that erred most like the reference. A car
knows its roll gradient (a suspension constant) and measures its lateral acceleration, so the
shift is removed as

    roll = roll_gradient * accel_lat,    offset error = lever(camera) * roll

with each camera's lever (offset error per radian of roll) measured once. The accelerometer is
low-passed first (`filter_s`) and clipped (`accel_limit_mps2`): the body rolls through its
suspension, not at once, and the signal spikes on kerbs and contacts (+-8.5 m/s^2 within three
steps at the end of clear_straight, which unfiltered moved every lane by 30 cm). Only sensor
signals and constants: no simulator state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from lanekeep.detectors.base import LaneEstimate


@dataclass(frozen=True)
class RollCompensation:
    """The vehicle's roll gradient and each camera's lever; a zero gradient turns it off."""

    roll_gradient_deg_per_mps2: float = 0.0
    lever_m: tuple[tuple[str, float], ...] = ()  # (camera, offset error per radian of roll)
    filter_s: float = 0.3
    accel_limit_mps2: float = 6.0  # beyond what the tyres hold (about 0.6 g)

    def offset_error_m(self, camera: str, accel_lat_mps2: float) -> float:
        """The error roll adds to `camera`'s offsets at this (filtered) lateral acceleration
        (+ = left)."""
        lever = dict(self.lever_m).get(camera, 0.0)
        roll_rad = math.radians(self.roll_gradient_deg_per_mps2) * accel_lat_mps2
        return lever * roll_rad if math.isfinite(roll_rad) else 0.0


class RollFilter:
    """The lateral acceleration the body's roll follows: the accelerometer clipped and
    low-passed over `filter_s`, one update per control step."""

    def __init__(self, compensation: RollCompensation, dt_s: float) -> None:
        self.compensation = compensation
        self.blend = 1.0 - math.exp(-dt_s / compensation.filter_s)
        self.accel_lat_mps2 = 0.0

    def update(self, accel_lat_mps2: float) -> None:
        if not math.isfinite(accel_lat_mps2):
            return
        limit = self.compensation.accel_limit_mps2
        clipped = min(max(accel_lat_mps2, -limit), limit)
        self.accel_lat_mps2 += self.blend * (clipped - self.accel_lat_mps2)

    def offset_error_m(self, camera: str) -> float:
        return self.compensation.offset_error_m(camera, self.accel_lat_mps2)


def corrected(estimate: LaneEstimate, offset_error_m: float) -> LaneEstimate:
    """`estimate` with an offset error taken out: the offset less it, the lane moved by it
    (offset = -centre(x), so an offset too large by e is a lane too far right by e)."""
    if not estimate.valid or offset_error_m == 0.0:
        return estimate
    move = np.array([offset_error_m, 0.0, 0.0])
    return replace(
        estimate,
        offset_m=estimate.offset_m - offset_error_m,
        left=None if estimate.left is None else np.asarray(estimate.left, dtype=float) + move,
        right=None if estimate.right is None else np.asarray(estimate.right, dtype=float) + move,
    )
