"""Scenario files: TOML read into frozen, validated dataclasses; the registry of shipped scenarios.

A scenario names a road (segments, lanes, markings), where the car starts, the camera settings and
the conditions. Reading is strict: an unknown key, a wrong type or a bad value raises
`ScenarioError` naming the dotted key and the file (see config_io).

    [road]
    n_lanes = 2
    [[road.segments]]
    kind = "straight"
    length_m = 300
"""

from __future__ import annotations

import dataclasses
import math
import re
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from lanekeep.core.config_io import ConfigError, InvalidValue, from_dict
from lanekeep.estimators.settings import (
    EstimatorSettings,
)
from lanekeep.geometry.markings import MarkingStyle
from lanekeep.geometry.road import MAX_LANES, MAX_ROAD_M, Road, SegmentSpec
from lanekeep.scenario.pavement import PavementStyle
from lanekeep.scenario.roadside import Roadside
from lanekeep.scenario.sensors import SensorsConfig
from lanekeep.scenario.traffic import Traffic

TIMES_OF_DAY = ("day", "dawn", "dusk", "night")
SHADOW_KINDS = ("buildings", "trees")
SIDES = ("left", "right")
CAMERA_PRESETS = ("paper", "dashcam")  # lanekeep/world/camera_mount.py: the front camera's pose


class ScenarioError(ConfigError):
    """A scenario file or name is invalid; the message names the key and the file."""


@dataclass(frozen=True)
class RoadConfig:
    segments: tuple[SegmentSpec, ...]
    n_lanes: int = 2
    lane_width_m: float = 3.7
    ego_lane: int = 0  # lane the car starts in, 0 = rightmost
    markings: tuple[MarkingStyle, ...] = ()  # one per boundary, rightmost first; () = default
    start_heading_deg: float = 0.0
    # The pavement (lanekeep/world/pavement.py): surface "asphalt" | "concrete"; the rest 0..1.
    surface: str = "asphalt"
    asphalt_tone: float = 0.5  # 0 fresh black .. 1 old, sun-bleached grey
    cracks: float = 0.3
    patches: float = 0.2
    tyre_marks: float = 0.4  # darker wheel paths and oil strip in every lane

    def __post_init__(self):
        if not self.segments:
            raise InvalidValue("segments", "at least one segment is needed")
        if not sum(seg.length_m for seg in self.segments) <= MAX_ROAD_M:
            raise InvalidValue("segments", f"the road may be at most {MAX_ROAD_M:g} m long, "
                                           f"got {sum(seg.length_m for seg in self.segments):g}")
        if not 1 <= self.n_lanes <= MAX_LANES:
            raise InvalidValue("n_lanes", f"must be 1..{MAX_LANES}, got {self.n_lanes}")
        if not self.lane_width_m > 0:
            raise InvalidValue("lane_width_m", f"must be > 0, got {self.lane_width_m}")
        if not 0 <= self.ego_lane < self.n_lanes:
            raise InvalidValue("ego_lane", f"must be in 0..{self.n_lanes - 1}, got {self.ego_lane}")
        if self.markings and len(self.markings) != self.n_lanes + 1:
            raise InvalidValue(
                "markings",
                f"need n_lanes + 1 = {self.n_lanes + 1} styles (one per boundary), "
                f"got {len(self.markings)}",
            )
        _ = self.pavement  # validates the pavement keys

    @property
    def pavement(self) -> PavementStyle:
        return PavementStyle(self.surface, self.asphalt_tone, self.cracks, self.patches,
                             self.tyre_marks)

    @property
    def length_m(self) -> float:
        return sum(seg.length_m for seg in self.segments)


@dataclass(frozen=True)
class StartJitter:
    """Half-widths of the uniform ranges a seed draws the start from, unless it is the file's
    own seed (the nominal drive, exactly as the file says): what an experimenter calls
    nuisance, so that seeds sample drives rather than repeat one (lanekeep/scenario/nuisance.py).

    `speed_mps` moves the start speed and the target speed together; `traffic_s` moves when
    the car meets each other vehicle (its speed relative to the car's, times a draw in
    +-traffic_s)."""

    offset_m: float = 0.15
    heading_deg: float = 0.5
    speed_mps: float = 0.5
    traffic_s: float = 2.0

    def __post_init__(self):
        for key in ("offset_m", "heading_deg", "speed_mps", "traffic_s"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value >= 0):
                raise InvalidValue(key, f"must be a number >= 0, got {value}")


@dataclass(frozen=True)
class StartConfig:
    s_m: float = 10.0  # arc length along the road
    offset_m: float = 0.0  # lateral offset from the ego lane centre, + = left
    heading_deg: float = 0.0  # relative to the road heading, + = pointing left
    speed_mps: float = 0.0
    jitter: StartJitter = field(default_factory=StartJitter)  # [start.jitter]: not the file's seed

    def __post_init__(self):
        if not self.speed_mps >= 0:
            raise InvalidValue("speed_mps", f"must be >= 0, got {self.speed_mps}")


@dataclass(frozen=True)
class CameraConfig:
    """Onboard camera image size and what the renderer spends on it.

    `antialias_samples` is MuJoCo's offscreen multisampling (`offsamples`). On a CPU (Mesa
    llvmpipe) 4 samples cost 2.6x a plain render of both cameras (94 vs 36 ms, `lanekeep
    perf`) and bought the detectors nothing measurable, since they shrink the frame with
    area averaging before they look at it (2x2 pixels per working pixel): the bench table in
    docs/experiments.md's performance section shows both. Raise it for frames meant for people.
    """

    width: int = 1280
    height: int = 720
    shadows: bool = False
    antialias_samples: int = 0
    # The camera model (lanekeep/sensing/camera_sensor.py), on by default as on a real camera.
    read_noise_dn: float = 1.0  # sensor read noise (digital numbers, before the gain)
    auto_exposure: bool = True  # causal gain from the past frames' metering
    exposure_time_constant_s: float = 0.3  # how fast the exposure follows the scene
    vignetting: float = 0.2  # corner darkening of the lens, 0 none .. 0.6
    # Lens + demosaic point spread: Gaussian sigma in pixels of the frame; 0.8 makes a hard
    # edge rise over ~2-3 px as on real photos instead of a 1 px stair step. 0 = off, .. 3.
    lens_blur_px: float = 0.8
    bloom: float = 0.4  # glare around near-saturated areas (sky, lamps), 0 = off .. 1
    # JPEG compression of every frame, 0 = off, else 10..100. Off by default: an ADAS camera
    # hands perception uncompressed frames (JPEG is how dashcams and datasets store them; the
    # LaneNet dataset draws 30..95), and at 1280x720 it would cost ~4-5 ms a frame per camera
    # here (`lanekeep perf`, 2026-11-27), most of the richer world's step budget.
    jpeg_quality: int = 0
    show_hood: bool = True  # the ego car's hood at the bottom of the front image
    # The mounting of both onboard cameras, changed from the car's own (mjcf/car.xml: 1.5 m
    # high, front pitched 10 deg up with a 120 deg horizontal field of view): other cameras, as
    # real rigs and the datasets (lanekeep/evaluation/dataset.py) have. Applied by
    # lanekeep/world/camera_mount.py
    # to the compiled model, so the detectors' camera models (read from it) stay exact.
    mount_height_m: float = 0.0  # 0 = the preset's (1.5 m; dashcam front 1.4 m); else both
    pitch_offset_deg: float = 0.0  # added to each camera's pitch, + = looking up
    roll_deg: float = 0.0  # about each camera's optical axis, + = image turns anticlockwise
    yaw_offset_deg: float = 0.0  # about the car's vertical axis, + = towards the car's left
    fov_scale: float = 1.0  # scales tan(field of view / 2): < 1 a longer lens
    # The front camera's base pose before the keys above: "paper" = the car's (Table 1),
    # "dashcam" = a real dashcam's (60 deg wide, 1.4 m, horizon near row 300 of 720); the
    # rear camera keeps the car's pose under either.
    preset: str = "paper"
    # OpenCV lens distortion k1, k2, p1, p2, k3 of the front and the rear camera
    # (lanekeep/geometry/lens.py); all zero = a pinhole. The detectors are given the same
    # coefficients, as from a camera file.
    distortion: tuple[float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0)
    rear_distortion: tuple[float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0)

    def __post_init__(self):
        if not (self.mount_height_m == 0.0 or 0.5 <= self.mount_height_m <= 4.0):
            raise InvalidValue("mount_height_m",
                               f"must be 0 (the car's) or 0.5..4 m, got {self.mount_height_m}")
        for key, limit in (("pitch_offset_deg", 30.0), ("roll_deg", 20.0),
                           ("yaw_offset_deg", 30.0)):
            if not -limit <= getattr(self, key) <= limit:
                raise InvalidValue(key, f"must be in [-{limit:g}, {limit:g}] deg, "
                                        f"got {getattr(self, key)}")
        if self.preset not in CAMERA_PRESETS:
            raise InvalidValue("preset", f"must be one of {', '.join(CAMERA_PRESETS)}, "
                                         f"got {self.preset!r}")
        if not 0.3 <= self.fov_scale <= 1.5:
            raise InvalidValue("fov_scale", f"must be in [0.3, 1.5], got {self.fov_scale}")
        for key in ("width", "height"):
            if not getattr(self, key) > 0:
                raise InvalidValue(key, f"must be > 0, got {getattr(self, key)}")
        if not 0.0 <= self.read_noise_dn <= 20.0:
            raise InvalidValue("read_noise_dn", f"must be in [0, 20], got {self.read_noise_dn}")
        if not 0.01 <= self.exposure_time_constant_s <= 10.0:
            raise InvalidValue("exposure_time_constant_s",
                               f"must be in [0.01, 10] s, got {self.exposure_time_constant_s}")
        if not 0.0 <= self.vignetting <= 0.6:
            raise InvalidValue("vignetting", f"must be in [0, 0.6], got {self.vignetting}")
        if not 0.0 <= self.lens_blur_px <= 3.0:
            raise InvalidValue("lens_blur_px", f"must be in [0, 3] px, got {self.lens_blur_px}")
        if not 0.0 <= self.bloom <= 1.0:
            raise InvalidValue("bloom", f"must be in [0, 1], got {self.bloom}")
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


def _check_unit(obj, keys: tuple[str, ...]) -> None:
    for key in keys:
        if not 0.0 <= getattr(obj, key) <= 1.0:
            raise InvalidValue(key, f"must be in [0, 1], got {getattr(obj, key)}")


@dataclass(frozen=True)
class ShadowZone:
    """Hard shadows cast across the road by buildings or trees standing on one side of it.

    The casters' heights are chosen so that, with the scenario's sun, their shadows reach
    `reach` of the carriageway's width (1 = to the far edge line) from the `side` they stand on.
    """

    s_start_m: float
    s_end_m: float
    kind: str = "buildings"  # "buildings" | "trees"
    side: str = "left"  # side of the road the casters stand on
    reach: float = 1.0  # how far across the carriageway the shadows reach, 0..1.5 of its width
    coverage: float = 0.6  # fraction of the zone's length in shadow; 1 = one continuous shadow
    darkness: float = 0.55  # optical depth: 0 none, 0.55 a solid caster (lanekeep/world/shade.py)

    def __post_init__(self):
        if self.kind not in SHADOW_KINDS:
            raise InvalidValue("kind", f"must be one of {SHADOW_KINDS}, got {self.kind!r}")
        if self.side not in SIDES:
            raise InvalidValue("side", f"must be one of {SIDES}, got {self.side!r}")
        if not self.s_end_m > self.s_start_m >= 0.0:
            raise InvalidValue("s_end_m", "need 0 <= s_start_m < s_end_m")
        if not 0.0 < self.reach <= 1.5:
            raise InvalidValue("reach", f"must be in (0, 1.5], got {self.reach}")
        if not 0.05 <= self.coverage <= 1.0:
            raise InvalidValue("coverage", f"must be in [0.05, 1], got {self.coverage}")
        _check_unit(self, ("darkness",))


@dataclass(frozen=True)
class VehicleSpec:
    """Another car (or truck) driving along a lane at constant speed; it hides markings.

    Driven kinematically (a mocap body): s(t) = s_m + speed_mps * t; negative speeds drive
    towards decreasing s (oncoming traffic, facing the other way).
    """

    lane: int = 1
    s_m: float = 30.0  # arc length of its centre at t = 0
    speed_mps: float = 15.0
    offset_m: float = 0.0  # from the lane centre, + = left
    length_m: float = 4.6
    width_m: float = 1.85
    height_m: float = 1.5
    colour: tuple[float, float, float] = (0.6, 0.08, 0.08)

    def __post_init__(self):
        for key in ("length_m", "width_m", "height_m"):
            if not 0.5 <= getattr(self, key) <= 20.0:
                raise InvalidValue(key, f"must be in [0.5, 20] m, got {getattr(self, key)}")
        if len(self.colour) != 3 or not all(0.0 <= c <= 1.0 for c in self.colour):
            raise InvalidValue("colour", f"must be 3 values in [0, 1], got {self.colour}")


@dataclass(frozen=True)
class Conditions:
    """Light, weather, road surface, traffic and sensor conditions; all off by default.

    Rendered by MuJoCo (lanekeep/world/conditions.py): sun and time of day, shadows, speed bumps,
    wet asphalt and puddles, headlights, other vehicles, snow on the verges. Applied to the
    images with the render's depth (lanekeep/sensing/weather.py): Koschmieder fog, rain streaks
    in depth, wet-road reflections, lens drops, snowflakes, motion blur; `noise` is extra read
    noise of the camera model (lanekeep/sensing/camera_sensor.py, which also does the exposure). The
    default sun reproduces world.py's clear-day light.
    """

    time_of_day: str = "day"  # "day" | "dawn" | "dusk" | "night"; headlights on unless "day"
    sun_elevation_deg: float = 66.7  # above the horizon
    sun_azimuth_deg: float = -144.5  # towards the sun, from the road's start heading, + = left
    shadows: tuple[ShadowZone, ...] = ()
    speed_bumps_m: tuple[float, ...] = ()  # arc length of each bump across the road
    speed_bump_height_m: float = 0.08
    wet: float = 0.0  # 0 dry .. 1 soaked: darker, glossier asphalt and more puddles
    fog: float = 0.0  # 0 none .. 1 dense (visibility 400 m .. 25 m)
    rain: float = 0.0  # 0..1 streaks and lens drops (image effect)
    snow: float = 0.0  # 0..1 flakes and whitening (image effect), snow on the verges (world)
    noise: float = 0.0  # 0..1 sensor noise (Gaussian read noise + shot noise)
    motion_blur: float = 0.0  # 0..1 scale of the speed-proportional motion blur
    vehicles: tuple[VehicleSpec, ...] = ()

    def __post_init__(self):
        if self.time_of_day not in TIMES_OF_DAY:
            raise InvalidValue(
                "time_of_day", f"must be one of {TIMES_OF_DAY}, got {self.time_of_day!r}"
            )
        if not 2.0 <= self.sun_elevation_deg <= 90.0:
            raise InvalidValue(
                "sun_elevation_deg", f"must be in [2, 90], got {self.sun_elevation_deg}"
            )
        if not 0.02 <= self.speed_bump_height_m <= 0.15:
            raise InvalidValue(
                "speed_bump_height_m", f"must be in [0.02, 0.15], got {self.speed_bump_height_m}"
            )
        for i, s in enumerate(self.speed_bumps_m):
            if not s >= 0.0:
                raise InvalidValue(f"speed_bumps_m[{i}]", f"must be >= 0, got {s}")
        _check_unit(self, ("wet", "fog", "rain", "snow", "noise", "motion_blur"))

    @property
    def headlights(self) -> bool:
        return self.time_of_day != "day"


ESTIMATION_MODES = ("default", "paper")
CAMERAS = ("front", "rear")
# The front models of each estimation mode when a scenario names none: our loop adds the
# learned model (detectors/lanenet.py) to the paper's two classical ones; the paper's loop
# keeps its two.
DEFAULT_FRONT_DETECTORS = {"default": ("hough", "sliding_window", "lanenet"),
                           "paper": ("hough", "sliding_window")}


@dataclass(frozen=True)
class EstimationConfig(EstimatorSettings):
    """Which detectors run, which one is the MMAE reference, and how the output is formed.

    The estimator's own keys (residual_mode, output, model_lane, mmae_prior, ...) and their
    defaults are `EstimatorSettings`' (estimators/settings.py), defined once; the keys below
    are the loop's. The paper runs two front models and a rear-camera reference; residuals
    compare the reference with the models one step earlier (eq. 2) or, our default, at the
    same road position.
    """

    # "paper": the paper's own loop (lanekeep/loop/paper_mode.py): one-step-delay residuals, the
    # selected model's detection at its nearest row into eq. 9 with Table 2's gain shape and no
    # feed-forward, model #1 long range and model #2 short range. It overrides residual_mode,
    # model_lane, mmae_prior and the front windows; "default" is our loop with its improvements.
    mode: str = "default"
    # None: the mode's own (DEFAULT_FRONT_DETECTORS), filled in at construction.
    front_detectors: tuple[str, ...] | None = None
    # The learned detector on the rear camera, as the paper's reference is a learned one
    # (CLRNet); model #2 ("sliding_window") there errs with front model #2 and fails in traffic.
    reference_detector: str = "lanenet"
    reference_camera: str = "rear"
    control_lookahead_m: float = 8.0  # where the PID reads the chosen lane
    # Body roll compensation (estimators/roll.py; default mode only): the car's roll per m/s^2
    # of lateral acceleration (a suspension constant; 0 turns it off) and each camera's offset
    # error per radian of roll, both measured by tools/measure_roll_coupling.py on the tuning
    # scenarios.
    roll_gradient_deg_per_mps2: float = 0.71
    roll_lever_front_m: float = 2.4
    roll_lever_rear_m: float = 2.5

    def __post_init__(self):
        super().__post_init__()  # the estimator's own checks
        if self.mode not in ESTIMATION_MODES:
            raise InvalidValue("mode", f"must be one of {ESTIMATION_MODES}, got {self.mode!r}")
        if self.front_detectors is None:
            object.__setattr__(self, "front_detectors", DEFAULT_FRONT_DETECTORS[self.mode])
        if not self.front_detectors:
            raise InvalidValue("front_detectors", "at least one front detector is needed")
        if self.reference_camera not in CAMERAS:
            raise InvalidValue("reference_camera", f"must be one of {CAMERAS}")
        if not 0.0 <= self.control_lookahead_m <= 40.0:
            raise InvalidValue("control_lookahead_m",
                               f"must be in [0, 40] m, got {self.control_lookahead_m}")
        if not 0.0 <= self.roll_gradient_deg_per_mps2 <= 5.0:
            raise InvalidValue("roll_gradient_deg_per_mps2",
                               f"must be in [0, 5], got {self.roll_gradient_deg_per_mps2}")
        for key in ("roll_lever_front_m", "roll_lever_rear_m"):
            if not -10.0 <= getattr(self, key) <= 10.0:
                raise InvalidValue(key, f"must be in [-10, 10] m, got {getattr(self, key)}")

    def estimator_settings(self) -> EstimatorSettings:
        """The estimator's part of this table, as the estimator's own type."""
        return EstimatorSettings(**{f.name: getattr(self, f.name)
                                    for f in dataclasses.fields(EstimatorSettings)})


_MARGIN_TEXT = re.compile(r"[a-z_:]+(\.[a-z_]+)?=\d+(\.\d*)?(,\d+(\.\d*)?%)?")


@dataclass(frozen=True)
class CriteriaConfig:
    """Pass/fail limits of an episode (`[criteria]`, judged by lanekeep/scoring/criteria.py); None =
    not checked. An episode that leaves the road or stops early fails whatever these say."""

    max_lane_departures: int | None = None  # times a wheel crossed an ego-lane boundary
    max_car_lateral_error_m: float | None = None  # the car's largest |true offset| from centre
    max_fused_rmse_m: float | None = None  # offset RMSE of the MMAE output ("fused")
    # Not a limit: marks a two-mode scenario for the regression gate (lanekeep/report/
    # regression.py): an episode with a fused RMSE above it is a bad episode.
    bad_episode_fused_rmse_m: float | None = None
    # Not a limit: this scenario's own margins of practical relevance for the regression gate
    # (`bench --baseline`), "METRIC=ABS[,REL%]" each, e.g. "car_max_cm=2" (cm) for a noisy one;
    # the command line's `--margin` wins.
    margins: tuple[str, ...] = ()
    # Ends the episode as off road once the car's centre is this far (m) from the ego lane's
    # centre; None: only when all four wheels are off the paved surface (always checked).
    off_road_distance_m: float | None = None

    def __post_init__(self):
        if self.max_lane_departures is not None and not self.max_lane_departures >= 0:
            raise InvalidValue("max_lane_departures",
                               f"must be >= 0, got {self.max_lane_departures}")
        for text in self.margins:
            if not _MARGIN_TEXT.fullmatch(text):
                raise InvalidValue("margins", f"{text!r}: expected METRIC=ABS[,REL%], e.g. "
                                              "fused.rmse_cm=0.2,5%")
        for key in ("max_car_lateral_error_m", "max_fused_rmse_m", "bad_episode_fused_rmse_m",
                    "off_road_distance_m"):
            value = getattr(self, key)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise InvalidValue(key, f"must be a number > 0 (m), got {value}")


@dataclass(frozen=True)
class ControlConfig:
    """Which controller turns the estimated lane into steer and throttle (`[control]`)."""

    # "pid" (the paper's eq. 9, default), "stanley", an entry point of the group
    # lanekeep.control.registry, or an import path "package.module:Class"
    # (lanekeep/control/registry.py)
    controller: str = "pid"

    def __post_init__(self):
        if not self.controller.strip():
            raise InvalidValue("controller", "must name a controller, got an empty string")


@dataclass(frozen=True)
class Scenario:
    name: str
    description: str
    road: RoadConfig
    seed: int = 0
    duration_s: float = 20.0
    control_period_s: float = 0.1
    target_speed_mps: float = 15.0
    start: StartConfig = field(default_factory=StartConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)
    conditions: Conditions = field(default_factory=Conditions)
    estimation: EstimationConfig = field(default_factory=EstimationConfig)
    control: ControlConfig = field(default_factory=ControlConfig)  # the controller, by name
    sensors: SensorsConfig = field(default_factory=SensorsConfig)
    roadside: Roadside = field(default_factory=Roadside)  # props: lanekeep/world/props.py
    traffic: Traffic = field(default_factory=Traffic)  # lanekeep/world/traffic_flow.py
    criteria: CriteriaConfig = field(default_factory=CriteriaConfig)  # pass/fail limits
    source: str = field(default="", metadata={"toml": False})  # file it was read from
    # The seed its file gives: that seed is the file's nominal drive, any other draws the
    # start and traffic timing (lanekeep/scenario/nuisance.py). None (built in memory): 0.
    nominal_seed: int | None = field(default=None, metadata={"toml": False})

    def __post_init__(self):
        for key in ("duration_s", "control_period_s"):
            if not getattr(self, key) > 0:
                raise InvalidValue(key, f"must be > 0, got {getattr(self, key)}")
        if not self.target_speed_mps >= 0:
            raise InvalidValue("target_speed_mps", f"must be >= 0, got {self.target_speed_mps}")

    def build_road(self) -> Road:
        """The road of this scenario; 'worn' markings are seeded from the scenario seed."""
        return Road(
            self.road.segments,
            n_lanes=self.road.n_lanes,
            lane_width_m=self.road.lane_width_m,
            markings=self.road.markings or None,
            start_heading_rad=math.radians(self.road.start_heading_deg),
            rng_seed=self.seed,
        )

    def start_pose(self, road: Road | None = None) -> tuple[float, float, float]:
        """World (x, y, yaw) of the car at the start: lane centre + offset, heading + angle."""
        road = road or self.build_road()
        r = road.lane_center_r(self.road.ego_lane) + self.start.offset_m
        x, y = road.position(self.start.s_m, r)
        yaw = road.heading_at(self.start.s_m) + math.radians(self.start.heading_deg)
        return float(x), float(y), float(yaw)


def shipped_scenarios() -> list[str]:
    """Names of the scenarios shipped in lanekeep/scenario/shipped/*.toml, sorted."""
    files = resources.files("lanekeep.scenario.shipped").iterdir()
    return sorted(f.name[: -len(".toml")] for f in files if f.name.endswith(".toml"))


def parse_scenario(text: str, source: str = "<string>") -> Scenario:
    """A scenario from TOML text; `source` names it in error messages."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(source, "", f"invalid TOML: {err}") from None
    scenario = scenario_from_dict(data, source)
    return dataclasses.replace(scenario, nominal_seed=scenario.seed)


def scenario_from_dict(data: dict, source: str = "<dict>") -> Scenario:
    """A scenario from a parsed TOML table, with the checks of a file (`lanekeep sweep` builds
    each cell's table in memory: a base scenario with its parameters set)."""
    try:
        scenario = from_dict(Scenario, data, source=source)
    except ConfigError as err:
        raise ScenarioError(err.source, err.key, err.message) from None
    return dataclasses.replace(scenario, source=source)


def load_scenario(name_or_path: str | Path) -> Scenario:
    """A shipped scenario by name ("clear_straight") or a scenario file by path."""
    text = str(name_or_path)
    if isinstance(name_or_path, Path) or text.endswith(".toml") or "/" in text:
        path = Path(name_or_path)
        if not path.is_file():
            raise ScenarioError(str(path), "", "no such scenario file")
        return parse_scenario(path.read_text(encoding="utf-8"), source=str(path))
    if text not in shipped_scenarios():
        known = ", ".join(shipped_scenarios())
        raise ScenarioError("", "", f"unknown scenario {text!r} (shipped: {known})")
    resource = resources.files("lanekeep.scenario.shipped").joinpath(f"{text}.toml")
    return parse_scenario(resource.read_text(encoding="utf-8"), source=str(resource))
