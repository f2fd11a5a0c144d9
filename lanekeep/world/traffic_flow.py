"""A scenario's `[traffic]` table (lanekeep/scenario/traffic.py) as vehicles: cars, vans and trucks
of real sizes and colours in the lanes beside the car's, drawn from the scenario seed and a key
of its name (lanekeep/scenario/streams.py), so two scenarios on one seed meet other traffic.

Why one speed per lane: the vehicles are driven kinematically (lanekeep/world/traffic.py moves
each at a constant speed along its lane), so vehicles of one lane at two speeds would drive
through each other. A lane that already holds listed vehicles (`[[conditions.vehicles]]`)
takes the first one's speed and keeps the drawn ones clear of them. No vehicle is drawn in the
car's own lane, nor within `clear_m` of its start in any lane, and each stays inside its own
lane (its offset leaves 0.3 m to the lines), so no drawn vehicle stands on the ego lane's lines.
"""

from __future__ import annotations

import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.scenario.conditions import VehicleSpec
from lanekeep.scenario.schema import Scenario
from lanekeep.scenario.streams import stream_entropy

TRAFFIC_STREAM = 0x7AF1C  # the traffic's own generator: stream_entropy(scenario, this)
SPAN_BEYOND_M = 60.0  # vehicles are drawn this far beyond both ends of an open road
MIN_GAP_M = 8.0  # bumper to bumper, plus one second at the lane's speed
LINE_CLEARANCE_M = 0.3  # from a vehicle's side to its lane's lines, at least
# (length, width, height) ranges in metres, per kind
SIZES = {"car": ((4.1, 4.9), (1.72, 1.9), (1.4, 1.6)),
         "van": ((4.9, 5.9), (1.9, 2.05), (1.95, 2.5)),
         "truck": ((9.0, 16.5), (2.45, 2.55), (3.3, 4.0))}
# Body colours in the proportions of the cars on European and American roads (white, black,
# greys and silver are about three quarters), as (RGB, weight).
PALETTE = (((0.88, 0.88, 0.87), 0.24), ((0.04, 0.04, 0.05), 0.2), ((0.35, 0.36, 0.38), 0.16),
           ((0.62, 0.63, 0.65), 0.13), ((0.08, 0.16, 0.38), 0.09), ((0.5, 0.06, 0.05), 0.08),
           ((0.18, 0.26, 0.2), 0.03), ((0.45, 0.38, 0.28), 0.04), ((0.8, 0.55, 0.1), 0.03))


def traffic_vehicles(scenario: Scenario, road: Road) -> tuple[VehicleSpec, ...]:
    """The vehicles of the scenario's `[traffic]` table (none when its density is 0).

    Raises:
      ValueError: `traffic.directions` names a number of lanes other than the road's.
    """
    cfg = scenario.traffic
    if cfg.directions and len(cfg.directions) != road.n_lanes:
        raise ValueError(f"traffic.directions: need one per lane ({road.n_lanes}), "
                         f"got {len(cfg.directions)}")
    if cfg.vehicles_per_km <= 0.0:
        return ()
    rng = np.random.default_rng(stream_entropy(scenario, TRAFFIC_STREAM))
    s0, s1 = (0.0, road.length_m) if road.closed else (-SPAN_BEYOND_M,
                                                        road.length_m + SPAN_BEYOND_M)
    ego_s = scenario.start.s_m
    out: list[VehicleSpec] = []
    for lane in range(road.n_lanes):
        if lane == scenario.road.ego_lane:
            continue
        listed = [v for v in scenario.conditions.vehicles if v.lane == lane]
        sign = -1.0 if cfg.direction(lane) == "oncoming" else 1.0
        speed = listed[0].speed_mps if listed else sign * float(rng.uniform(*cfg.speed_mps))
        taken = [(v.s_m, 0.5 * v.length_m) for v in listed]
        n = int(rng.poisson(cfg.vehicles_per_km * (s1 - s0) / 1000.0))
        for s in np.sort(rng.uniform(s0, s1, n)):
            v = _vehicle(rng, road, lane, float(s), speed, cfg.van_share, cfg.truck_share)
            half = 0.5 * v.length_m
            gap = MIN_GAP_M + abs(speed) * 1.0
            if abs(v.s_m - ego_s) < cfg.clear_m + half:
                continue
            if any(abs(v.s_m - s) < h + half + gap for s, h in taken):
                continue
            taken.append((v.s_m, half))
            out.append(v)
    return tuple(out)


def _vehicle(rng: np.random.Generator, road: Road, lane: int, s: float, speed: float,
             van_share: float, truck_share: float) -> VehicleSpec:
    """One vehicle: its kind, size within the kind's range, colour and place in its lane."""
    u = rng.random()
    kind = "truck" if u < truck_share else "van" if u < truck_share + van_share else "car"
    length, width, height = (float(rng.uniform(*r)) for r in SIZES[kind])
    weights = np.array([w for _, w in PALETTE])
    rgb = np.array(PALETTE[int(rng.choice(len(PALETTE), p=weights / weights.sum()))][0])
    colour = np.clip(rgb * rng.uniform(0.85, 1.15) + rng.normal(0.0, 0.02, 3), 0.0, 1.0)
    if kind == "truck" and rng.random() < 0.6:  # most trailers are white or light grey
        colour = np.full(3, rng.uniform(0.75, 0.92))
    slack = max(0.0, 0.5 * (road.lane_width_m - width) - LINE_CLEARANCE_M)
    return VehicleSpec(lane=lane, s_m=s, speed_mps=speed,
                       offset_m=float(rng.uniform(-1.0, 1.0) * min(0.25, slack)),
                       length_m=length, width_m=width, height_m=height,
                       colour=tuple(float(c) for c in colour))
