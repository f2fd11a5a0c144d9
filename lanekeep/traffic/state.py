"""The traffic's shared types: what a vehicle is set up as, where it is at a step, and the car
(ego) as the traffic sees it. Frenet coordinates of the road (lanekeep/geometry/road.py): s is
arc length along the road, r the lateral offset (+ = left) of the vehicle's centre."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from lanekeep.traffic.idm import IdmParams
from lanekeep.traffic.mobil import MobilParams


@dataclass(frozen=True)
class VehicleSetup:
    """One other vehicle at t = 0 and how it drives.

    `direction` +1 drives towards increasing s, -1 is oncoming (towards decreasing s);
    `speed_mps` is its initial speed (>= 0) along its direction; `idm.desired_speed_mps` the
    speed it wants. `mobil` None: it never changes lane by itself (scripted cut-ins still
    move it). `parked`: it stands where it is (a vehicle stopped on the shoulder): no IDM, no
    lane change, never a follower; a leader (a standing obstacle the lane's traffic stops
    behind) only in a lane its body overlaps by more than 0.3 m (lanekeep/traffic/flow.py).
    """

    name: str
    lane: int
    s_m: float
    speed_mps: float
    direction: int = 1
    offset_m: float = 0.0  # from its lane's centre, + = left
    length_m: float = 4.6
    width_m: float = 1.85
    idm: IdmParams = field(default_factory=IdmParams)
    mobil: MobilParams | None = None
    parked: bool = False
    r_m: float | None = None  # parked vehicles: their lateral place (None: the lane's centre)


@dataclass(frozen=True)
class VehicleState:
    """One vehicle at one instant (a snapshot; the flow keeps its own mutable state)."""

    name: str
    s_m: float  # centre; on a closed road in [0, length)
    r_m: float  # centre, + = left
    speed_mps: float  # >= 0, along its direction of travel
    direction: int  # +1 along s, -1 oncoming
    lane: int  # its lane (the target lane while it changes); -1 parked off the lanes
    length_m: float
    width_m: float
    accel_mps2: float = 0.0  # along its direction of travel, over the last step (0 standing)
    lateral_speed_mps: float = 0.0  # dr/dt
    changing_lane: bool = False

    @property
    def heading_offset_rad(self) -> float:
        """Yaw relative to the road's tangent at s for its direction of travel (a lane
        change's angle, atan2(dr/dt, ds/dt) in its own frame)."""
        if self.speed_mps <= 0.0:
            return 0.0
        return math.atan2(self.direction * self.lateral_speed_mps, self.speed_mps)


@dataclass(frozen=True)
class EgoState:
    """The car as the traffic sees it: the others follow it, let it in or cut in front of
    it, but the flow never moves it (its physics does)."""

    s_m: float
    r_m: float
    speed_mps: float
    length_m: float
    width_m: float
