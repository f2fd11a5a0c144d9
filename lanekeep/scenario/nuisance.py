"""What a seed draws besides the noise: the start and the traffic's timing.

Why: a bench over seeds should sample drives, not replay one drive with other pixel noise.
The file's own seed (`Scenario.nominal_seed`; 0 for a scenario built in memory) is the nominal
drive, exactly as the file says; any other seed draws, from its own stream
`stream_entropy(scenario, NUISANCE_STREAM)` (the seed and a key of the scenario's name:
lanekeep/scenario/streams.py; its own tag, so it shifts no other draw):
  - the start's lateral offset, heading and speed (start and target speed move together),
    uniform within the file's `[start.jitter]` half-widths;
  - each other vehicle's timing: when the car meets it moves by a draw in +-`traffic_s`,
    i.e. the vehicle moves along its lane by its speed relative to the car's target speed
    times that draw (a lead car at the car's speed keeps its gap; oncoming traffic moves
    most); a vehicle in the car's own lane, its way, also takes the drawn speed change.
The seed also draws, as before, the sensor noise, the image effects and weather particles
(lanekeep/loop/episode.py's generator, which folds in the name too) and the world's details
(textures, props, shadow casters: lanekeep/world/, from the seed alone).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from lanekeep.scenario.schema import Scenario
from lanekeep.scenario.streams import stream_entropy

NUISANCE_STREAM = 0x5EED


def is_nominal(scenario: Scenario) -> bool:
    """Whether `scenario` runs its file's own drive: its seed is the file's (0 in memory)."""
    nominal = 0 if scenario.nominal_seed is None else scenario.nominal_seed
    return scenario.seed == nominal


def with_nuisance(scenario: Scenario) -> Scenario:
    """`scenario` with its seed's start and traffic timing (unchanged for the nominal seed)."""
    if is_nominal(scenario):
        return scenario
    jitter = scenario.start.jitter
    rng = np.random.default_rng(stream_entropy(scenario, NUISANCE_STREAM))
    d_offset, d_heading, d_speed = rng.uniform(-1.0, 1.0, 3) * (
        jitter.offset_m, jitter.heading_deg, jitter.speed_mps)
    shifts = rng.uniform(-1.0, 1.0, len(scenario.conditions.vehicles)) * jitter.traffic_s
    start = scenario.start
    start = dataclasses.replace(
        start, offset_m=start.offset_m + float(d_offset),
        heading_deg=start.heading_deg + float(d_heading),
        speed_mps=max(0.0, start.speed_mps + float(d_speed)) if start.speed_mps > 0
        else start.speed_mps)
    ego = scenario.target_speed_mps  # the file's: timing is when the car meets a vehicle
    lane = scenario.road.ego_lane
    vehicles = tuple(dataclasses.replace(
        v, s_m=v.s_m + (v.speed_mps - ego) * float(dt),
        speed_mps=v.speed_mps + (float(d_speed) if _ahead_in_lane(v, lane) else 0.0))
        for v, dt in zip(scenario.conditions.vehicles, shifts, strict=True))
    return dataclasses.replace(
        scenario, start=start,
        target_speed_mps=max(0.0, scenario.target_speed_mps + float(d_speed)),
        conditions=dataclasses.replace(scenario.conditions, vehicles=vehicles))


def _ahead_in_lane(vehicle, lane: int) -> bool:
    """Whether a vehicle drives in the car's own lane, its way: it keeps the car's drawn speed
    change, so a lead car at the car's speed keeps its gap (the car has no cruise control that
    would keep it; a faster draw used to run it into the lead car)."""
    return vehicle.lane == lane and vehicle.speed_mps > 0.0


def nuisance_summary(scenario: Scenario) -> dict[str, float]:
    """What `with_nuisance` changes for this seed, against the file: the start's offset (m),
    heading (deg) and the speed (m/s); all 0 for the nominal seed."""
    drawn = with_nuisance(scenario)
    return {"start_offset_m": drawn.start.offset_m - scenario.start.offset_m,
            "start_heading_deg": drawn.start.heading_deg - scenario.start.heading_deg,
            "speed_mps": drawn.target_speed_mps - scenario.target_speed_mps}
