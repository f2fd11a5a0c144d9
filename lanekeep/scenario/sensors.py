"""The `[sensors]` table of a scenario: the error magnitudes of the car's sensors, with the
sources of their defaults (the simulator that applies them is
lanekeep/sensing/vehicle_sensors.py)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

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
