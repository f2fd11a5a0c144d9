"""The traffic flow (lanekeep/traffic/flow.py): car following, lane changes, events, rules."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from lanekeep.traffic.events import CutIn, LeadBrake
from lanekeep.traffic.flow import TrafficFlow
from lanekeep.traffic.idm import IdmParams
from lanekeep.traffic.mobil import MobilParams
from lanekeep.traffic.state import EgoState, VehicleSetup

DT = 0.05
TWO_LANES = dict(lane_centres_m=(-1.75, 1.75), lane_directions=(1, 1))
ONCOMING = dict(lane_centres_m=(-1.75, 1.75), lane_directions=(1, -1))


def ego_at(s: float, r: float = -1.75, speed: float = 0.0) -> EgoState:
    return EgoState(s_m=s, r_m=r, speed_mps=speed, length_m=4.6, width_m=1.85)


def ring_vehicles(seed: int = 7, n: int = 30) -> list[VehicleSetup]:
    """n vehicles on two lanes of a 1000 m ring, desired speeds and time gaps drawn."""
    rng = np.random.default_rng(seed)
    vehicles = []
    for i in range(n):
        lane = i % 2
        idm = IdmParams(desired_speed_mps=float(rng.uniform(18.0, 32.0)),
                        time_gap_s=float(rng.uniform(1.0, 1.8)))
        vehicles.append(VehicleSetup(
            name=f"v{i}", lane=lane, s_m=(i // 2) * 1000.0 / (n // 2) + 30.0 * lane,
            speed_mps=15.0, idm=idm, mobil=MobilParams(politeness=float(rng.uniform(0, 0.5)))))
    return vehicles


def ring(**kw) -> TrafficFlow:
    return TrafficFlow(**TWO_LANES, road_length_m=1000.0, closed=True,
                       vehicles=kw.pop("vehicles", ring_vehicles()), **kw)


def test_a_busy_ring_never_crashes_and_changes_lanes():
    """30 vehicles, 100 s (3000 vehicle-seconds): no two bodies that overlap laterally ever
    overlap along the road, speeds stay in [0, v0], and MOBIL changes lanes."""
    vehicles = ring_vehicles()
    flow = ring(vehicles=vehicles)
    v0 = np.array([v.idm.desired_speed_mps for v in vehicles])
    length = np.array([v.length_m for v in vehicles])
    width = np.array([v.width_m for v in vehicles])
    half_len = 0.5 * (length[:, None] + length[None, :])
    half_wid = 0.5 * (width[:, None] + width[None, :])
    off_diagonal = ~np.eye(len(vehicles), dtype=bool)
    was_changing = np.zeros(len(vehicles), dtype=bool)
    changes, min_gap = 0, math.inf
    for _ in range(2000):
        flow.step(DT)
        states = flow.states
        s = np.array([st.s_m for st in states])
        r = np.array([st.r_m for st in states])
        v = np.array([st.speed_mps for st in states])
        changing = np.array([st.changing_lane for st in states])
        assert np.all(np.isfinite(s)) and np.all(np.isfinite(r)) and np.all(np.isfinite(v))
        assert np.all((s >= 0.0) & (s < 1000.0))
        assert np.all((v >= 0.0) & (v <= v0 + 0.01))
        ds = np.abs((s[:, None] - s[None, :] + 500.0) % 1000.0 - 500.0)
        beside = (np.abs(r[:, None] - r[None, :]) < half_wid) & off_diagonal
        gaps = (ds - half_len)[beside]
        if gaps.size:
            min_gap = min(min_gap, float(gaps.min()))
        changes += int(np.sum(changing & ~was_changing))
        was_changing = changing
    assert min_gap > 0.0
    assert changes >= 1
    assert flow.time_s == pytest.approx(100.0)


def test_a_follower_stops_behind_a_standing_ego_car():
    flow = TrafficFlow(lane_centres_m=(-1.75,), lane_directions=(1,), road_length_m=1000.0,
                       closed=False, vehicles=[VehicleSetup("f", 0, 0.0, 15.0)])
    ego = ego_at(120.0)
    gaps = []
    for _ in range(1200):  # 60 s
        flow.step(DT, ego)
        gaps.append(ego.s_m - flow.state("f").s_m - 4.6)
    assert min(gaps) > 0.0
    assert gaps[-1] == pytest.approx(2.0, abs=0.5)  # s0
    assert flow.state("f").speed_mps == 0.0


def test_the_ego_car_only_matters_in_the_lanes_it_overlaps():
    flow = TrafficFlow(**TWO_LANES, road_length_m=1000.0, closed=False,
                       vehicles=[VehicleSetup("f", 0, 0.0, 15.0)])
    for _ in range(400):  # an ego standing in lane 1 (r = +1.75) is passed
        flow.step(DT, ego_at(120.0, r=1.75))
    assert flow.state("f").s_m > 150.0


def test_cut_in_at_a_gap():
    cutter = VehicleSetup("cutter", 1, 34.6, 12.0, idm=IdmParams(desired_speed_mps=12.0))
    flow = TrafficFlow(**TWO_LANES, road_length_m=2000.0, closed=False, vehicles=[cutter],
                       events=[CutIn("cutter", to_lane=0, at_gap_m=15.0, duration_s=3.0)])
    ego_s, ego_v = 0.0, 14.0  # closes at 2 m/s from a 30 m gap
    gaps_before, started, drs = [], None, []
    for step in range(600):
        st = flow.state("cutter")
        gaps_before.append(st.s_m - ego_s - 4.6)
        flow.step(DT, ego_at(ego_s, speed=ego_v))
        ego_s += ego_v * DT
        st = flow.state("cutter")
        if st.changing_lane and started is None:
            started = step
            assert st.lane == 0
        if started is not None:
            drs.append(st.lateral_speed_mps)
            if step - started == 59:  # the change has run 3.0 s
                assert not st.changing_lane
                assert st.r_m == -1.75 and st.lateral_speed_mps == 0.0
                break
            assert st.changing_lane, step - started
    assert started is not None
    assert gaps_before[started] <= 15.0 < gaps_before[started - 1]
    # peak lateral speed 1.875 * 3.5 m / 3 s = 2.1875 m/s towards lane 0 (right)
    assert min(drs) == pytest.approx(-2.1875, rel=2e-3)
    assert max(drs) <= 0.0


def test_cut_in_at_a_time_is_forced_and_fires_once():
    flow = TrafficFlow(**TWO_LANES, road_length_m=2000.0, closed=False,
                       vehicles=[VehicleSetup("c", 1, 50.0, 10.0)],
                       events=[CutIn("c", to_lane=0, at_time_s=1.0)])
    for _ in range(20):
        flow.step(DT)
    assert not flow.state("c").changing_lane  # t = 1.0 is reached at the start of step 21
    flow.step(DT)
    assert flow.state("c").changing_lane and flow.state("c").lane == 0
    for _ in range(200):
        flow.step(DT)
    assert flow.state("c").r_m == -1.75 and flow.state("c").lane == 0


def test_lead_brake_to_a_stop():
    lead = VehicleSetup("lead", 0, 100.0, 20.0, idm=IdmParams(desired_speed_mps=20.0))
    follower = VehicleSetup("f", 0, 50.0, 20.0, idm=IdmParams(desired_speed_mps=20.0))
    flow = TrafficFlow(lane_centres_m=(0.0,), lane_directions=(1,), road_length_m=1000.0,
                       closed=False, vehicles=[lead, follower],
                       events=[LeadBrake("lead", at_time_s=2.0, decel_mps2=3.0)])
    for _ in range(40):
        flow.step(DT)
    assert flow.state("lead").speed_mps == pytest.approx(20.0, abs=1e-9)  # at v0: no change
    for _ in range(20):
        flow.step(DT)
    assert flow.state("lead").speed_mps == pytest.approx(17.0, abs=1e-9)  # 20 - 3 m/s^2 * 1 s
    assert flow.state("lead").accel_mps2 == -3.0
    # stops at t = 2 + 20 / 3 = 8.67 s after 20^2 / (2 * 3) = 66.67 m, and stays
    for _ in range(120):
        flow.step(DT)
    stopped = flow.state("lead")
    assert stopped.speed_mps == 0.0
    assert stopped.s_m == pytest.approx(100.0 + 40.0 + 200.0 / 3.0, abs=1e-6)
    for _ in range(400):
        flow.step(DT)
        assert flow.state("lead").speed_mps == 0.0 and flow.state("lead").s_m == stopped.s_m
        follower_gap = flow.state("lead").s_m - flow.state("f").s_m - 4.6
        assert follower_gap > 0.0
    assert flow.state("f").speed_mps == pytest.approx(0.0, abs=0.05)


def test_lead_brake_to_a_lower_speed_keeps_it():
    flow = TrafficFlow(lane_centres_m=(0.0,), lane_directions=(1,), road_length_m=1000.0,
                       closed=False, vehicles=[VehicleSetup("lead", 0, 0.0, 25.0)],
                       events=[LeadBrake("lead", at_time_s=0.0, decel_mps2=2.0,
                                         to_speed_mps=15.0)])
    for _ in range(400):
        flow.step(DT)
    assert flow.state("lead").speed_mps == pytest.approx(15.0, abs=1e-6)


def test_stop_and_go_lead_drives_on_after_its_stop():
    # 20 m/s, braking at 4 m/s^2 from t = 1 s: stands at t = 6 s, wants 20 m/s again at 8 s
    flow = TrafficFlow(lane_centres_m=(0.0,), lane_directions=(1,), road_length_m=2000.0,
                       closed=False, vehicles=[VehicleSetup(
                           "lead", 0, 0.0, 20.0, idm=IdmParams(desired_speed_mps=20.0))],
                       events=[LeadBrake("lead", at_time_s=1.0, decel_mps2=4.0,
                                         resume_after_s=2.0)])
    speeds = []
    for _ in range(400):
        flow.step(DT)
        speeds.append(flow.state("lead").speed_mps)
    t = DT * (1 + np.arange(len(speeds)))
    assert np.all(np.asarray(speeds)[(t > 6.05) & (t < 7.95)] == 0.0)  # stands 2 s
    assert speeds[int(round(9.0 / DT)) - 1] > 0.0  # then drives on
    # free road from 8 s: dv/dt = 1 - (v / 20)^4 is 0.88..1 m/s^2 below 11.7 m/s, so 12 s later
    # (t = 20 s) v lies between 0.88 * 12 = 10.6 and 12 m/s
    assert 10.5 < speeds[-1] < 12.0


def test_oncoming_traffic_follows_its_own_leader():
    fast = VehicleSetup("fast", 1, 500.0, 20.0, direction=-1,
                        idm=IdmParams(desired_speed_mps=25.0))
    slow = VehicleSetup("slow", 1, 400.0, 10.0, direction=-1,
                        idm=IdmParams(desired_speed_mps=10.0))
    # in the other direction's lane, just ahead of `fast` along s: not its leader
    other = VehicleSetup("other", 0, 505.0, 5.0, idm=IdmParams(desired_speed_mps=5.0))
    flows = [TrafficFlow(**ONCOMING, road_length_m=1000.0, closed=False, vehicles=vehicles)
             for vehicles in ([fast, slow, other], [fast, slow])]
    for _ in range(1200):  # 60 s
        for flow in flows:
            flow.step(DT)
        gap = flows[0].state("fast").s_m - flows[0].state("slow").s_m - 4.6
        assert gap > 0.0
        assert flows[0].state("fast") == flows[1].state("fast")
    assert flows[0].state("fast").s_m < 100.0 and flows[0].state("other").s_m > 505.0
    assert flows[0].state("fast").speed_mps == pytest.approx(10.0, abs=0.2)


def test_mobil_overtakes_but_never_into_an_oncoming_lane():
    slow = VehicleSetup("slow", 0, 60.0, 10.0, idm=IdmParams(desired_speed_mps=10.0))
    fast = VehicleSetup("fast", 0, 0.0, 25.0, mobil=MobilParams())
    same = TrafficFlow(**TWO_LANES, road_length_m=2000.0, closed=False, vehicles=[slow, fast])
    facing = TrafficFlow(**ONCOMING, road_length_m=2000.0, closed=False, vehicles=[slow, fast])
    lanes_same, lanes_facing = set(), set()
    for _ in range(600):
        same.step(DT)
        facing.step(DT)
        lanes_same.add(same.state("fast").lane)
        lanes_facing.add(facing.state("fast").lane)
    assert lanes_same == {0, 1} and same.state("fast").s_m > same.state("slow").s_m
    assert lanes_facing == {0} and facing.state("fast").s_m < facing.state("slow").s_m


def test_a_parked_car_blocks_only_the_lane_it_stands_in():
    def run(r_parked: float) -> float:
        parked = VehicleSetup("parked", 0, 200.0, 0.0, parked=True, r_m=r_parked)
        flow = TrafficFlow(lane_centres_m=(0.0,), lane_directions=(1,), road_length_m=1000.0,
                           closed=False, vehicles=[parked, VehicleSetup("f", 0, 0.0, 15.0)])
        for _ in range(1200):
            flow.step(DT)
            assert flow.state("parked").s_m == 200.0 and flow.state("parked").speed_mps == 0.0
        return flow.state("f").s_m
    # lane 0 spans [-1.75, 1.75]; a 1.85 m car at r = -2.2 reaches 0.475 m into it: blocks
    assert run(-2.2) == pytest.approx(200.0 - 4.6 - 2.0, abs=0.5)
    # at r = -2.6 it reaches 0.075 m in, under the 0.3 m margin: on the shoulder, passed
    assert run(-2.6) > 300.0


def test_same_construction_same_states_and_reset_returns_to_the_start():
    events = [LeadBrake("v3", at_time_s=2.0, decel_mps2=2.0, to_speed_mps=5.0),
              CutIn("v4", to_lane=0, at_gap_m=20.0)]
    flows = [ring(events=events) for _ in range(2)]
    start = flows[0].states
    for i in range(200):
        for flow in flows:
            flow.step(DT, ego_at(3.0 * i * DT, speed=3.0))
    assert flows[0].states == flows[1].states
    assert flows[0].states != start
    flows[0].reset()
    assert flows[0].states == start and flows[0].time_s == 0.0
    for i in range(200):
        flows[0].step(DT, ego_at(3.0 * i * DT, speed=3.0))
    assert flows[0].states == flows[1].states


def test_a_zero_step_changes_nothing():
    flow = ring()
    before = flow.states
    flow.step(0.0)
    assert flow.states == before and flow.time_s == 0.0
    with pytest.raises(ValueError, match="dt_s"):
        flow.step(-0.05)


def test_states_keep_the_given_order_and_names():
    vehicles = ring_vehicles(n=6)
    flow = ring(vehicles=vehicles)
    assert [st.name for st in flow.states] == [v.name for v in vehicles]
    assert flow.state("v2") == flow.states[2]
    with pytest.raises(KeyError, match="nope"):
        flow.state("nope")


def test_bad_input_names_what_is_wrong():
    wrong_way = VehicleSetup("ghost_rider", 1, 10.0, 20.0, direction=1)
    with pytest.raises(ValueError, match="ghost_rider"):
        TrafficFlow(**ONCOMING, road_length_m=500.0, closed=False, vehicles=[wrong_way])
    ok = VehicleSetup("a", 0, 10.0, 20.0)
    with pytest.raises(ValueError, match="nobody"):
        TrafficFlow(**TWO_LANES, road_length_m=500.0, closed=False, vehicles=[ok],
                    events=[CutIn("nobody", to_lane=1, at_time_s=1.0)])
    with pytest.raises(ValueError, match="LeadBrake.*nobody"):
        TrafficFlow(**TWO_LANES, road_length_m=500.0, closed=False, vehicles=[ok],
                    events=[LeadBrake("nobody", at_time_s=1.0, decel_mps2=2.0)])
    with pytest.raises(ValueError, match="'a'"):
        TrafficFlow(**TWO_LANES, road_length_m=500.0, closed=False, vehicles=[ok, ok])
    with pytest.raises(ValueError, match="lane 5"):
        TrafficFlow(**TWO_LANES, road_length_m=500.0, closed=False,
                    vehicles=[replace(ok, lane=5)])
    with pytest.raises(ValueError, match="to_lane|lane 1"):
        TrafficFlow(**ONCOMING, road_length_m=500.0, closed=False, vehicles=[ok],
                    events=[CutIn("a", to_lane=1, at_time_s=1.0)])


def test_mobil_never_enters_a_no_entry_lane_but_a_cut_in_does():
    slow = VehicleSetup("slow", 0, 60.0, 10.0, idm=IdmParams(desired_speed_mps=10.0))
    fast = VehicleSetup("fast", 0, 0.0, 25.0, mobil=MobilParams())
    cutter = VehicleSetup("cutter", 0, 300.0, 20.0, idm=IdmParams(desired_speed_mps=20.0))
    flow = TrafficFlow(**TWO_LANES, road_length_m=2000.0, closed=False,
                       vehicles=[slow, fast, cutter], no_entry_lanes=(1,),
                       events=[CutIn("cutter", to_lane=1, at_time_s=5.0)])
    for _ in range(600):
        flow.step(DT)
        assert flow.state("fast").lane == 0
    assert flow.state("cutter").lane == 1 and flow.state("cutter").r_m == 1.75
    with pytest.raises(ValueError, match="no_entry_lanes"):
        TrafficFlow(**TWO_LANES, road_length_m=2000.0, closed=False, vehicles=[slow],
                    no_entry_lanes=(2,))
