"""The Stanley lateral controller, on the estimated lane only: a second standard steering law
behind the same `Controller` interface as the PID (lanekeep/control/registry.py).

Textbook form (Hoffmann, Tomlin, Montemerlo, Thrun, "Autonomous automobile trajectory
tracking for off-road driving", ACC 2007, eq. 2; Snider, "Automatic steering methods for
autonomous automobile path tracking", CMU-RI-TR-09-08, 2009, sec. 2.3):

    delta = psi_e + atan(k e / (k_soft + v))

with psi_e the path's heading relative to the car's and e the cross-track error, both at the
centre of the front axle, v the speed, saturated at the steering lock. On a kinematic bicycle
the cross-track error then decays as e' = -k e (for small angles) whatever the speed, and on
a circle the heading term alone holds the curve (the front wheel points along the path).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from lanekeep.control.base import ControlContext
from lanekeep.control.pid import SpeedController
from lanekeep.core.signals import VehicleSignals
from lanekeep.geometry.lane_poly import LanePoly

if TYPE_CHECKING:
    from lanekeep.estimators.lane_estimator import EstimatorOutput


@dataclass(frozen=True)
class StanleyGains:
    """The law's two constants (Hoffmann et al. use k = 2.5 on their car)."""

    k_per_s: float = 2.5  # cross-track gain: e decays with time constant 1/k
    softening_mps: float = 1.0  # keeps the cross-track term finite at low speed

    def __post_init__(self) -> None:
        if not self.k_per_s > 0 or not self.softening_mps > 0:
            raise ValueError(f"Stanley gains must be > 0, got {self}")


class StanleyController:
    """Stanley steering on the estimator's lane centre, the speed PI for throttle (or the
    adaptive cruise when the context has one, lanekeep/control/acc.py).

    The lane is a polynomial y(x) = c0 + c1 x + c2 x^2 in the vehicle frame (origin under the
    middle of the wheelbase, y left); the front axle is at x = L / 2, where the tracker's
    lane is extrapolated a little behind the cameras' nearest ground (~4 m).
    """

    def __init__(self, context: ControlContext, gains: StanleyGains | None = None) -> None:
        self.context = context
        self.gains = gains or StanleyGains()
        self.speed = SpeedController(context.target_speed_mps, context.dt_s)
        self.acc = context.adaptive_cruise()

    def reset(self) -> None:
        self.speed.reset()
        if self.acc is not None:
            self.acc.reset()

    def steering_angle(self, centre, speed_mps: float) -> float:
        """delta (rad, + = left) for lane centre coefficients `centre` at speed `speed_mps`."""
        x_front = self.context.wheelbase_m / 2.0
        lane = LanePoly.of(centre)
        heading_error = lane.heading_rad(x_front)  # path heading - car heading
        # perpendicular distance from the front axle to the centre line, + = line to the left
        cross_track = float(lane.y(x_front)) * math.cos(heading_error)
        v = max(speed_mps, 0.0) if math.isfinite(speed_mps) else 0.0
        g = self.gains
        return heading_error + math.atan(g.k_per_s * cross_track / (g.softening_mps + v))

    def control(self, estimate: EstimatorOutput, signals: VehicleSignals
                ) -> tuple[float, float]:
        throttle = self.speed(signals.speed_mps) if self.acc is None else self.acc(signals)
        if estimate.centre is None:  # no lane: wheel straight, as the PID does
            return 0.0, throttle
        delta = self.steering_angle(estimate.centre, signals.speed_mps)
        steer = delta / self.context.max_steer_rad
        return min(max(steer, -1.0), 1.0), throttle
