"""Simulated vehicle sensors: what a production car's bus gives its lane-keeping ECU.

Sampled once per control period, seeded from the episode's numpy Generator:
  - wheel-speed odometry: forward speed times a per-episode scale error (the real tyre rolling
    radius is not the nominal one the ECU assumes), plus white noise, quantised;
  - gyro yaw rate: white noise plus a bias that starts at a drawn offset and random-walks;
  - longitudinal and lateral acceleration (body frame, kinematic: gravity removed, as if the
    ground were flat and the ECU compensated roll and pitch) with white noise;
  - steering angle, reported as the bicycle-equivalent road-wheel angle, with noise and the
    resolution of a steering-angle sensor (both given at the steering wheel).
Not modelled: latency and message rates, tyre slip in the odometry, accelerometer bias, road
vibration, gravity components from body roll or road slope.

Noise densities (per sqrt(Hz)) are continuous white-noise intensities: one sample, the average
over the sample period dt, has sigma = density * sqrt(1/dt) (the Allan-deviation convention,
sigma(tau) = N / sqrt(tau), as in Kalibr's IMU noise model). A random walk with density W
(per sqrt(s)) moves by W * sqrt(dt) (1-sigma) per sample.

These sensors are the only thing besides scoring and recording that reads the car's true
state; every such read is in `VehicleSensors.sample`.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from lanekeep.core.signals import VehicleSignals
from lanekeep.scenario.sensors import SensorsConfig


class CarState(Protocol):
    """The true-state reads the sensors make (lanekeep.world.vehicle.Car provides them)."""

    def speed_mps(self) -> float: ...
    def yaw_rate_rps(self) -> float: ...
    def acceleration_body(self) -> np.ndarray: ...
    def steer_angle_rad(self) -> float: ...


def _quantise(value: float, step: float) -> float:
    if step <= 0.0 or not math.isfinite(value):  # a broken state reads as broken, not a crash
        return value
    return step * math.floor(value / step + 0.5)


class VehicleSensors:
    """The car's sensors for one episode; call `sample` once per control period of `dt_s`.

    Random numbers come only from `rng`: with imperfect sensors, two draws here (speed scale,
    initial gyro bias) and six per `sample`, always all six in the same order whatever the
    magnitudes (a zero magnitude still consumes its draw), so a seed gives one sequence. With
    `perfect` nothing is drawn.
    """

    def __init__(self, config: SensorsConfig, dt_s: float, rng: np.random.Generator) -> None:
        if not 0.0 < dt_s < math.inf:
            raise ValueError(f"dt_s must be > 0, got {dt_s}")
        self.config = config
        self.dt_s = dt_s
        self._rng = rng
        # Per-sample standard deviations at this sample period (see the module docstring).
        self.gyro_sigma_rps = math.radians(config.gyro_noise_density_dps_rthz) / math.sqrt(dt_s)
        self.gyro_walk_step_rps = math.radians(config.gyro_bias_walk_dps_rts) * math.sqrt(dt_s)
        self.accel_sigma_mps2 = config.accel_noise_density_mps2_rthz / math.sqrt(dt_s)
        ratio = config.steering_ratio  # steering-wheel figures -> road-wheel angle
        self.steer_sigma_rad = math.radians(config.steer_noise_deg) / ratio
        self.steer_resolution_rad = math.radians(config.steer_resolution_deg) / ratio
        # Per-episode errors: they belong to this car (its tyres, its gyro), not to a sample.
        if config.perfect:
            self.speed_scale, self.initial_gyro_bias_rps = 1.0, 0.0
        else:
            scale_draw, bias_draw = rng.standard_normal(2)
            self.speed_scale = 1.0 + config.speed_scale_sigma * float(scale_draw)
            self.initial_gyro_bias_rps = math.radians(config.gyro_bias_sigma_dps) * float(bias_draw)
        self.gyro_bias_rps = self.initial_gyro_bias_rps

    def reset(self) -> None:
        """Back to the start of the episode: the gyro bias returns to its drawn initial offset.

        Nothing is re-drawn (scale factor and initial bias stay) and the Generator is not
        rewound, so the noise after a reset differs from the first run's.
        """
        self.gyro_bias_rps = self.initial_gyro_bias_rps

    def sample(self, car: CarState) -> VehicleSignals:
        """Read the car's true state and return what its sensors report."""
        speed = car.speed_mps()
        yaw_rate = car.yaw_rate_rps()
        # Acceleration from MuJoCo's qacc rather than by differencing the velocity between
        # samples: it is stateless, so it is right from the first sample after a reset and
        # whatever the sampling cadence. It is the acceleration of one physics step (5 ms
        # here), not the period's mean (the difference quotient would need the mid-period
        # heading to split into long/lat correctly); in clear_curve's steady turn the two
        # agree within ~0.02 m/s^2.
        accel = car.acceleration_body()
        steer = car.steer_angle_rad()
        if self.config.perfect:
            return VehicleSignals(speed, yaw_rate, float(accel[0]), float(accel[1]), steer)
        c = self.config
        n_speed, n_gyro, n_walk, n_long, n_lat, n_steer = self._rng.standard_normal(6)
        bias = self.gyro_bias_rps
        self.gyro_bias_rps = bias + self.gyro_walk_step_rps * float(n_walk)
        return VehicleSignals(
            speed_mps=_quantise(self.speed_scale * speed + c.speed_noise_mps * float(n_speed),
                                c.speed_resolution_mps),
            yaw_rate_rps=yaw_rate + bias + self.gyro_sigma_rps * float(n_gyro),
            accel_long_mps2=float(accel[0]) + self.accel_sigma_mps2 * float(n_long),
            accel_lat_mps2=float(accel[1]) + self.accel_sigma_mps2 * float(n_lat),
            steer_angle_rad=_quantise(steer + self.steer_sigma_rad * float(n_steer),
                                      self.steer_resolution_rad),
        )
