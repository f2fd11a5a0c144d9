"""The `[road]` and `[start]` tables of a scenario: the road the car drives (its centre line,
lanes, paint and pavement) and where and how fast the car starts on it, with the nuisance a seed
draws around that start (lanekeep/scenario/nuisance.py).

    [road]
    n_lanes = 2
    [[road.segments]]
    kind = "straight"
    length_m = 300
    [start]
    s_m = 10.0
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, same_as, setting
from lanekeep.geometry.markings import MarkingStyle
from lanekeep.geometry.road import DEFAULT_LANE_WIDTH_M, MAX_LANES, MAX_ROAD_M, SegmentSpec
from lanekeep.scenario.pavement import PavementStyle


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
    tar_lines: float = same_as(PavementStyle, "tar_lines")
    seams: float = same_as(PavementStyle, "seams")
    oil_stripe: float = same_as(PavementStyle, "oil_stripe")
    surface_changes: float = same_as(PavementStyle, "surface_changes")
    section_surface: str = same_as(PavementStyle, "section_surface")

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
        return PavementStyle(**{f.name: getattr(self, f.name)
                                for f in dataclasses.fields(PavementStyle)})

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
