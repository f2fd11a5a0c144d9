"""What the car's own sensors say each control period: the one type perception, estimation and
control may read besides camera frames (lanekeep/sensing/vehicle_sensors.py and
lanekeep/sensing/radar.py make them)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RadarDetection:
    """One object the forward radar reports, in the radar's own frame (its axis = the car's x):
    what a real radar's object list gives, never which body it is."""

    range_m: float  # from the radar to the object's nearest reflecting point
    azimuth_rad: float  # + = left of the radar's axis
    range_rate_mps: float  # d(range)/dt (Doppler): + = opening, - = closing


@dataclass(frozen=True)
class RadarReading:
    """One radar cycle: its detections, nearest first. `mount_x_m` is where the radar sits ahead
    of the vehicle reference point (the car's spec sheet, not a measurement), so that the car
    can put a detection on its own predicted path."""

    detections: tuple[RadarDetection, ...]
    mount_x_m: float


@dataclass(frozen=True)
class VehicleSignals:
    """One control period's sensor readings, SI units, vehicle frame (x forward, y left)."""

    speed_mps: float  # wheel odometry
    yaw_rate_rps: float  # gyro, + = left
    accel_long_mps2: float
    accel_lat_mps2: float  # + = left
    steer_angle_rad: float  # bicycle-equivalent road-wheel angle, + = left
    # The forward radar's cycle; None when the car has none or it has not reported yet.
    radar: RadarReading | None = None
