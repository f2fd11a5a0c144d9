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
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from lanekeep.config_io import ConfigError, InvalidValue, from_dict
from lanekeep.markings import MarkingStyle
from lanekeep.road import Road, SegmentSpec

TIMES_OF_DAY = ("day", "dawn", "dusk", "night")
SHADOW_KINDS = ("buildings", "trees", "poles", "overpass")


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

    def __post_init__(self):
        if not self.segments:
            raise InvalidValue("segments", "at least one segment is needed")
        if not 1 <= self.n_lanes <= 4:
            raise InvalidValue("n_lanes", f"must be 1..4, got {self.n_lanes}")
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
    def length_m(self) -> float:
        return sum(seg.length_m for seg in self.segments)


@dataclass(frozen=True)
class StartConfig:
    s_m: float = 10.0  # arc length along the road
    offset_m: float = 0.0  # lateral offset from the ego lane centre, + = left
    heading_deg: float = 0.0  # relative to the road heading, + = pointing left
    speed_mps: float = 0.0

    def __post_init__(self):
        if not self.speed_mps >= 0:
            raise InvalidValue("speed_mps", f"must be >= 0, got {self.speed_mps}")


@dataclass(frozen=True)
class CameraConfig:
    width: int = 1280
    height: int = 720
    shadows: bool = False

    def __post_init__(self):
        for key in ("width", "height"):
            if not getattr(self, key) > 0:
                raise InvalidValue(key, f"must be > 0, got {getattr(self, key)}")


@dataclass(frozen=True)
class Conditions:
    """Weather, light and sensor conditions; all off by default (the conditions issue fills in)."""

    shadows: tuple[str, ...] = ()  # kinds of cast shadows on the road
    wet: bool = False
    fog: float = 0.0  # 0..1
    time_of_day: str = "day"
    rain: float = 0.0  # 0..1
    snow: float = 0.0  # 0..1
    noise: float = 0.0  # 0..1 sensor noise level

    def __post_init__(self):
        if self.time_of_day not in TIMES_OF_DAY:
            raise InvalidValue(
                "time_of_day", f"must be one of {TIMES_OF_DAY}, got {self.time_of_day!r}"
            )
        for i, kind in enumerate(self.shadows):
            if kind not in SHADOW_KINDS:
                raise InvalidValue(f"shadows[{i}]", f"must be one of {SHADOW_KINDS}, got {kind!r}")
        for key in ("fog", "rain", "snow", "noise"):
            if not 0.0 <= getattr(self, key) <= 1.0:
                raise InvalidValue(key, f"must be in [0, 1], got {getattr(self, key)}")


RESIDUAL_MODES = ("distance_aligned", "one_step_delay")
OUTPUT_MODES = ("select", "fused")
CAMERAS = ("front", "rear")


@dataclass(frozen=True)
class EstimationConfig:
    """Which detectors run, which one is the MMAE reference, and how the output is formed.

    The paper runs two front models and a rear-camera reference; residuals compare the
    reference with the models one step earlier (eq. 2, "one_step_delay") or, our default,
    at the same road position ("distance_aligned"). Output: the paper's argmax ("select") or
    the probability-weighted lane ("fused").
    """

    front_detectors: tuple[str, ...] = ("hough", "sliding_window")
    reference_detector: str = "sliding_window"
    reference_camera: str = "rear"
    residual_mode: str = "distance_aligned"
    output: str = "select"
    offset_lookahead_m: float = 6.0  # where offsets are compared and reported (front)
    control_lookahead_m: float = 8.0  # where the PID reads the chosen lane

    def __post_init__(self):
        if not self.front_detectors:
            raise InvalidValue("front_detectors", "at least one front detector is needed")
        if self.reference_camera not in CAMERAS:
            raise InvalidValue("reference_camera", f"must be one of {CAMERAS}")
        if self.residual_mode not in RESIDUAL_MODES:
            raise InvalidValue("residual_mode", f"must be one of {RESIDUAL_MODES}")
        if self.output not in OUTPUT_MODES:
            raise InvalidValue("output", f"must be one of {OUTPUT_MODES}")
        for key in ("offset_lookahead_m", "control_lookahead_m"):
            if not 0.0 <= getattr(self, key) <= 40.0:
                raise InvalidValue(key, f"must be in [0, 40] m, got {getattr(self, key)}")


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
    source: str = field(default="", metadata={"toml": False})  # file it was read from

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
    """Names of the scenarios shipped in lanekeep/scenarios/*.toml, sorted."""
    files = resources.files("lanekeep.scenarios").iterdir()
    return sorted(f.name[: -len(".toml")] for f in files if f.name.endswith(".toml"))


def parse_scenario(text: str, source: str = "<string>") -> Scenario:
    """A scenario from TOML text; `source` names it in error messages."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(source, "", f"invalid TOML: {err}") from None
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
    resource = resources.files("lanekeep.scenarios").joinpath(f"{text}.toml")
    return parse_scenario(resource.read_text(encoding="utf-8"), source=str(resource))
