"""The `[camera]` table of a scenario: both onboard cameras' image size, the renderer's effort,
the camera model (noise, exposure, optics, JPEG) and the mounting (preset, pose, lens distortion).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, setting

CAMERA_PRESETS = ("paper", "dashcam")  # lanekeep/world/camera_mount.py: the front camera's pose


@dataclass(frozen=True)
class CameraConfig:
    """Onboard camera image size and what the renderer spends on it.

    `antialias_samples` is MuJoCo's offscreen multisampling (`offsamples`). On a CPU (Mesa
    llvmpipe) 4 samples cost 2.6x a plain render of both cameras (94 vs 36 ms, `lanekeep
    perf`) and bought the detectors nothing measurable, since they shrink the frame with
    area averaging before they look at it (2x2 pixels per working pixel): the bench table in
    docs/experiments.md's performance section shows both. Raise it for frames meant for people.
    """

    width: int = setting(1280, "Image width of both onboard cameras.", unit="px", allowed="> 0")
    height: int = setting(720, "Image height of both onboard cameras.", unit="px", allowed="> 0")
    shadows: bool = setting(False, "MuJoCo's shadow maps for the lights (costly on a CPU).",
                            allowed="true, false")
    antialias_samples: int = setting(0, "MuJoCo's offscreen multisampling.", allowed="0, 2, 4, 8")
    # The camera model (lanekeep/sensing/camera_sensor.py), on by default as on a real camera.
    read_noise_dn: float = setting(1.0, "Sensor read noise before the gain.", bounds=(0.0, 20.0))
    auto_exposure: bool = setting(True, "Causal gain from the past frames' metering.",
                                  allowed="true, false")
    exposure_time_constant_s: float = setting(0.3, "How fast the exposure follows the scene.",
                                              bounds=(0.01, 10.0))
    vignetting: float = setting(0.2, "Corner darkening of the lens.", bounds=(0.0, 0.6))
    # Lens + demosaic point spread: Gaussian sigma in pixels of the frame; 0.8 makes a hard
    # edge rise over ~2-3 px as on real photos instead of a 1 px stair step. 0 = off, .. 3.
    lens_blur_px: float = setting(0.8, "Lens + demosaic point spread (Gaussian sigma, pixels); 0 "
                                  "= off.", bounds=(0.0, 3.0))
    bloom: float = setting(0.4, "Glare around near-saturated areas (sky, lamps); 0 = off.",
                           bounds=(0.0, 1.0))
    # JPEG compression of every frame, 0 = off, else 10..100. Off by default: an ADAS camera
    # hands perception uncompressed frames (JPEG is how dashcams and datasets store them; the
    # LaneNet dataset draws 30..95), and at 1280x720 it would cost ~4-5 ms a frame per camera
    # here (`lanekeep perf`, 2026-11-27), most of the richer world's step budget.
    jpeg_quality: int = setting(0, "JPEG compression of every frame; 0 = off.",
                                allowed="0 or 10..100")
    show_hood: bool = setting(True, "The car's hood at the bottom of the front image.",
                              allowed="true, false")
    # The mounting of both onboard cameras, changed from the car's own (mjcf/car.xml: 1.5 m
    # high, front pitched 10 deg up with a 120 deg horizontal field of view): other cameras, as
    # real rigs and the datasets (lanekeep/evaluation/dataset.py) have. Applied by
    # lanekeep/world/camera_mount.py
    # to the compiled model, so the detectors' camera models (read from it) stay exact.
    mount_height_m: float = setting(0.0, "Both cameras' height above the ground; 0 = the preset's "
                                    "(1.5 m; the dashcam front's 1.4 m).", allowed="0 or 0.5..4")
    pitch_offset_deg: float = setting(0.0, "Added to each camera's pitch; + = looking up.",
                                      bounds=(-30.0, 30.0))
    roll_deg: float = setting(0.0, "About each camera's optical axis; + = image turns "
                              "anticlockwise.", bounds=(-20.0, 20.0))
    yaw_offset_deg: float = setting(0.0, "About the car's vertical axis; + = towards the car's "
                                    "left.", bounds=(-30.0, 30.0))
    fov_scale: float = setting(1.0, "Scales tan(field of view / 2); < 1 = a longer lens (the "
                               "car's: 120 deg horizontal).", bounds=(0.3, 1.5))
    preset: str = setting("paper", "The front camera's pose before the mounting keys: \"paper\" = "
                          "the car's (1.5 m, 10 deg up, 120 deg horizontal, horizon at row 425 of "
                          "720); \"dashcam\" = a real dashcam's (1.4 m, 3.1 deg down, 60 deg "
                          "horizontal, horizon at row 300 of 720). The rear camera keeps the "
                          "car's pose.", choices=CAMERA_PRESETS)
    # lanekeep/geometry/lens.py; the detectors are given the same coefficients, as from a
    # camera file.
    distortion: tuple[float, float, float, float, float] = setting(
        (0.0, 0.0, 0.0, 0.0, 0.0), "OpenCV lens distortion k1, k2, p1, p2, k3 of the front "
        "camera; every image is bent by it and the detectors are given it. All zero = a pinhole; "
        "k1 < 0 = barrel (wide lenses). The delivered focal length grows by the least factor that "
        "keeps the image inside the render; coefficients that fold the image are an error.",
        allowed="5 numbers, each -2..2")
    rear_distortion: tuple[float, float, float, float, float] = setting(
        (0.0, 0.0, 0.0, 0.0, 0.0), "The same for the rear camera (150 deg wide: the polynomial "
        "model folds early there).", allowed="5 numbers, each -2..2")

    def __post_init__(self):
        check_settings(self)
        if not (self.mount_height_m == 0.0 or 0.5 <= self.mount_height_m <= 4.0):
            raise InvalidValue("mount_height_m",
                               f"must be 0 (the car's) or 0.5..4 m, got {self.mount_height_m}")
        for key in ("width", "height"):
            if not getattr(self, key) > 0:
                raise InvalidValue(key, f"must be > 0, got {getattr(self, key)}")
        if not (self.jpeg_quality == 0 or 10 <= self.jpeg_quality <= 100):
            raise InvalidValue("jpeg_quality",
                               f"must be 0 (off) or 10..100, got {self.jpeg_quality}")
        for key in ("distortion", "rear_distortion"):
            value = getattr(self, key)
            if len(value) != 5 or not all(
                    math.isfinite(float(d)) and abs(float(d)) <= 2.0 for d in value):
                raise InvalidValue(key, "must be 5 numbers k1, k2, p1, p2, k3 in [-2, 2], "
                                        f"got {list(value)}")
        if self.antialias_samples not in (0, 2, 4, 8):
            raise InvalidValue("antialias_samples",
                               f"must be 0, 2, 4 or 8, got {self.antialias_samples}")
