"""What happens to a rendered frame before the car sees it: the weather, then the camera.

Order, as light reaches the sensor: the scene's weather in depth (motion blur, fog, falling rain
or snow, drops on the lens; lanekeep/sensing/weather.py), then the camera's own chain
(vignetting, auto-exposure, read noise, tone curve, glare, point spread, JPEG;
lanekeep/sensing/camera_sensor.py). The camera chain is on by default, as on every real camera; a
`CameraConfig` with `read_noise_dn = 0`, `auto_exposure = false`, `vignetting = 0`,
`lens_blur_px = 0`, `bloom = 0` and `jpeg_quality = 0` passes a weatherless frame through
the tone curve only.

`ImageEffects` is made once per camera and episode (the lens drops and the auto-exposure keep
state). Every random choice per frame comes from the `numpy.random.Generator` passed in, so a
seed gives bit-identical frames. `apply(image, conditions, rng)` is the one-shot form.
"""

from __future__ import annotations

import numpy as np

from lanekeep.geometry.camera_model import CameraModel
from lanekeep.scenario.camera import CameraConfig
from lanekeep.scenario.conditions import Conditions
from lanekeep.sensing.camera_sensor import CameraSensor
from lanekeep.sensing.paint_visibility import visible_paint
from lanekeep.sensing.road_water import RoadWater
from lanekeep.sensing.weather import DEPTH_STEP_PX, Weather, needs_depth
from lanekeep.world.lighting import LIGHTING

FAR_M = 1000.0  # depth assumed everywhere when none is given (the far clip plane)
DEFAULT_FOVY_DEG = 88.54  # the front camera's (mjcf/car.xml), for frames without a model


def default_camera(height: int, width: int) -> CameraModel:
    """A forward camera 1.5 m high, pitched 10 deg up, of the front camera's field of view."""
    focal = (height / 2.0) / np.tan(np.radians(DEFAULT_FOVY_DEG) / 2.0)
    K = np.array([[focal, 0.0, (width - 1) / 2.0], [0.0, focal, (height - 1) / 2.0],  # noqa: N806
                  [0.0, 0.0, 1.0]])
    return CameraModel.from_mounting("front", K, width, height, 1.5, np.radians(10.0), 1.0)


class ImageEffects:
    """The weather and the camera of one scenario for one camera of size (height, width).

    `camera_model` places the weather (focus of expansion, depth rays; default: a front camera),
    `airlight_rgb` is the fog colour in 0..255 (default: the time of day's sky horizon),
    `frame_period_s` the auto-exposure's and the lens drops' clock, `start_time_s` the
    drive's time of the first frame (the lens drops are those of that time), `water` where a
    wet road's water lies (lanekeep/sensing/road_water.py; None: on all flat ground).
    """

    def __init__(self, conditions: Conditions, height: int, width: int,
                 rng: np.random.Generator, camera: CameraConfig | None = None,
                 camera_model: CameraModel | None = None, airlight_rgb=None,
                 frame_period_s: float = 0.1, start_time_s: float = 0.0,
                 water: RoadWater | None = None) -> None:
        self.conditions = conditions
        self.height, self.width = height, width
        self.needs_depth = needs_depth(conditions)
        model = camera_model or default_camera(height, width)
        if (model.height, model.width) != (height, width):
            model = model.scaled(width, height)
        if airlight_rgb is None:
            airlight_rgb = 255.0 * np.asarray(LIGHTING[conditions.time_of_day][3][1])
        self.weather = Weather(conditions, model, airlight_rgb, rng, frame_period_s,
                               start_time_s, water)
        self.sensor = CameraSensor(camera or CameraConfig(), conditions.noise, height, width,
                                   frame_period_s, rng)

    def __call__(self, image: np.ndarray, rng: np.random.Generator, speed_mps: float = 0.0,
                 depth_m: np.ndarray | None = None, pose=None) -> np.ndarray:
        """All effects on one RGB uint8 frame (H, W, 3); returns a new array. `depth_m`: the
        render's z-depth at every DEPTH_STEP_PX-th pixel; without it the scene counts as far
        (rain streaks everywhere) and there is no fog (MuJoCo's own fog may be in the frame).
        `pose`: the car's world (x, y, yaw), where the wet road's water is seen."""
        if image.shape != (self.height, self.width, 3) or image.dtype != np.uint8:
            raise ValueError(f"expected uint8 ({self.height}, {self.width}, 3), got "
                             f"{image.dtype} {image.shape}")
        conditions = self.conditions
        if self.needs_depth and depth_m is None:
            shape = (len(range(DEPTH_STEP_PX // 2, self.height, DEPTH_STEP_PX)),
                     len(range(DEPTH_STEP_PX // 2, self.width, DEPTH_STEP_PX)))
            depth_m = np.full(shape, FAR_M, np.float32)
            if conditions.fog > 0.0:  # no depth, no fog: the frame carries MuJoCo's
                self.weather.extinction_per_m = 0.0
        out = self.weather(image, depth_m, rng, speed_mps, pose)
        return self.sensor(out, rng)

    def visible_paint(self, paint: np.ndarray, bare_rgb: np.ndarray, depth_m: np.ndarray
                      ) -> np.ndarray:
        """Boolean (H, W): the pixels of `paint` (from the segmentation render) that this
        camera shows as paint, given the bare render and its depth: less what this camera's
        fog and exposure hide (lanekeep/sensing/paint_visibility.py)."""
        weather = self.weather
        return visible_paint(paint, bare_rgb, weather.range_m(depth_m), weather.extinction_per_m,
                             float(weather.airlight.mean()), self.sensor.gain)


def apply(image: np.ndarray, conditions: Conditions, rng: np.random.Generator,
          speed_mps: float = 0.0, camera: CameraConfig | None = None) -> np.ndarray:
    """One-shot form of ImageEffects (new lens drops, a settled exposure): image -> image."""
    h, w = image.shape[:2]
    return ImageEffects(conditions, h, w, rng, camera)(image, rng, speed_mps)
