"""What a seed draws besides the noise (lanekeep/scenario/nuisance.py): the file's own seed is
its nominal drive; other seeds move the start and the traffic's timing within [start.jitter]."""

import dataclasses

from lanekeep.scenario.nuisance import nuisance_summary, with_nuisance
from lanekeep.scenario.schema import StartJitter, load_scenario


def _seeded(name: str, seed: int):
    return dataclasses.replace(load_scenario(name), seed=seed)


def test_the_files_own_seed_is_the_nominal_drive():
    scenario = load_scenario("occlusion")
    assert scenario.seed == scenario.nominal_seed == 12 and with_nuisance(scenario) == scenario
    assert with_nuisance(_seeded("occlusion", 0)) != _seeded("occlusion", 0)
    in_memory = dataclasses.replace(scenario, nominal_seed=None, seed=0)
    assert with_nuisance(in_memory) == in_memory  # built in memory: seed 0 is nominal


def test_other_seeds_draw_within_the_jitter_and_repeat_exactly():
    base = load_scenario("clear_curve")
    jitter = base.start.jitter
    drawn = [nuisance_summary(_seeded("clear_curve", s)) for s in range(1, 30)]
    assert all(abs(d["start_offset_m"]) <= jitter.offset_m for d in drawn)
    assert all(abs(d["start_heading_deg"]) <= jitter.heading_deg for d in drawn)
    assert all(abs(d["speed_mps"]) <= jitter.speed_mps for d in drawn)
    assert len({d["start_offset_m"] for d in drawn}) == len(drawn)  # every seed its own
    assert with_nuisance(_seeded("clear_curve", 7)) == with_nuisance(_seeded("clear_curve", 7))
    moved = with_nuisance(_seeded("clear_curve", 7))
    assert moved.target_speed_mps - base.target_speed_mps == moved.start.speed_mps - \
        base.start.speed_mps


def test_traffic_timing_moves_by_relative_speed():
    base = load_scenario("occlusion")
    moved = with_nuisance(_seeded("occlusion", 3))
    ego = base.target_speed_mps
    for before, after in zip(base.conditions.vehicles, moved.conditions.vehicles, strict=True):
        limit = abs(before.speed_mps - ego) * base.start.jitter.traffic_s + 1e-9
        assert abs(after.s_m - before.s_m) <= limit
        if before.speed_mps == ego:  # the lead car keeps its gap
            assert after.s_m == before.s_m


def test_zero_jitter_keeps_every_seed_on_the_nominal_start():
    base = load_scenario("clear_straight")
    still = dataclasses.replace(base, seed=5, start=dataclasses.replace(
        base.start, jitter=StartJitter(0.0, 0.0, 0.0, 0.0)))
    assert with_nuisance(still) == still


def test_a_lead_car_in_the_cars_lane_keeps_the_drawn_speed():
    """Occlusion's lead car drives 7 m ahead at the car's speed: a seed that draws the car
    faster must draw the lead car faster too, or the car (no cruise control) runs into it."""
    base = load_scenario("occlusion")
    lane = base.road.ego_lane
    for seed in (13, 14, 1000):
        moved = with_nuisance(_seeded("occlusion", seed))
        d_speed = moved.target_speed_mps - base.target_speed_mps
        assert d_speed != 0.0
        for before, after in zip(base.conditions.vehicles, moved.conditions.vehicles,
                                 strict=True):
            same_way_ahead = before.lane == lane and before.speed_mps > 0.0
            expected = before.speed_mps + (d_speed if same_way_ahead else 0.0)
            assert after.speed_mps == expected
        assert any(v.lane == lane for v in base.conditions.vehicles)
