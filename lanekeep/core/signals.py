"""What the car's own sensors say each control period: the one type perception, estimation and
control may read besides camera frames (lanekeep/sensing/vehicle_sensors.py makes them)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class VehicleSignals:
    """One control period's sensor readings, SI units, vehicle frame (x forward, y left)."""

    speed_mps: float  # wheel odometry
    yaw_rate_rps: float  # gyro, + = left
    accel_long_mps2: float
    accel_lat_mps2: float  # + = left
    steer_angle_rad: float  # bicycle-equivalent road-wheel angle, + = left
