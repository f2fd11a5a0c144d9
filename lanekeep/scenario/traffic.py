"""The `[traffic]` table of a scenario: other vehicles drawn from the seed, and how every other
vehicle drives: car-following by the Intelligent Driver Model, lane changes by MOBIL (along a
minimum-jerk path on the road's Frenet frame), and scripted events (a cut-in, a braking lead,
a vehicle stopped on the shoulder), as real roads have them (a TuSimple frame shows 5-10
vehicles) and as a lane-keeping test needs them.

Off by default (`vehicles_per_km = 0`, no events), so a scenario without the table keeps only
the vehicles it lists under `[[conditions.vehicles]]`; those drive by the same models.
lanekeep/world/traffic_flow.py turns the table into vehicles and lanekeep/traffic/ drives
them; every draw (places, speeds, kinds, sizes, colours, each vehicle's IDM figures) comes from
the scenario seed, so a seed reproduces its traffic.

    [traffic]
    vehicles_per_km = 20.0                 # per lane, each lane but the car's
    lane_vehicles_per_km = []              # or one per lane, rightmost first (the car's too)
    directions = ["same", "oncoming"]      # per lane, rightmost first; [] = all "same"
    speed_mps = [12.0, 18.0]               # each lane's speed is drawn from this range
    speed_spread_mps = 2.0                 # each vehicle wants its lane's speed +- this
    clear_m = 25.0                         # no vehicle this near the car's start, any lane
    politeness = 0.3                       # MOBIL's p: 0 selfish (aggressive), 1 altruistic

    [[traffic.events]]
    kind = "cut_in"                        # or "lead_brake", "stopped"
    ahead_m = 30.0                         # where its vehicle starts, ahead of the car
    at_gap_m = 12.0                        # cuts in when its rear is 12 m ahead of the car
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, choices_text, setting

DIRECTIONS = ("same", "oncoming")
MODELS = ("idm", "constant")
EVENT_KINDS = ("cut_in", "lead_brake", "stopped")
VEHICLE_KINDS = ("car", "van", "truck")
SIDES = ("right", "left")
MAX_VEHICLES_PER_KM = 60.0  # per lane: 17 m from front to front, bumper to bumper in a jam


@dataclass(frozen=True)
class TrafficEventSpec:
    """A scripted event and the vehicle it brings: placed `ahead_m` along the road from the
    car's start (behind it when negative) at t = 0.

    - "cut_in": a vehicle in `lane` (default: the lane beside the car's, the car's way, left
      first) changes into the car's lane at `at_time_s`, or once its rear is `at_gap_m` ahead
      of the car's front; the change takes `duration_s` and is forced (no safety check).
    - "lead_brake": a vehicle in the car's lane brakes at `decel_mps2` from `at_time_s` to
      `to_speed_mps`, and with `resume_after_s` drives on again that long after (stop-and-go);
      with `of_event` it is that earlier event's vehicle (a cut-in that then brakes) and brings
      none of its own.
    - "stopped": a vehicle standing on the `side` shoulder, `shoulder_gap_m` from the edge
      line to its side (negative: it stands that far into the lane).
    """

    kind: str = setting(doc="What happens.", choices=EVENT_KINDS)
    ahead_m: float = setting(40.0, "Where its vehicle starts: arc length ahead of the car's "
                             "start (negative = behind).", bounds=(-500.0, 2000.0))
    speed_mps: float | None = setting(None, "Its vehicle's speed and desired speed; default "
                                      "the car's target speed.", allowed="0..40 or absent")
    vehicle: str = setting("car", "Its vehicle's kind (size drawn from the seed).",
                           choices=VEHICLE_KINDS)
    lane: int | None = setting(None, "cut_in: the lane it comes from; default the lane beside "
                               "the car's that drives the car's way (left first).",
                               allowed="0..n_lanes - 1, not the car's, or absent")
    at_time_s: float | None = setting(None, "cut_in, lead_brake: when it starts.",
                                      allowed=">= 0 or absent")
    at_gap_m: float | None = setting(None, "cut_in: start once its rear is this far ahead of "
                                     "the car's front (when at_time_s is absent).",
                                     allowed="> 0 or absent")
    duration_s: float = setting(3.0, "cut_in: how long the lane change takes.",
                                bounds=(0.5, 10.0))
    decel_mps2: float = setting(4.0, "lead_brake: its deceleration.", bounds=(0.1, 10.0))
    to_speed_mps: float = setting(0.0, "lead_brake: the speed it brakes to.", bounds=(0.0, 40.0))
    resume_after_s: float | None = setting(None, "lead_brake: drives on at its speed this long "
                                           "after reaching to_speed_mps (stop-and-go).",
                                           allowed=">= 0 or absent")
    of_event: int | None = setting(None, "lead_brake: brake the vehicle of this earlier event "
                                   "(its index) instead of bringing one.",
                                   allowed="0..this event's index - 1, or absent")
    side: str = setting("right", "stopped: the shoulder it stands on.", choices=SIDES)
    shoulder_gap_m: float = setting(0.5, "stopped: from the edge line to its side; negative = "
                                    "into the lane.", bounds=(-2.0, 5.0))

    def __post_init__(self):
        check_settings(self)
        if self.speed_mps is not None and not 0.0 <= self.speed_mps <= 40.0:
            raise InvalidValue("speed_mps", f"must be in 0..40, got {self.speed_mps}")
        if self.at_time_s is not None and not self.at_time_s >= 0.0:
            raise InvalidValue("at_time_s", f"must be >= 0, got {self.at_time_s}")
        if self.at_gap_m is not None and not self.at_gap_m > 0.0:
            raise InvalidValue("at_gap_m", f"must be > 0, got {self.at_gap_m}")
        if self.resume_after_s is not None and not self.resume_after_s >= 0.0:
            raise InvalidValue("resume_after_s", f"must be >= 0, got {self.resume_after_s}")
        if self.kind == "cut_in" and (self.at_time_s is None) == (self.at_gap_m is None):
            raise InvalidValue("at_time_s", "a cut_in needs exactly one of at_time_s, at_gap_m")
        if self.kind == "lead_brake" and self.at_time_s is None:
            raise InvalidValue("at_time_s", "a lead_brake needs at_time_s")
        if self.of_event is not None and (self.kind != "lead_brake" or self.of_event < 0):
            raise InvalidValue("of_event", "only a lead_brake names an earlier event (>= 0)")


@dataclass(frozen=True)
class Traffic:
    """Seeded traffic and how all other vehicles drive; see the module docstring."""

    vehicles_per_km: float = setting(0.0, "Vehicles per km of road in each lane but the car's; 0 "
                                     "= no traffic.", bounds=(0.0, MAX_VEHICLES_PER_KM))
    lane_vehicles_per_km: tuple[float, ...] = setting(
        (), "Per lane, rightmost first, vehicles per km, the car's lane too (its vehicles keep "
        "clear_m from the car's start); empty = vehicles_per_km in each lane but the car's.",
        allowed=f"empty or one per lane, each 0..{MAX_VEHICLES_PER_KM:g}")
    directions: tuple[str, ...] = setting(
        (), "Per lane, rightmost first: traffic driving the car's way or towards it; empty = all "
        "the car's way.", allowed=f"each of {choices_text(DIRECTIONS)}; empty or one per lane")
    speed_mps: tuple[float, float] = setting((12.0, 18.0), "Range each lane's speed is drawn from.",
                                             allowed="[low, high], 0 <= low <= high <= 40")
    speed_spread_mps: float = setting(0.0, "Each vehicle's desired speed is its lane's speed plus "
                                      "a uniform draw in +- this (IDM only).", bounds=(0.0, 10.0))
    van_share: float = setting(0.2, "Share of vans among the vehicles.", bounds=(0.0, 1.0))
    truck_share: float = setting(0.15, "Share of trucks among the vehicles.", bounds=(0.0, 1.0),
                                 allowed="0..1, with vans at most 1")
    clear_m: float = setting(25.0, "No vehicle within this arc length of the car's start, in any "
                             "lane.", bounds=(0.0, 200.0))
    model: str = setting("idm", "How the other vehicles drive: \"idm\" follows the vehicle (or "
                         "the car) ahead by the Intelligent Driver Model and changes lanes by "
                         "MOBIL; \"constant\" drives each at its speed through everything.",
                         choices=MODELS)
    time_gap_s: tuple[float, float] = setting(
        (1.0, 2.0), "IDM: range each vehicle's desired time gap is drawn from.",
        allowed="[low, high], 0.3 <= low <= high <= 4")
    min_gap_m: float = setting(2.0, "IDM: bumper-to-bumper gap kept at standstill.",
                               bounds=(0.5, 10.0))
    max_accel_mps2: tuple[float, float] = setting(
        (0.8, 1.5), "IDM: range each vehicle's maximum acceleration is drawn from (trucks take "
        "half).", allowed="[low, high], 0.2 <= low <= high <= 4")
    comfort_decel_mps2: float = setting(2.0, "IDM: comfortable deceleration.", bounds=(0.5, 5.0))
    lane_changes: bool = setting(True, "MOBIL lane changes between lanes of one direction.")
    politeness: float = setting(0.3, "MOBIL's politeness p: 0 selfish (aggressive), 0.3 usual, 1 "
                                "altruistic.", bounds=(0.0, 1.0))
    safe_decel_mps2: float = setting(4.0, "MOBIL: a change may make the new follower brake at "
                                     "most this hard.", bounds=(1.0, 9.0))
    events: tuple[TrafficEventSpec, ...] = setting((), "Scripted events (each brings its own "
                                                   "vehicle); see TrafficEventSpec.")

    def __post_init__(self):
        check_settings(self)
        for i, d in enumerate(self.directions):
            if d not in DIRECTIONS:
                raise InvalidValue(f"directions[{i}]", f"must be one of {DIRECTIONS}, got {d!r}")
        _check_range(self.speed_mps, "speed_mps", 0.0, 40.0)
        _check_range(self.time_gap_s, "time_gap_s", 0.3, 4.0)
        _check_range(self.max_accel_mps2, "max_accel_mps2", 0.2, 4.0)
        for i, d in enumerate(self.lane_vehicles_per_km):
            if not 0.0 <= d <= MAX_VEHICLES_PER_KM:
                raise InvalidValue(f"lane_vehicles_per_km[{i}]",
                                   f"must be in 0..{MAX_VEHICLES_PER_KM:g}, got {d}")
        if self.van_share + self.truck_share > 1.0:
            raise InvalidValue("truck_share", "van_share + truck_share must be at most 1")
        for i, event in enumerate(self.events):
            if event.of_event is not None and not event.of_event < i:
                raise InvalidValue(f"events[{i}].of_event",
                                   f"must name an earlier event (0..{i - 1}), got {event.of_event}")
            if event.of_event is not None and self.events[event.of_event].of_event is not None:
                raise InvalidValue(f"events[{i}].of_event",
                                   "must name an event that brings its own vehicle")

    def direction(self, lane: int) -> str:
        """"same" or "oncoming" for a lane (all "same" when `directions` is empty)."""
        return self.directions[lane] if self.directions else "same"

    def density(self, lane: int, ego_lane: int) -> float:
        """Vehicles per km drawn in a lane."""
        if self.lane_vehicles_per_km:
            return self.lane_vehicles_per_km[lane]
        return 0.0 if lane == ego_lane else self.vehicles_per_km


def _check_range(pair: tuple[float, ...], key: str, low: float, high: float) -> None:
    lo, hi = (tuple(pair) + (math.nan, math.nan))[:2]
    if len(pair) != 2 or not low <= lo <= hi <= high:
        raise InvalidValue(key, f"must be [low, high] with {low:g} <= low <= high <= {high:g}, "
                                f"got {list(pair)}")
