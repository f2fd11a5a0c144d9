"""The `[traffic]` table of a scenario: other vehicles drawn from the seed, in the lanes beside
the car's (never in its own), as real roads have them (a TuSimple frame shows 5-10 vehicles).

Off by default (`vehicles_per_km = 0`), so a scenario without the table keeps only the vehicles
it lists under `[[conditions.vehicles]]`. lanekeep/world/traffic_flow.py turns the table into
such vehicles; every draw (places, speeds, kinds, sizes, colours) comes from the scenario
seed, so a seed reproduces its traffic.

    [traffic]
    vehicles_per_km = 20.0                 # per lane, each lane but the car's
    directions = ["same", "oncoming"]      # per lane, rightmost first; [] = all "same"
    speed_mps = [12.0, 18.0]               # each lane's speed is drawn from this range
    clear_m = 25.0                         # no vehicle this near the car's start, any lane
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, choices_text, setting

DIRECTIONS = ("same", "oncoming")
MAX_VEHICLES_PER_KM = 60.0  # per lane: 17 m from front to front, bumper to bumper in a jam


@dataclass(frozen=True)
class Traffic:
    """Seeded traffic in the lanes beside the car's; see the module docstring for the keys."""

    vehicles_per_km: float = setting(0.0, "Vehicles per km of road in each lane but the car's; 0 "
                                     "= no traffic.", bounds=(0.0, MAX_VEHICLES_PER_KM))
    directions: tuple[str, ...] = setting(
        (), "Per lane, rightmost first: traffic driving the car's way or towards it; empty = all "
        "the car's way.", allowed=f"each of {choices_text(DIRECTIONS)}; empty or one per lane")
    speed_mps: tuple[float, float] = setting((12.0, 18.0), "Range each lane's speed is drawn from "
                                             "(one speed per lane, so vehicles keep their gaps).",
                                             allowed="[low, high], 0 <= low <= high <= 40")
    van_share: float = setting(0.2, "Share of vans among the vehicles.", bounds=(0.0, 1.0))
    truck_share: float = setting(0.15, "Share of trucks among the vehicles.", bounds=(0.0, 1.0),
                                 allowed="0..1, with vans at most 1")
    clear_m: float = setting(25.0, "No vehicle within this arc length of the car's start, in any "
                             "lane.", bounds=(0.0, 200.0))

    def __post_init__(self):
        check_settings(self)
        for i, d in enumerate(self.directions):
            if d not in DIRECTIONS:
                raise InvalidValue(f"directions[{i}]", f"must be one of {DIRECTIONS}, got {d!r}")
        lo, hi = (self.speed_mps + (math.nan, math.nan))[:2]
        if len(self.speed_mps) != 2 or not 0.0 <= lo <= hi <= 40.0:
            raise InvalidValue("speed_mps",
                               f"must be [low, high] with 0 <= low <= high <= 40, "
                               f"got {list(self.speed_mps)}")
        if self.van_share + self.truck_share > 1.0:
            raise InvalidValue("truck_share", "van_share + truck_share must be at most 1")

    def direction(self, lane: int) -> str:
        """"same" or "oncoming" for a lane (all "same" when `directions` is empty)."""
        return self.directions[lane] if self.directions else "same"
