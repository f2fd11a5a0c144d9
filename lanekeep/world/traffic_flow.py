"""A scenario's other vehicles as a plan: what each looks like and where it starts (the
`VehicleSpec`s the world builds), how each drives (IDM and MOBIL figures, lanekeep/traffic/),
and the scripted events. Drawn from the scenario seed and a key of its name
(lanekeep/scenario/streams.py), so two scenarios on one seed meet other traffic.

Three sources, in this order (a vehicle's index names its body, `cond_vehicle_<i>`):
  1. `[[conditions.vehicles]]`, as listed; they keep their lane (no MOBIL: an author placed
     them), but follow the vehicle ahead.
  2. `[traffic]`'s drawn vehicles, lane by lane: cars, vans and trucks of real sizes and
     colours. No vehicle within `clear_m` of the car's start in any lane, each inside its lane
     (its offset leaves 0.3 m to the lines), none on the car's lane unless
     `lane_vehicles_per_km` asks for it.
  3. One vehicle per `[[traffic.events]]` entry (a cut-in, a braking lead, a stopped car).

The draws of sources 1-2 (places, kinds, sizes, colours, lane speeds) are those the traffic
drew before it was reactive (one stream, one order); each vehicle's IDM figures and the events'
vehicles come from streams of their own, so adding them moved no vehicle.

Why a lane's vehicles share one speed: the draw predates IDM, and a lane's drawn speed is
still its vehicles' desired speed (plus `speed_spread_mps`). A lane that already holds listed
vehicles takes the first one's speed and keeps the drawn ones clear of them. MOBIL never
changes a vehicle into the car's lane (a car without adaptive cruise could not follow it):
vehicles come into that lane only by a scripted cut-in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.scenario.conditions import VehicleSpec
from lanekeep.scenario.schema import Scenario
from lanekeep.scenario.streams import stream_entropy
from lanekeep.scenario.traffic import Traffic, TrafficEventSpec
from lanekeep.traffic.events import CutIn, LeadBrake, TrafficEvent
from lanekeep.traffic.idm import IdmParams
from lanekeep.traffic.mobil import MobilParams
from lanekeep.traffic.state import VehicleSetup

TRAFFIC_STREAM = 0x7AF1C  # the drawn vehicles: stream_entropy(scenario, this)
DRIVING_STREAM = 0x1D3A  # each vehicle's IDM figures, in vehicle order
EVENT_STREAM = 0xE7E47  # the events' vehicles (kind sizes, colours)
SPAN_BEYOND_M = 60.0  # vehicles are drawn this far beyond both ends of an open road
MIN_GAP_M = 8.0  # bumper to bumper, plus one second at the lane's speed
LINE_CLEARANCE_M = 0.3  # from a vehicle's side to its lane's lines, at least
TRUCK_ACCEL_SHARE = 0.5  # a loaded truck accelerates at about half a car's rate
# (length, width, height) ranges in metres, per kind
SIZES = {"car": ((4.1, 4.9), (1.72, 1.9), (1.4, 1.6)),
         "van": ((4.9, 5.9), (1.9, 2.05), (1.95, 2.5)),
         "truck": ((9.0, 16.5), (2.45, 2.55), (3.3, 4.0))}
# Body colours in the proportions of the cars on European and American roads (white, black,
# greys and silver are about three quarters), as (RGB, weight).
PALETTE = (((0.88, 0.88, 0.87), 0.24), ((0.04, 0.04, 0.05), 0.2), ((0.35, 0.36, 0.38), 0.16),
           ((0.62, 0.63, 0.65), 0.13), ((0.08, 0.16, 0.38), 0.09), ((0.5, 0.06, 0.05), 0.08),
           ((0.18, 0.26, 0.2), 0.03), ((0.45, 0.38, 0.28), 0.04), ((0.8, 0.55, 0.1), 0.03))


@dataclass(frozen=True)
class TrafficPlan:
    """Every other vehicle (in body-index order) with how it drives, and the events."""

    vehicles: tuple[VehicleSpec, ...]
    setups: tuple[VehicleSetup, ...]
    events: tuple[TrafficEvent, ...]
    lane_directions: tuple[int, ...]  # +1 the car's way, -1 oncoming, per lane
    model: str  # Traffic.model
    ego_lane: int  # the car's lane: MOBIL never changes into it


def vehicle_name(index: int) -> str:
    """The mocap body of vehicle `index` (lanekeep/world/traffic.py builds it)."""
    return f"cond_vehicle_{index}"


def traffic_plan(scenario: Scenario, road: Road) -> TrafficPlan:
    """The scenario's other vehicles and how they drive.

    Raises:
      ValueError: a lane count or lane index that does not fit the road, or a listed vehicle
        driving against its lane's direction (each names the key).
    """
    cfg = scenario.traffic
    directions = lane_directions(scenario, road)
    listed = scenario.conditions.vehicles
    drawn = drawn_vehicles(scenario, road)
    own = [i for i, e in enumerate(cfg.events) if e.of_event is None]  # bring a vehicle
    events = tuple(_event_vehicle(scenario, road, cfg.events[i], i, directions) for i in own)
    vehicles = listed + drawn + tuple(v for v, _ in events)
    rng = np.random.default_rng(stream_entropy(scenario, DRIVING_STREAM))
    setups = []
    for i, v in enumerate(vehicles):
        source = "listed" if i < len(listed) else "drawn" if i < len(listed) + len(drawn) \
            else "event"
        setups.append(_setup(cfg, v, i, source, rng, road, directions[v.lane]))
    first = len(listed) + len(drawn)
    name_of = {i: vehicle_name(first + k) for k, i in enumerate(own)}  # event -> its vehicle
    flow_events = tuple(
        _flow_event(spec, name_of[i if spec.of_event is None else spec.of_event], road, scenario)
        for i, spec in enumerate(cfg.events) if spec.kind != "stopped")
    return TrafficPlan(vehicles, tuple(setups), flow_events, directions, cfg.model,
                       scenario.road.ego_lane)


def lane_directions(scenario: Scenario, road: Road) -> tuple[int, ...]:
    """+1 or -1 per lane: `traffic.directions` where given, else the sign of the first listed
    vehicle's speed in the lane, else +1; a listed vehicle against its lane raises."""
    cfg = scenario.traffic
    if cfg.directions and len(cfg.directions) != road.n_lanes:
        raise ValueError(f"traffic.directions: need one per lane ({road.n_lanes}), "
                         f"got {len(cfg.directions)}")
    if cfg.lane_vehicles_per_km and len(cfg.lane_vehicles_per_km) != road.n_lanes:
        raise ValueError(f"traffic.lane_vehicles_per_km: need one per lane ({road.n_lanes}), "
                         f"got {len(cfg.lane_vehicles_per_km)}")
    for i, v in enumerate(scenario.conditions.vehicles):
        if not 0 <= v.lane < road.n_lanes:  # the message the world's builder gives
            raise ValueError(f"conditions.vehicles[{i}].lane = {v.lane} not in "
                             f"0..{road.n_lanes - 1}")
    out = []
    for lane in range(road.n_lanes):
        listed = [v for v in scenario.conditions.vehicles if v.lane == lane and v.speed_mps]
        if cfg.directions:
            out.append(-1 if cfg.direction(lane) == "oncoming" else 1)
        else:
            out.append(-1 if listed and listed[0].speed_mps < 0 else 1)
    for i, v in enumerate(scenario.conditions.vehicles):
        if v.speed_mps * out[v.lane] < 0:
            raise ValueError(f"conditions.vehicles[{i}]: drives against lane {v.lane}'s "
                             f"direction (its speed's sign must match the lane's traffic)")
    return tuple(out)


def drawn_vehicles(scenario: Scenario, road: Road) -> tuple[VehicleSpec, ...]:
    """The vehicles of the scenario's `[traffic]` table (none when no lane has a density)."""
    cfg = scenario.traffic
    ego_lane = scenario.road.ego_lane
    if all(cfg.density(lane, ego_lane) <= 0.0 for lane in range(road.n_lanes)):
        return ()
    rng = np.random.default_rng(stream_entropy(scenario, TRAFFIC_STREAM))
    s0, s1 = (0.0, road.length_m) if road.closed else (-SPAN_BEYOND_M,
                                                        road.length_m + SPAN_BEYOND_M)
    ego_s = scenario.start.s_m
    out: list[VehicleSpec] = []
    for lane in range(road.n_lanes):
        density = cfg.density(lane, ego_lane)
        if density <= 0.0:
            continue
        listed = [v for v in scenario.conditions.vehicles if v.lane == lane]
        sign = -1.0 if cfg.direction(lane) == "oncoming" else 1.0
        speed = listed[0].speed_mps if listed else sign * float(rng.uniform(*cfg.speed_mps))
        taken = [(v.s_m, 0.5 * v.length_m) for v in listed]
        n = int(rng.poisson(density * (s1 - s0) / 1000.0))
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
             van_share: float, truck_share: float, kind: str | None = None,
             centred: bool = False) -> VehicleSpec:
    """One vehicle: its kind, size within the kind's range, colour and place in its lane."""
    u = rng.random()
    if kind is None:
        kind = "truck" if u < truck_share else "van" if u < truck_share + van_share else "car"
    length, width, height = (float(rng.uniform(*r)) for r in SIZES[kind])
    weights = np.array([w for _, w in PALETTE])
    rgb = np.array(PALETTE[int(rng.choice(len(PALETTE), p=weights / weights.sum()))][0])
    colour = np.clip(rgb * rng.uniform(0.85, 1.15) + rng.normal(0.0, 0.02, 3), 0.0, 1.0)
    if kind == "truck" and rng.random() < 0.6:  # most trailers are white or light grey
        colour = np.full(3, rng.uniform(0.75, 0.92))
    slack = max(0.0, 0.5 * (road.lane_width_m - width) - LINE_CLEARANCE_M)
    offset = float(rng.uniform(-1.0, 1.0) * min(0.25, slack))
    return VehicleSpec(lane=lane, s_m=s, speed_mps=speed, offset_m=0.0 if centred else offset,
                       length_m=length, width_m=width, height_m=height,
                       colour=tuple(float(c) for c in colour))


def _event_vehicle(scenario: Scenario, road: Road, spec: TrafficEventSpec, index: int,
                   directions: tuple[int, ...]) -> tuple[VehicleSpec, TrafficEventSpec]:
    """The vehicle an event brings, at its start (its look from the event stream)."""
    key = f"traffic.events[{index}]"
    ego = scenario.road.ego_lane
    rng = np.random.default_rng(stream_entropy(scenario, EVENT_STREAM, index))
    speed = scenario.target_speed_mps if spec.speed_mps is None else spec.speed_mps
    s = scenario.start.s_m + spec.ahead_m
    if road.closed:
        s %= road.length_m
    if spec.kind == "cut_in":
        lane = spec.lane if spec.lane is not None else _beside(ego, directions, road.n_lanes, key)
        if not 0 <= lane < road.n_lanes or lane == ego:
            raise ValueError(f"{key}.lane = {lane}: must be a lane of 0..{road.n_lanes - 1} "
                             f"other than the car's ({ego})")
        if directions[lane] != directions[ego]:
            raise ValueError(f"{key}.lane = {lane} drives the other way: a cut-in comes from a "
                             f"lane of the car's direction")
        return _vehicle(rng, road, lane, s, speed, 0.0, 0.0, spec.vehicle, centred=True), spec
    if spec.kind == "lead_brake":
        return _vehicle(rng, road, ego, s, speed, 0.0, 0.0, spec.vehicle, centred=True), spec
    # stopped: on a shoulder, its side `shoulder_gap_m` beyond the edge line
    v = _vehicle(rng, road, 0, s, 0.0, 0.0, 0.0, spec.vehicle, centred=True)
    half = 0.5 * v.width_m
    if spec.side == "right":
        lane, r = 0, road.boundary_r(0) - spec.shoulder_gap_m - half
    else:
        lane, r = road.n_lanes - 1, road.boundary_r(road.n_lanes) + spec.shoulder_gap_m + half
    return VehicleSpec(lane=lane, s_m=v.s_m, speed_mps=0.0,
                       offset_m=r - road.lane_center_r(lane), length_m=v.length_m,
                       width_m=v.width_m, height_m=v.height_m, colour=v.colour), spec


def _beside(ego: int, directions: tuple[int, ...], n_lanes: int, key: str) -> int:
    for lane in (ego + 1, ego - 1):
        if 0 <= lane < n_lanes and directions[lane] == directions[ego]:
            return lane
    raise ValueError(f"{key}: no lane beside the car's drives its way; give `lane`")


def _setup(cfg: Traffic, v: VehicleSpec, index: int, source: str, rng: np.random.Generator,
           road: Road, lane_direction: int) -> VehicleSetup:
    """How vehicle `index` drives. Four draws per vehicle, always (its desired-speed spread,
    time gap, acceleration, and one spare), so that one vehicle's figures shift no other's."""
    spread, gap_u, accel_u, _ = rng.random(4)
    speed = abs(v.speed_mps)
    parked = source == "event" and v.speed_mps == 0.0 and not _in_a_lane(v, road)
    desired = speed
    if source == "drawn":
        desired = max(0.0, speed + (2.0 * spread - 1.0) * cfg.speed_spread_mps)
    accel = cfg.max_accel_mps2[0] + accel_u * (cfg.max_accel_mps2[1] - cfg.max_accel_mps2[0])
    if v.length_m > 8.0:  # a truck
        accel *= TRUCK_ACCEL_SHARE
    idm = IdmParams(desired_speed_mps=desired,
                    time_gap_s=cfg.time_gap_s[0] + gap_u * (cfg.time_gap_s[1] - cfg.time_gap_s[0]),
                    min_gap_m=cfg.min_gap_m, max_accel_mps2=accel,
                    comfort_decel_mps2=cfg.comfort_decel_mps2)
    mobil = None
    if source == "drawn" and cfg.lane_changes:
        mobil = MobilParams(politeness=cfg.politeness, safe_decel_mps2=cfg.safe_decel_mps2)
    r = road.lane_center_r(v.lane) + v.offset_m
    return VehicleSetup(name=vehicle_name(index), lane=v.lane, s_m=v.s_m, speed_mps=speed,
                        direction=lane_direction, offset_m=v.offset_m,
                        length_m=v.length_m, width_m=v.width_m, idm=idm, mobil=mobil,
                        parked=parked, r_m=r if parked else None)


def _in_a_lane(v: VehicleSpec, road: Road) -> bool:
    """Whether a vehicle's side reaches into the carriageway by more than 0.3 m."""
    r = road.lane_center_r(v.lane) + v.offset_m
    half = 0.5 * v.width_m
    return r + half > road.boundary_r(0) + 0.3 and r - half < road.boundary_r(road.n_lanes) - 0.3


def _flow_event(spec: TrafficEventSpec, name: str, road: Road, scenario: Scenario
                ) -> TrafficEvent:
    if spec.kind == "cut_in":
        return CutIn(vehicle=name, to_lane=scenario.road.ego_lane, at_time_s=spec.at_time_s,
                     at_gap_m=spec.at_gap_m, duration_s=spec.duration_s)
    return LeadBrake(vehicle=name, at_time_s=float(spec.at_time_s), decel_mps2=spec.decel_mps2,
                     to_speed_mps=spec.to_speed_mps, resume_after_s=spec.resume_after_s)


def traffic_vehicles(scenario: Scenario, road: Road) -> tuple[VehicleSpec, ...]:
    """The vehicles `[traffic]` adds beyond the listed ones: drawn, then the events' (kept for
    callers that only need the look: the eval sets and the datasets)."""
    plan = traffic_plan(scenario, road)
    return plan.vehicles[len(scenario.conditions.vehicles):]

