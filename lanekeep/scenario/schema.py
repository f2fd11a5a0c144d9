"""Scenario files: TOML read into frozen, validated dataclasses; the registry of shipped scenarios.

A scenario names a road (segments, lanes, markings), where the car starts, the camera settings and
the conditions. Reading is strict: an unknown key, a wrong type or a bad value raises
`ScenarioError` naming the dotted key and the file (see config_io).

    [road]
    n_lanes = 2
    [[road.segments]]
    kind = "straight"
    length_m = 300

Each table's dataclass lives in its own module (road.py: `[road]` and `[start]`; camera.py,
conditions.py, estimation.py, criteria.py, sensors.py, roadside.py, traffic.py); this module
holds `Scenario`, which nests them, `[control]`, and the loading, and names every table's class
and constants too.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from lanekeep.core.config_io import ConfigError, InvalidValue, from_dict
from lanekeep.core.setting import check_settings, setting
from lanekeep.detectors.config import DetectorsConfig
from lanekeep.geometry.road import Road
from lanekeep.scenario.camera import CAMERA_PRESETS, CameraConfig
from lanekeep.scenario.conditions import (
    SHADOW_KINDS,
    SIDES,
    TIMES_OF_DAY,
    Conditions,
    ShadowZone,
    VehicleSpec,
)
from lanekeep.scenario.criteria import CriteriaConfig
from lanekeep.scenario.estimation import (
    CAMERAS,
    DEFAULT_FRONT_DETECTORS,
    ESTIMATION_MODES,
    EstimationConfig,
)
from lanekeep.scenario.road import RoadConfig, StartConfig, StartJitter
from lanekeep.scenario.roadside import Roadside
from lanekeep.scenario.sensors import SensorsConfig
from lanekeep.scenario.traffic import Traffic

# The tables' own modules hold their dataclasses; they are named here too, where Scenario and
# the code that reads scenario files have always found them.
__all__ = [
    "CAMERAS", "CAMERA_PRESETS", "DEFAULT_FRONT_DETECTORS", "ESTIMATION_MODES", "SHADOW_KINDS",
    "SIDES", "TIMES_OF_DAY", "CameraConfig", "Conditions", "ControlConfig", "CriteriaConfig",
    "EstimationConfig", "InvalidValue", "RoadConfig", "Scenario", "ScenarioError", "ShadowZone",
    "StartConfig", "StartJitter", "VehicleSpec", "load_scenario", "parse_scenario",
    "scenario_from_dict", "shipped_scenarios",
]


class ScenarioError(ConfigError):
    """A scenario file or name is invalid; the message names the key and the file."""


@dataclass(frozen=True)
class ControlConfig:
    """Which controller turns the estimated lane into steer and throttle (`[control]`)."""

    # "pid" (the paper's eq. 9, default), "stanley", an entry point of the group
    # lanekeep.control.registry, or an import path "package.module:Class"
    # (lanekeep/control/registry.py)
    controller: str = setting("pid", "Controller turning the estimated lane into steer and "
                              "throttle.", allowed='"pid", "stanley", package.module:Class, '
                              "entry points")
    # Adaptive cruise (lanekeep/control/acc.py, which gives the sources of the defaults): the
    # built-in controllers' throttle from the forward radar ([sensors.radar]) and the car's own
    # signals; the steering is the same either way.
    acc: bool = setting(False, "Adaptive cruise: follow the vehicle ahead by the forward radar "
                        "(IDM, ISO 15622 limits, emergency braking) up to target_speed_mps; off "
                        "= hold target_speed_mps. Ignored in paper mode (the paper's constant "
                        "speed). The forward radar is read only when it is on.",
                        allowed="true, false")
    acc_time_gap_s: float = setting(1.8, "Time gap the adaptive cruise keeps to the vehicle "
                                    "ahead.", bounds=(0.8, 4.0))
    acc_min_gap_m: float = setting(4.0, "Gap the adaptive cruise keeps when standing behind a "
                                   "vehicle.", bounds=(1.0, 20.0))
    acc_corridor_half_width_m: float = setting(
        1.2, "A radar object within this of the car's predicted path is a target.",
        bounds=(0.3, 3.0))
    acc_emergency_ttc_s: float = setting(1.5, "Time to collision below which the adaptive "
                                         "cruise brakes fully (0 = never).", bounds=(0.0, 5.0))

    def __post_init__(self):
        if not self.controller.strip():
            raise InvalidValue("controller", "must name a controller, got an empty string")
        check_settings(self)


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
    detectors: DetectorsConfig | None = setting(
        None, "Settings of the detectors for this scenario's episodes: the tables of a "
        "detectors file (detectors/config.py; e.g. `[detectors.hough]` with `binarisation = "
        "\"ridge\"`), each key laid over the shipped detectors/detectors.toml. Not set: the "
        "shipped settings. Paper mode still sets its own windows and thresholds over them.",
        allowed="the keys of a detectors file")
    control: ControlConfig = setting(factory=ControlConfig,
                                     doc="The controller, by name, and the adaptive cruise.")
    sensors: SensorsConfig = setting(
        factory=SensorsConfig,
        doc="Error magnitudes of the car's own sensors and its forward radar (sources: "
            "lanekeep/scenario/sensors.py).")
    roadside: Roadside = setting(  # placed by lanekeep/world/props.py
        factory=Roadside,
        doc="Props beside and over the road; all off by default, placed from the seed.")
    traffic: Traffic = setting(  # drawn by lanekeep/world/traffic_flow.py
        factory=Traffic,
        doc="Other vehicles drawn from the seed, how all other vehicles drive (IDM car-following, "
            "MOBIL lane changes) and scripted events (cut-ins, braking leads, stopped vehicles); "
            "no drawn traffic by default.")
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
