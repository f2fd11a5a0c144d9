"""The car's spec sheet: the dimensions its kinematics, its controller and its estimator are
built from (a datasheet, not its state). It lives here, below the world that builds the car
from it and the driver that is built from it, so that neither reads the other."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class CarGeometry:
    """Dimensions that the kinematics need; they must match mjcf/car.xml."""

    wheelbase_m: float = 2.8
    track_m: float = 1.62
    wheel_radius_m: float = 0.36
    max_steer_rad: float = math.radians(35.0)  # bicycle-equivalent road-wheel angle at |steer| = 1
    length_m: float = 4.7
    width_m: float = 1.9
