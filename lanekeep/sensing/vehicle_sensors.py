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

import dataclasses
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from lanekeep.core.config_io import InvalidValue

G_MPS2 = 9.80665  # standard gravity, to convert µg figures
MAX_SPEED_SCALE_SIGMA = 0.1  # beyond this a drawn scale factor could come near zero
STEERING_RATIO_RANGE = (5.0, 30.0)


@dataclass(frozen=True)
class SensorsConfig:
    """Error magnitudes of the car's sensors; `perfect = true` reads the true values exactly.

    Units in names: dps = deg/s, rthz = sqrt(Hz), rts = sqrt(s). Defaults and their sources:
      - speed_scale_sigma = 0.01 (1-sigma fraction, drawn once per episode). Order of magnitude,
        not a datasheet figure: a ~0.33 m tyre's rolling radius shrinks by ~2 % from new
        tread (~8 mm) to the 1.6 mm legal minimum (EU Directive 89/459/EEC), and inflation
        pressure and load move it by another ~0.5-1 %.
      - speed_noise_mps = 0.03 (per-sample sigma at the control rate, not a density: the ABS
        ECU already averages tooth periods). Order of magnitude: tone-wheel pitch errors of a
        few tenths of a per cent of road speed.
      - speed_resolution_mps = 0.01 km/h: the LSB of the wheel speeds on the CAN bus, e.g.
        Honda's WHEEL_SPEEDS message (commaai/opendbc, _honda_common.dbc: 0.01 kph per bit).
      - gyro_noise_density_dps_rthz = 0.014 °/s/√Hz: Bosch BMI088 (and BMG160) datasheet,
        gyroscope output noise density, typical; 0.044 °/s per sample at 10 Hz.
      - gyro_bias_sigma_dps = 0.3 °/s: order of magnitude, not a datasheet figure. A raw MEMS
        gyro's zero-rate offset is ±1 °/s typical (BMI088, BMG160 datasheets); a car's
        yaw-rate signal is offset-compensated at standstill, leaving a few tenths of °/s.
      - gyro_bias_walk_dps_rts = 1e-4 °/s/√s (≈ 22 °/h/√h): order of magnitude. Datasheets
        give only bias stability (BMG160 1.6 °/h typical, BMI088 ~2 °/h); the rate random
        walk past that floor of a MEMS gyro's Allan deviation is tens of °/h/√h. Over a 30 s
        episode it moves the bias by ~5e-4 °/s, so the drawn offset dominates.
      - accel_noise_density_mps2_rthz = 150 µg/√Hz: Bosch BMI055 / BMI160 datasheets,
        accelerometer noise density, typical; the BMI088's is of the same order. 4.7e-3 m/s^2
        per sample at 10 Hz.
      - steer_noise_deg = 0.1° and steer_resolution_deg = 0.1°, at the steering wheel: the
        steering-angle LSB on the CAN bus, e.g. Honda's STEERING_SENSORS message (opendbc:
        0.1 deg per bit), the usual resolution of steering-angle sensors; noise of one LSB is
        an order-of-magnitude choice.
      - steering_ratio = 15: order of magnitude of passenger cars' overall steering ratio
        (about 14-17:1); only used to express the steering-wheel figures at the road wheels.
    """

    perfect: bool = False
    speed_scale_sigma: float = 0.01
    speed_noise_mps: float = 0.03
    speed_resolution_mps: float = 0.01 / 3.6
    gyro_noise_density_dps_rthz: float = 0.014
    gyro_bias_sigma_dps: float = 0.3
    gyro_bias_walk_dps_rts: float = 1e-4
    accel_noise_density_mps2_rthz: float = 150e-6 * G_MPS2
    steer_noise_deg: float = 0.1
    steer_resolution_deg: float = 0.1
    steering_ratio: float = 15.0

    def __post_init__(self):
        for f in dataclasses.fields(self):
            if f.name in ("perfect", "steering_ratio"):
                continue
            value = getattr(self, f.name)
            if not 0.0 <= value < math.inf:
                raise InvalidValue(f.name, f"must be finite and >= 0, got {value}")
        if not self.speed_scale_sigma <= MAX_SPEED_SCALE_SIGMA:
            raise InvalidValue("speed_scale_sigma",
                               f"must be <= {MAX_SPEED_SCALE_SIGMA}, got {self.speed_scale_sigma}")
        low, high = STEERING_RATIO_RANGE
        if not low <= self.steering_ratio <= high:
            raise InvalidValue("steering_ratio",
                               f"must be in [{low}, {high}], got {self.steering_ratio}")


@dataclass(frozen=True)
class VehicleSignals:
    """One control period's sensor readings, SI units, vehicle frame (x forward, y left)."""

    speed_mps: float  # wheel odometry
    yaw_rate_rps: float  # gyro, + = left
    accel_long_mps2: float
    accel_lat_mps2: float  # + = left
    steer_angle_rad: float  # bicycle-equivalent road-wheel angle, + = left


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
