"""The `[sensors]` table of a scenario: the error magnitudes of the car's sensors, with the
sources of their defaults (the simulator that applies them is
lanekeep/sensing/vehicle_sensors.py), and its `[sensors.radar]` table: the forward radar's
coverage and accuracy from its data sheet (lanekeep/sensing/radar.py models it)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, setting

G_MPS2 = 9.80665  # standard gravity, to convert µg figures
MAX_SPEED_SCALE_SIGMA = 0.1  # beyond this a drawn scale factor could come near zero
STEERING_RATIO_RANGE = (5.0, 30.0)
KMH = 1.0 / 3.6  # km/h in m/s


@dataclass(frozen=True)
class RadarConfig:
    """The forward radar: Continental ARS 408-21 long-range radar (77 GHz FMCW), from its data
    sheet ("ARS 408-21 Premium Long Range Radar Sensor 77 GHz", Continental Engineering
    Services, technical data; the 250 m reach and ~13 Hz cycle also in Caesar et al., nuScenes,
    CVPR 2020, which fits five of them):
      - far scan: 0.20-250 m over +-9 deg azimuth; near scan: 0.20-70 m over +-45 deg (the
        sheet's third zone, 0.20-20 m at +-60 deg, is left out: nothing the car follows is
        there);
      - distance accuracy +-0.40 m far, +-0.10 m near; azimuth accuracy +-0.1 deg far, near
        +-0.3 deg at 0 deg growing to +-1 deg at +-45 deg; velocity accuracy +-0.1 km/h;
      - cycle ~72 ms (here one reading per control period).
    The sheet's "+-" accuracies are taken as 1-sigma of Gaussian noise: conservative, since a
    tolerance band usually covers more than one sigma. `[sensors] perfect = true` makes the
    radar exact too.
    """

    far_range_m: float = setting(250.0, "Reach of the far scan, straight ahead.",
                                 bounds=(1.0, 1000.0))
    far_half_fov_deg: float = setting(9.0, "Half the far scan's azimuth field of view.",
                                      bounds=(0.5, 60.0))
    near_range_m: float = setting(70.0, "Reach of the near scan (0 = none); a ray in both scans "
                                  "reaches the longer.", bounds=(0.0, 1000.0))
    near_half_fov_deg: float = setting(45.0, "Half the near scan's azimuth field of view.",
                                       bounds=(0.5, 60.0))
    min_range_m: float = setting(0.2, "Nothing nearer is reported.", bounds=(0.0, 10.0))
    range_sigma_far_m: float = setting(0.40, "Range noise beyond near_range_m, 1-sigma.",
                                       allowed=">= 0")
    range_sigma_near_m: float = setting(0.10, "Range noise within near_range_m, 1-sigma.",
                                        allowed=">= 0")
    azimuth_sigma_far_deg: float = setting(0.1, "Azimuth noise of far detections, 1-sigma.",
                                           allowed=">= 0")
    azimuth_sigma_near_deg: float = setting(0.3, "Azimuth noise of near detections straight "
                                            "ahead, 1-sigma.", allowed=">= 0")
    azimuth_sigma_near_edge_deg: float = setting(1.0, "Azimuth noise at the near scan's edge, "
                                                 "1-sigma (linear in between).", allowed=">= 0")
    range_rate_sigma_mps: float = setting(0.1 * KMH, "Range-rate (Doppler) noise, 1-sigma "
                                          "(0.1 km/h).", allowed=">= 0")

    def __post_init__(self):
        check_settings(self)
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if not 0.0 <= value < math.inf:
                raise InvalidValue(f.name, f"must be finite and >= 0, got {value}")


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

    perfect: bool = setting(False, "Read the true values exactly (ablations).",
                            allowed="true, false")
    speed_scale_sigma: float = setting(0.01, "Wheel-speed scale error, 1-sigma, drawn once per "
                                       "episode.", bounds=(0.0, MAX_SPEED_SCALE_SIGMA))
    speed_noise_mps: float = setting(0.03, "Wheel-speed noise per sample, 1-sigma.", allowed=">= 0")
    speed_resolution_mps: float = setting(0.01 / 3.6, "Wheel-speed quantisation step (0.01 km/h).",
                                          allowed=">= 0")
    gyro_noise_density_dps_rthz: float = setting(
        0.014, "Yaw-rate white noise density; + yaw = left.", allowed=">= 0")
    gyro_bias_sigma_dps: float = setting(0.3, "Yaw-rate bias, 1-sigma, drawn per episode.",
                                         allowed=">= 0")
    gyro_bias_walk_dps_rts: float = setting(1e-4, "Random walk of the yaw-rate bias.",
                                            allowed=">= 0")
    accel_noise_density_mps2_rthz: float = setting(
        150e-6 * G_MPS2, "Accelerometer white noise density (150 ug/sqrt(Hz)).", allowed=">= 0")
    steer_noise_deg: float = setting(0.1, "Steering-angle noise at the steering wheel; + = left.",
                                     allowed=">= 0")
    steer_resolution_deg: float = setting(0.1, "Steering-angle quantisation at the steering "
                                          "wheel.", allowed=">= 0")
    steering_ratio: float = setting(15.0, "Steering wheel to road wheel, for the two keys above.",
                                    bounds=STEERING_RATIO_RANGE)
    radar: RadarConfig = setting(factory=RadarConfig, doc="The forward radar (Continental ARS "
                                 "408-21 data sheet; sources: lanekeep/scenario/sensors.py).")

    def __post_init__(self):
        check_settings(self)
        for f in dataclasses.fields(self):
            if f.name in ("perfect", "steering_ratio", "radar"):
                continue
            value = getattr(self, f.name)
            if not 0.0 <= value < math.inf:
                raise InvalidValue(f.name, f"must be finite and >= 0, got {value}")
