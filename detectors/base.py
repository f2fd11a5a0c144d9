"""What every lane detector returns, and the protocol it implements.

A detector maps one camera frame to a `LaneEstimate` in the vehicle ground frame (x forward,
y left, metres, origin on the ground under the middle of the wheelbase). Boundaries are
2nd-order polynomials y(x) = c0 + c1 x + c2 x^2, coefficients low order first, read through
`lanekeep.geometry.lane_poly.LanePoly` (`LanePoly.of(estimate.left).y(x)`). A detector that
finds nothing returns `LaneEstimate.invalid(...)`: never NaN, never an exception for a frame
that is merely hard (black, sky, noise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from lanekeep.detectors.config import GroundWindow


@dataclass(frozen=True)
class LaneEstimate:
    """One detector's view of the ego lane in one frame.

    Attributes:
        valid: False when the detector found no usable lane; then the numbers mean nothing.
        offset_m: signed lateral offset of the car from the lane centre at look-ahead `x_m`,
            + = car left of centre (so the centre line lies at y = -offset_m there).
        x_m: look-ahead (vehicle frame x, metres; negative = behind, for a rear camera).
        left, right: boundary polynomials [c0, c1, c2] (None when that side was not found).
        confidence: 0..1, the detector's own belief (e.g. share of windows with paint).
        image_points: pixel points (N, 2) per side ("left"/"right") the fit came from.
        reason: why the estimate is invalid, for logs.
        others: boundary polynomials of the other lanes' lines the detector found beside the
            ego lane (neighbouring lanes), for evaluations that count every lane; the ego
            lane's own are `left` and `right`. Empty when it reports the ego lane only.
    """

    valid: bool
    offset_m: float = 0.0
    x_m: float = 0.0
    left: np.ndarray | None = None
    right: np.ndarray | None = None
    confidence: float = 0.0
    image_points: dict[str, np.ndarray] = field(default_factory=dict)
    reason: str = ""
    others: tuple[np.ndarray, ...] = ()

    def __post_init__(self) -> None:
        if self.valid:
            numbers = [self.offset_m, self.x_m, self.confidence]
            for side in (self.left, self.right, *self.others):
                if side is not None:
                    numbers.extend(np.asarray(side, dtype=float).ravel().tolist())
            if not all(math.isfinite(v) for v in numbers):
                raise ValueError("a valid LaneEstimate must not hold NaN or inf")

    @classmethod
    def invalid(cls, reason: str, x_m: float = 0.0) -> LaneEstimate:
        return cls(valid=False, x_m=x_m, reason=reason)

    @property
    def center(self) -> np.ndarray | None:
        """Centre-line polynomial: the mean of both boundaries, or None if one is missing."""
        if self.left is None or self.right is None:
            return None
        return (np.asarray(self.left) + np.asarray(self.right)) / 2.0


@runtime_checkable
class Detector(Protocol):
    """Maps an RGB frame (H, W, 3) uint8 to a LaneEstimate; may keep state between frames.

    Detectors are made by `detectors.registry.make_detector(name, camera, config, distortion)`,
    which calls the detector's factory as `factory(camera, config=..., distortion=...)`.

    A detector that carries what it saw from frame to frame may also define
    `move(speed_mps, yaw_rate_rps, dt_s, lateral_speed_mps)`: the driver calls it before each
    frame with the period's motion from the car's own sensors (wheel speed, yaw rate and the
    odometry's sideslip estimate; never the simulator's state).
    """

    name: str
    x_ref: float  # vehicle-frame x (m) of the offset it reports (negative behind the car)

    @property
    def window(self) -> GroundWindow:
        """The patch of ground it looks at (its lanes are meant for this x range)."""
        ...

    def detect(self, frame: np.ndarray) -> LaneEstimate: ...

    def reset(self) -> None:
        """Forget state carried between frames (a new episode)."""
        ...
