"""Dead reckoning from the car's own sensors: what the estimator knows of the car's motion.

A lane-keeping ECU has wheel-speed odometry and an IMU yaw rate, not the simulator's state
(lanekeep/sensing/vehicle_sensors.py makes those signals). From them this module integrates a pose
in an
odometry frame (its origin where the episode started; only relative poses matter to the
alignment of estimators/alignment.py) and estimates the sideslip, which no production sensor
measures: in a kinematic bicycle the rear axle does not slide sideways, so a point
`reference_ahead_of_rear_axle_m` ahead of it moves sideways at yaw_rate x that distance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class EgoMotion:
    """What the estimator knows of the car's motion at this step.

    `speed_mps`, `yaw_rate_rps` and `lateral_speed_mps` predict the tracks over `dt_s`;
    `pose` (x, y, yaw in the odometry frame, dead-reckoned) carries the models' past lane
    points to where the rear reference looks now; `travelled_m` is the odometer.
    """

    dt_s: float
    speed_mps: float
    yaw_rate_rps: float
    lateral_speed_mps: float
    pose: tuple[float, float, float]
    travelled_m: float


class DeadReckoning:
    """Integrates wheel speed and yaw rate into an odometry pose, one control period a call."""

    def __init__(self, dt_s: float, reference_ahead_of_rear_axle_m: float) -> None:
        if not dt_s > 0:
            raise ValueError(f"dt_s must be > 0, got {dt_s}")
        self.dt_s = dt_s
        self.lever_m = reference_ahead_of_rear_axle_m
        self.reset()

    def reset(self) -> None:
        self.pose = (0.0, 0.0, 0.0)
        self.travelled_m = 0.0
        self._previous: tuple[float, float] | None = None

    def lateral_speed_mps(self, yaw_rate_rps: float) -> float:
        """Sideways speed of the reference point (+ = left) of a car whose rear axle rolls."""
        return yaw_rate_rps * self.lever_m

    def update(self, speed_mps: float, yaw_rate_rps: float) -> EgoMotion:
        """Advance by one period with the signals sampled at its end (trapezoidal in speed and
        yaw rate between this sample and the last); the first call only sets the origin."""
        if not (math.isfinite(speed_mps) and math.isfinite(yaw_rate_rps)):
            speed_mps, yaw_rate_rps = (self._previous or (0.0, 0.0))
        if self._previous is not None:
            v0, r0 = self._previous
            v, r = 0.5 * (v0 + speed_mps), 0.5 * (r0 + yaw_rate_rps)
            x, y, yaw = self.pose
            dt = self.dt_s
            heading = yaw + 0.5 * r * dt  # midpoint heading over the period
            forward, sideways = v * dt, self.lateral_speed_mps(r) * dt
            c, s = math.cos(heading), math.sin(heading)
            self.pose = (x + c * forward - s * sideways, y + s * forward + c * sideways,
                         yaw + r * dt)
            self.travelled_m += abs(forward)
        self._previous = (speed_mps, yaw_rate_rps)
        return EgoMotion(self.dt_s, speed_mps, yaw_rate_rps,
                         self.lateral_speed_mps(yaw_rate_rps), self.pose, self.travelled_m)
