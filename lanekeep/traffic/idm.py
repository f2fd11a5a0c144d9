"""The Intelligent Driver Model (IDM): one vehicle's acceleration from its speed, the gap to the
one ahead and how fast it closes that gap.

Treiber, Hennecke and Helbing (2000), "Congested traffic states in empirical observations and
microscopic simulations", Phys. Rev. E 62, 1805; Treiber and Kesting (2013), "Traffic Flow
Dynamics", Springer, chapter 11:

    dv/dt = a [1 - (v / v0)^delta - (s*(v, dv) / s)^2]
    s*(v, dv) = s0 + max(0, v T + v dv / (2 sqrt(a b)))

with s the bumper-to-bumper gap and dv = v - v_lead the approach rate. The first term is the
free road (accelerate towards v0, gently near it), the second the interaction (keep the
desired gap s*, which grows with speed and with the closing rate; its dv term brakes
"intelligently": just enough to stop behind a slower leader at about b).

Pure scalar functions: the traffic flow (lanekeep/traffic/flow.py) calls them once a vehicle
a step, and the car's adaptive cruise uses the same law on its radar's readings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

# The floor of every acceleration here: about 0.9 g, what a car's tyres give on dry asphalt.
# The IDM itself is unbounded when the gap closes fast (s*/s grows without limit); a real car
# cannot brake harder, and a bound keeps a step of the flow finite whatever the input.
MAX_DECEL_MPS2 = 9.0


@dataclass(frozen=True)
class IdmParams:
    """One driver's IDM parameters. Typical values (Treiber and Kesting 2013, Table 11.2):
    highway v0 = 120 km/h, T = 1.0-1.5 s, s0 = 2 m, a = 1.0 m/s^2, b = 1.5 m/s^2; city traffic
    v0 = 54 km/h, T = 1.0 s, s0 = 2 m, a = 1.0 m/s^2, b = 1.5 m/s^2."""

    # v0: the speed it drives at on a free road (30 m/s = 108 km/h). 0 = it wants to stand: it
    # brakes at b to a stop and stays (the free-road term (v/v0)^delta has no limit there).
    desired_speed_mps: float = 30.0
    # T: the time gap it keeps to its leader in steady traffic (1.5 s; 1.0 s is a tight driver).
    time_gap_s: float = 1.5
    # s0: the bumper-to-bumper gap it keeps when standing in a queue.
    min_gap_m: float = 2.0
    # a: its maximum acceleration, reached from standstill on a free road.
    max_accel_mps2: float = 1.0
    # b: its comfortable deceleration; it may brake harder when it must (up to MAX_DECEL_MPS2).
    comfort_decel_mps2: float = 1.5
    # delta: how abruptly it stops accelerating near v0 (4: the source's choice; 1 = linear).
    delta: float = 4.0

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if not math.isfinite(value):
                raise ValueError(f"IdmParams.{f.name} must be finite, got {value}")
            low_ok = value >= 0.0 if f.name == "desired_speed_mps" else value > 0.0
            if not low_ok:
                bound = ">= 0" if f.name == "desired_speed_mps" else "> 0"
                raise ValueError(f"IdmParams.{f.name} must be {bound}, got {value}")


def desired_gap(p: IdmParams, v: float, dv: float) -> float:
    """s*: the gap the driver wants at speed `v` (m/s) while closing on its leader at `dv` =
    v - v_lead (m/s; negative when the leader pulls away). Never below s0."""
    # s* = s0 + max(0, v T + v dv / (2 sqrt(a b)))
    braking = v * dv / (2.0 * math.sqrt(p.max_accel_mps2 * p.comfort_decel_mps2))
    return p.min_gap_m + max(0.0, v * p.time_gap_s + braking)


def free_road_acceleration(p: IdmParams, v: float) -> float:
    """The acceleration with nobody ahead: a at standstill, 0 at v0, negative above it."""
    if p.desired_speed_mps == 0.0:  # it wants to stand: brake comfortably, then hold
        return -p.comfort_decel_mps2 if v > 0.0 else 0.0
    # a [1 - (v / v0)^delta]
    return max(-MAX_DECEL_MPS2,
               p.max_accel_mps2 * (1.0 - (v / p.desired_speed_mps) ** p.delta))


def idm_acceleration(p: IdmParams, v: float, gap_m: float = math.inf,
                     lead_speed_mps: float | None = None) -> float:
    """The IDM acceleration (m/s^2) at speed `v` (m/s) behind a leader `gap_m` metres ahead
    (bumper to bumper) driving at `lead_speed_mps` along the same direction.

    gap_m = inf is a free road; lead_speed_mps None with a finite gap is a standing obstacle
    (speed 0). A gap <= 0 (the two overlap) gives the floor, -MAX_DECEL_MPS2; every result is
    clamped to that floor, so the answer is always finite. With v0 = 0 the free-road term is
    -b while moving and 0 at rest, and the result is the lower of it and the interaction
    a [1 - (s*/s)^2]: it stops, and no gap makes it start again.
    """
    free = free_road_acceleration(p, v)
    if math.isinf(gap_m):
        return free
    if gap_m <= 0.0:
        return -MAX_DECEL_MPS2
    lead = 0.0 if lead_speed_mps is None else lead_speed_mps
    # -a (s* / s)^2
    interaction = -p.max_accel_mps2 * (desired_gap(p, v, v - lead) / gap_m) ** 2
    if p.desired_speed_mps == 0.0:
        acc = min(free, p.max_accel_mps2 + interaction)
    else:
        acc = free + interaction
    return max(-MAX_DECEL_MPS2, acc)
