"""The traffic plan (lanekeep/world/traffic_flow.py): the events' vehicles where their keys
put them, the IDM draws on a stream of their own (they move no drawn vehicle), bad lane keys
named; and the world drives its mocap bodies from the traffic model."""

import dataclasses

import numpy as np
import pytest

from lanekeep.core.config_io import ConfigError
from lanekeep.scenario.keys import with_settings
from lanekeep.scenario.schema import load_scenario, parse_scenario
from lanekeep.world.build import build, check_buildable
from lanekeep.world.traffic_flow import drawn_vehicles, traffic_plan

THREE_LANES = """
name = "t"
description = "traffic plan"
seed = 5
target_speed_mps = 15.0
[road]
n_lanes = 3
ego_lane = 1
[[road.segments]]
kind = "straight"
length_m = 600
[start]
s_m = 20.0
[traffic]
vehicles_per_km = 20.0
[[traffic.events]]
kind = "cut_in"
ahead_m = 30.0
speed_mps = 12.0
at_gap_m = 10.0
[[traffic.events]]
kind = "lead_brake"
vehicle = "truck"
ahead_m = 80.0
at_time_s = 5.0
[[traffic.events]]
kind = "stopped"
side = "right"
ahead_m = 150.0
shoulder_gap_m = 0.5
"""


def test_events_bring_their_vehicles_where_their_keys_say():
    sc = parse_scenario(THREE_LANES)
    road = sc.build_road()
    plan = traffic_plan(sc, road)
    n_drawn = len(drawn_vehicles(sc, road))
    cut_in, lead, stopped = plan.vehicles[n_drawn:]
    assert cut_in.lane == 2 and cut_in.s_m == 50.0 and cut_in.speed_mps == 12.0  # left first
    assert lead.lane == 1 and lead.length_m > 8.0 and lead.speed_mps == 15.0  # a truck
    edge = road.boundary_r(0)  # the right edge line; the car stands 0.5 m beyond it
    right_side = road.lane_center_r(stopped.lane) + stopped.offset_m + 0.5 * stopped.width_m
    assert right_side == pytest.approx(edge - 0.5)
    setups = plan.setups[n_drawn:]
    assert setups[2].parked and not setups[0].parked and not setups[1].parked
    assert [type(e).__name__ for e in plan.events] == ["CutIn", "LeadBrake"]
    assert plan.events[0].to_lane == 1 and plan.events[0].at_gap_m == 10.0


def test_driving_figures_and_events_move_no_drawn_vehicle():
    sc = parse_scenario(THREE_LANES)
    road = sc.build_road()
    other = dataclasses.replace(sc, traffic=dataclasses.replace(
        sc.traffic, events=(), speed_spread_mps=3.0, politeness=0.0, time_gap_s=(0.5, 3.0)))
    assert drawn_vehicles(sc, road) == drawn_vehicles(other, road)
    spread = traffic_plan(other, road).setups
    assert len({s.idm.desired_speed_mps for s in spread if s.direction == 1 and s.lane == 0}) > 1


@pytest.mark.parametrize("key, value, message", [
    ("traffic.lane_vehicles_per_km", [1.0, 2.0], "traffic.lane_vehicles_per_km"),
    ("traffic.events[0].lane", 1, "traffic.events[0].lane"),
])
def test_lane_keys_that_do_not_fit_the_road_are_named(key, value, message):
    sc = with_settings(parse_scenario(THREE_LANES), ((key, value),))
    with pytest.raises(ConfigError, match=message.replace("[", r"\[")):
        check_buildable(sc)


def test_a_cut_in_comes_from_a_lane_of_the_cars_direction():
    sc = with_settings(parse_scenario(THREE_LANES),
                       (("traffic.directions", ["same", "same", "oncoming"]),))
    plan = traffic_plan(sc, sc.build_road())
    n_drawn = len(drawn_vehicles(sc, sc.build_road()))
    assert plan.vehicles[n_drawn].lane == 0  # the left lane is oncoming: from the right
    named = with_settings(sc, (("traffic.events[0].lane", 2),))
    with pytest.raises(ConfigError, match="drives the other way"):
        check_buildable(named)


def test_the_world_puts_its_vehicles_where_the_traffic_model_drives_them():
    sc = load_scenario("stop_and_go_truck")
    world = build(sc)
    for _ in range(30):
        world.step(0.0, 0.0, sc.control_period_s)
    assert world.traffic is not None and world.traffic.time_s == pytest.approx(3.0)
    for track in world.conditions.vehicles:
        state = world.traffic.state(track.name)
        xy = world.data.mocap_pos[track.mocap_id, :2]
        np.testing.assert_allclose(xy, world.road.position(state.s_m, state.r_m), atol=1e-9)
    world.reset()
    assert world.traffic.time_s == 0.0


def test_the_constant_model_drives_through_as_before():
    sc = with_settings(load_scenario("clear_straight"), (("traffic.model", "constant"),))
    world = build(sc)
    world.step(0.0, 0.0, 1.0)
    track = world.conditions.vehicles[0]
    expected = world.road.position(track.s_m + track.speed_mps * world.data.time, track.r_m)
    np.testing.assert_allclose(world.data.mocap_pos[track.mocap_id, :2], expected, atol=1e-9)
    state = world.traffic.state(track.name)  # scoring reads these as it reads the IDM's
    assert state.speed_mps == abs(track.speed_mps) and state.r_m == pytest.approx(track.r_m)


def test_a_lead_brake_of_an_earlier_event_brakes_that_events_vehicle():
    sc = with_settings(parse_scenario(THREE_LANES), (("traffic.events", [
        {"kind": "cut_in", "ahead_m": 30.0, "at_gap_m": 10.0},
        {"kind": "lead_brake", "of_event": 0, "at_time_s": 9.0, "decel_mps2": 6.0}]),))
    road = sc.build_road()
    plan = traffic_plan(sc, road)
    assert len(plan.vehicles) == len(drawn_vehicles(sc, road)) + 1  # one vehicle, two events
    cut_in, brake = plan.events
    assert cut_in.vehicle == brake.vehicle == plan.setups[-1].name
    with pytest.raises(ConfigError, match=r"traffic.events\[1\].of_event"):
        with_settings(sc, (("traffic.events[1].of_event", 1),))
