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
from lanekeep.core.setting import check_settings, same_as, setting
from lanekeep.estimators.settings import (
    EstimatorSettings,
)
from lanekeep.geometry.markings import MarkingStyle
from lanekeep.geometry.road import DEFAULT_LANE_WIDTH_M, MAX_LANES, MAX_ROAD_M, Road, SegmentSpec
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
    segments: tuple[SegmentSpec, ...] = setting(
        doc="The centre line, piece by piece from the start.", allowed="at least one")
    n_lanes: int = setting(2, "Lanes of the carriageway.", bounds=(1, MAX_LANES))
    lane_width_m: float = setting(DEFAULT_LANE_WIDTH_M, "Width of every lane.", allowed="> 0")
    ego_lane: int = setting(0, "Lane the car starts in and is scored against; 0 = the rightmost.",
                            allowed="0..n_lanes - 1")
    markings: tuple[MarkingStyle, ...] = setting(
        (), "One paint style per lane boundary, rightmost (boundary 0) first; none given = solid "
        "edges and dashed lines between lanes.", allowed="none or n_lanes + 1")
    start_heading_deg: float = setting(0.0, "World heading of the road at its start; + = "
                                       "anticlockwise seen from above.")
    # The pavement, drawn by lanekeep/world/pavement.py: PavementStyle's keys, defined there.
    surface: str = same_as(PavementStyle, "surface")
    asphalt_tone: float = same_as(PavementStyle, "asphalt_tone")
    cracks: float = same_as(PavementStyle, "cracks")
    patches: float = same_as(PavementStyle, "patches")
    tyre_marks: float = same_as(PavementStyle, "tyre_marks")

    def __post_init__(self):
        check_settings(self)
        if not self.segments:
            raise InvalidValue("segments", "at least one segment is needed")
        if not sum(seg.length_m for seg in self.segments) <= MAX_ROAD_M:
            raise InvalidValue("segments", f"the road may be at most {MAX_ROAD_M:g} m long, "
                                           f"got {sum(seg.length_m for seg in self.segments):g}")
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

    offset_m: float = setting(0.15, "Half-width of the start's lateral offset draw.",
                              allowed=">= 0")
    heading_deg: float = setting(0.5, "Half-width of the start's heading draw.", allowed=">= 0")
    speed_mps: float = setting(0.5, "Half-width of the speed draw; the start and target speeds "
                               "move together.", allowed=">= 0")
    traffic_s: float = setting(2.0, "Half-width of each vehicle's timing draw: when the car meets "
                               "it (its speed relative to the car's times the draw).",
                               allowed=">= 0")

    def __post_init__(self):
        for key in ("offset_m", "heading_deg", "speed_mps", "traffic_s"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value >= 0):
                raise InvalidValue(key, f"must be a number >= 0, got {value}")


@dataclass(frozen=True)
class StartConfig:
    s_m: float = setting(10.0, "Where the car starts: arc length along the road.")
    offset_m: float = setting(0.0, "Lateral offset from the ego lane's centre; + = left.")
    heading_deg: float = setting(0.0, "Heading relative to the road's; + = pointing left.")
    speed_mps: float = setting(0.0, "Initial speed.", allowed=">= 0")
    jitter: StartJitter = setting(factory=StartJitter, doc="What a seed other than the file's own "
                                  "draws (uniform within +-each half-width; the file's seed is "
                                  "the nominal drive): lanekeep/scenario/nuisance.py.")

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


@dataclass(frozen=True)
class ShadowZone:
    """Hard shadows cast across the road by buildings or trees standing on one side of it.

    The casters' heights are chosen so that, with the scenario's sun, their shadows reach
    `reach` of the carriageway's width (1 = to the far edge line) from the `side` they stand on.
    """

    s_start_m: float = setting(doc="Start of the zone along the road.", allowed=">= 0")
    s_end_m: float = setting(doc="End of the zone along the road.", allowed="> s_start_m")
    kind: str = setting("buildings", "What casts the shadows.", choices=SHADOW_KINDS)
    side: str = setting("left", "Side of the road the casters stand on.", choices=SIDES)
    reach: float = setting(1.0, "How far across the carriageway the shadows reach; 1 = to the far "
                           "edge line.", allowed="(0, 1.5]")
    coverage: float = setting(0.6, "Share of the zone's length in shadow.", bounds=(0.05, 1.0))
    darkness: float = setting(0.55, "How dark the shade is, as the casters' optical depth: 0 "
                              "none, 0.55 a solid building's shade lit by the open sky (about "
                              "0.2-0.35 of the sunlit road's light, from the sun's height, the "
                              "time of day and fog; lanekeep/world/shade.py), more darker still.",
                              bounds=(0.0, 1.0))

    def __post_init__(self):
        check_settings(self)
        if not self.s_end_m > self.s_start_m >= 0.0:
            raise InvalidValue("s_end_m", "need 0 <= s_start_m < s_end_m")
        if not 0.0 < self.reach <= 1.5:
            raise InvalidValue("reach", f"must be in (0, 1.5], got {self.reach}")


@dataclass(frozen=True)
class VehicleSpec:
    """Another car (or truck) driving along a lane at constant speed; it hides markings.

    Driven kinematically (a mocap body): s(t) = s_m + speed_mps * t; negative speeds drive
    towards decreasing s (oncoming traffic, facing the other way).
    """

    lane: int = setting(1, "Its lane; 0 = the rightmost.", allowed="0..n_lanes - 1")
    s_m: float = setting(30.0, "Arc length of its centre at t = 0.")
    speed_mps: float = setting(15.0, "Constant speed along s; negative = oncoming (facing the "
                               "other way).")
    offset_m: float = setting(0.0, "From its lane's centre; + = left.")
    length_m: float = setting(4.6, "Body length.", bounds=(0.5, 20.0))
    width_m: float = setting(1.85, "Body width.", bounds=(0.5, 20.0))
    height_m: float = setting(1.5, "Body height.", bounds=(0.5, 20.0))
    colour: tuple[float, float, float] = setting(
        (0.6, 0.08, 0.08), "Body colour, RGB.", allowed="3 values in 0..1")

    def __post_init__(self):
        check_settings(self)
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

    time_of_day: str = setting("day", "Light; headlights are on unless day.",
                               choices=TIMES_OF_DAY)
    sun_elevation_deg: float = setting(66.7, "Sun above the horizon.", bounds=(2.0, 90.0))
    sun_azimuth_deg: float = setting(-144.5, "Direction towards the sun from the road's start "
                                     "heading; + = to the left (anticlockwise).")
    shadows: tuple[ShadowZone, ...] = setting((), "Zones of hard shadows cast across the road.",
                                              allowed="any number")
    speed_bumps_m: tuple[float, ...] = setting((), "Arc length of each speed bump across the "
                                               "road.", allowed="each >= 0")
    speed_bump_height_m: float = setting(0.08, "Height of every speed bump.", bounds=(0.02, 0.15))
    wet: float = setting(0.0, "0 dry .. 1 soaked: darker, glossier asphalt and puddles.",
                         bounds=(0.0, 1.0))
    fog: float = setting(0.0, "0 none .. 1 dense (visibility 400 m .. 25 m).", bounds=(0.0, 1.0))
    rain: float = setting(0.0, "Rain streaks and lens drops (image effect).", bounds=(0.0, 1.0))
    snow: float = setting(0.0, "Flakes and whitening (image), snow on the verges (world).",
                          bounds=(0.0, 1.0))
    noise: float = setting(0.0, "Extra sensor noise of the camera model (read + shot noise).",
                           bounds=(0.0, 1.0))
    motion_blur: float = setting(0.0, "Scale of the speed-proportional motion blur.",
                                 bounds=(0.0, 1.0))
    vehicles: tuple[VehicleSpec, ...] = setting((), "Other vehicles driving along a lane at "
                                                "constant speed.", allowed="any number")

    def __post_init__(self):
        check_settings(self)
        for i, s in enumerate(self.speed_bumps_m):
            if not s >= 0.0:
                raise InvalidValue(f"speed_bumps_m[{i}]", f"must be >= 0, got {s}")

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

    # "paper": the paper's own loop (lanekeep/driver/paper_mode.py): one-step-delay residuals, the
    # selected model's detection at its nearest row into eq. 9 with Table 2's gain shape and no
    # feed-forward, model #1 long range and model #2 short range. It overrides residual_mode,
    # model_lane, mmae_prior and the front windows; "default" is our loop with its improvements.
    mode: str = setting("default", "default = our loop; paper = the paper's own loop (overrides "
                        "residual_mode, model_lane and the front windows).",
                        choices=ESTIMATION_MODES)
    # None: the mode's own (DEFAULT_FRONT_DETECTORS), filled in at construction.
    front_detectors: tuple[str, ...] | None = setting(
        None, "The MMAE's models, front camera, in order. Not set: the mode's own, hough, "
        "sliding_window and lanenet (default) or the paper's hough and sliding_window (paper).",
        allowed="registered names, package.module:Class, entry points")
    # The learned detector on the rear camera, as the paper's reference is a learned one
    # (CLRNet); model #2 ("sliding_window") there errs with front model #2 and fails in traffic.
    reference_detector: str = setting("lanenet", "The MMAE's reference (the paper's observer).",
                                      allowed="as front_detectors")
    reference_camera: str = setting("rear", "Camera the reference detector looks through.",
                                    choices=CAMERAS)
    control_lookahead_m: float = setting(8.0, "Where the controller reads the chosen lane.",
                                         bounds=(0.0, 40.0))
    # Body roll compensation (estimators/roll.py; default mode only): the car's roll per m/s^2
    # of lateral acceleration (a suspension constant; 0 turns it off) and each camera's offset
    # error per radian of roll, both measured by tools/measure_roll_coupling.py on the tuning
    # scenarios.
    roll_gradient_deg_per_mps2: float = setting(0.71, "The car's body roll per m/s^2 of lateral "
                                                "acceleration, with which each camera's lane is "
                                                "corrected for roll from the lateral "
                                                "accelerometer (default mode; 0 = off).",
                                                unit="deg/(m/s^2)", bounds=(0.0, 5.0))
    roll_lever_front_m: float = setting(2.4, "Front camera's offset error per radian of body "
                                        "roll.", bounds=(-10.0, 10.0))
    roll_lever_rear_m: float = setting(2.5, "Rear camera's offset error per radian of body roll.",
                                       bounds=(-10.0, 10.0))

    def __post_init__(self):
        super().__post_init__()  # the estimator's checks, and every field's bounds and choices
        if self.front_detectors is None:
            object.__setattr__(self, "front_detectors", DEFAULT_FRONT_DETECTORS[self.mode])
        if not self.front_detectors:
            raise InvalidValue("front_detectors", "at least one front detector is needed")

    def estimator_settings(self) -> EstimatorSettings:
        """The estimator's part of this table, as the estimator's own type."""
        return EstimatorSettings(**{f.name: getattr(self, f.name)
                                    for f in dataclasses.fields(EstimatorSettings)})


_MARGIN_TEXT = re.compile(r"[a-z_:]+(\.[a-z_]+)?=\d+(\.\d*)?(,\d+(\.\d*)?%)?")


@dataclass(frozen=True)
class CriteriaConfig:
    """Pass/fail limits of an episode (`[criteria]`, judged by lanekeep/scoring/criteria.py); None =
    not checked. An episode that leaves the road or stops early fails whatever these say."""

    max_lane_departures: int | None = setting(None, "Pass limit: times a wheel crossed an "
                                              "ego-lane boundary.",
                                              allowed=">= 0; unset = not checked")
    max_car_lateral_error_m: float | None = setting(
        None, "Pass limit: the car's largest |true offset|.", allowed="> 0; unset = not checked")
    max_fused_rmse_m: float | None = setting(None, "Pass limit: offset RMSE of the MMAE output.",
                                             allowed="> 0; unset = not checked")
    # Not a limit: marks a two-mode scenario for the regression gate (lanekeep/report/
    # regression.py): an episode with a fused RMSE above it is a bad episode.
    bad_episode_fused_rmse_m: float | None = setting(
        None, "Not a pass limit: marks a two-mode scenario (markings hidden on some drives); an "
        "episode whose fused RMSE exceeds it is a bad episode, and the regression gate (`bench "
        "--baseline`) compares the rate of bad episodes instead of the RMSE.",
        allowed="> 0; unset = one mode")
    # Not a limit: this scenario's own margins of practical relevance for the regression gate
    # (`bench --baseline`), "METRIC=ABS[,REL%]" each, e.g. "car_max_cm=2" (cm) for a noisy one;
    # the command line's `--margin` wins.
    margins: tuple[str, ...] = setting((), "Not a pass limit: this scenario's margins of "
                                       "practical relevance for the regression gate (`bench "
                                       '--baseline`), each "METRIC=ABS[,REL%]" as `--margin` '
                                       "takes them (docs/statistics.md#margins); the command "
                                       "line's win.", allowed="METRIC=ABS[,REL%] each")
    # Ends the episode as off road once the car's centre is this far (m) from the ego lane's
    # centre; None: only when all four wheels are off the paved surface (always checked).
    off_road_distance_m: float | None = setting(
        None, "End the episode as off road once the car's centre is this far from the ego lane's "
        "centre.", allowed="> 0; unset = only when all wheels leave the pavement")

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
    controller: str = setting("pid", "Controller turning the estimated lane into steer and "
                              "throttle.", allowed='"pid", "stanley", package.module:Class, '
                              "entry points")

    def __post_init__(self):
        if not self.controller.strip():
            raise InvalidValue("controller", "must name a controller, got an empty string")


@dataclass(frozen=True)
class Scenario:
    name: str = setting(doc="Scenario name, shown in reports.")
    description: str = setting(doc="One line saying what the scenario tests.")
    road: RoadConfig = setting(doc="The road: its centre line, lanes, paint and pavement.")
    seed: int = setting(0, "Seed of every random draw: worn paint, props, image effects, sensor "
                        "noise.", allowed="any integer")
    duration_s: float = setting(20.0, "Simulated length of the episode.", allowed="> 0")
    control_period_s: float = setting(0.1, "Period of the loop: one frame per camera, one control "
                                      "update.", allowed="> 0")
    target_speed_mps: float = setting(15.0, "Speed the speed controller holds.", allowed=">= 0")
    start: StartConfig = setting(factory=StartConfig, doc="Where and how fast the car starts.")
    camera: CameraConfig = setting(
        factory=CameraConfig,
        doc="Both onboard cameras: image size, the camera model, the mounting.")
    conditions: Conditions = setting(
        factory=Conditions,
        doc="Light, weather, surface, traffic and image conditions; all off by default.")
    estimation: EstimationConfig = setting(
        factory=EstimationConfig,
        doc="Which detectors run, the MMAE's reference, how the output is formed.")
    control: ControlConfig = setting(factory=ControlConfig, doc="The controller, by name.")
    sensors: SensorsConfig = setting(
        factory=SensorsConfig,
        doc="Error magnitudes of the car's own sensors (sources: lanekeep/scenario/sensors.py).")
    roadside: Roadside = setting(  # placed by lanekeep/world/props.py
        factory=Roadside,
        doc="Props beside and over the road; all off by default, placed from the seed.")
    traffic: Traffic = setting(  # drawn by lanekeep/world/traffic_flow.py
        factory=Traffic,
        doc="Other vehicles drawn from the seed in the lanes beside the car's, never in its own; "
            "off by default.")
    criteria: CriteriaConfig = setting(  # judged by lanekeep/scoring/criteria.py
        factory=CriteriaConfig,
        doc="Pass/fail limits of an episode; an episode that leaves the road or stops early fails "
            "whatever they say.")
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
