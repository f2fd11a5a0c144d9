"""The `[traffic]` table: seeded vehicles beside the car's lane, never in it, off at density 0;
street lamps lit at night; the roadside's tree kinds."""

import dataclasses

import mujoco
import numpy as np
import pytest

from lanekeep.core.config_io import ConfigError
from lanekeep.scenario.keys import with_settings
from lanekeep.scenario.schema import load_scenario, parse_scenario, shipped_scenarios
from lanekeep.scenario.traffic import Traffic
from lanekeep.world.build import build_spec, check_buildable
from lanekeep.world.props import prop_kind
from lanekeep.world.traffic_flow import traffic_vehicles

FOUR_LANES = """
name = "t"
description = "traffic"
seed = 5
[road]
n_lanes = 4
ego_lane = 1
[[road.segments]]
kind = "straight"
length_m = 400
[start]
s_m = 100.0
[traffic]
vehicles_per_km = 40.0
directions = ["same", "same", "oncoming", "oncoming"]
"""


def _scenario(**traffic):
    base = parse_scenario(FOUR_LANES)
    return dataclasses.replace(base, traffic=dataclasses.replace(base.traffic, **traffic))


def test_vehicles_keep_out_of_the_ego_lane_and_its_lines_and_clear_of_the_start():
    sc = _scenario()
    road = sc.build_road()
    vehicles = traffic_vehicles(sc, road)
    assert len(vehicles) >= 10
    assert {v.lane for v in vehicles} == {0, 2, 3}
    for v in vehicles:
        assert abs(v.s_m - sc.start.s_m) >= sc.traffic.clear_m + 0.5 * v.length_m
        assert abs(v.offset_m) + 0.5 * v.width_m <= 0.5 * road.lane_width_m  # inside its lane
        assert (v.speed_mps < 0) == (v.lane >= 2)  # oncoming lanes drive the other way
    for lane in (0, 2, 3):
        s = sorted(v.s_m for v in vehicles if v.lane == lane)
        assert len({v.speed_mps for v in vehicles if v.lane == lane}) == 1  # no run-ins
        assert all(b - a > 8.0 for a, b in zip(s, s[1:], strict=False))


def test_a_seed_reproduces_its_traffic_and_another_seed_draws_other_traffic():
    sc = _scenario()
    road = sc.build_road()
    assert traffic_vehicles(sc, road) == traffic_vehicles(sc, road)
    assert traffic_vehicles(sc, road) != traffic_vehicles(dataclasses.replace(sc, seed=6), road)


def test_density_zero_turns_traffic_off_and_is_the_default():
    sc = _scenario(vehicles_per_km=0.0)
    assert traffic_vehicles(sc, sc.build_road()) == ()
    assert Traffic().vehicles_per_km == 0.0
    spec, _, info = build_spec(sc, sc.build_road())
    assert info.vehicles == []
    on = _scenario()
    _, _, info = build_spec(on, on.build_road())
    assert len(info.vehicles) == len(traffic_vehicles(on, on.build_road()))


@pytest.mark.parametrize("setting", [
    ("traffic.vehicles_per_km", -1.0),
    ("traffic.directions", ["same", "sideways"]),
    ("traffic.speed_mps", [20.0, 10.0]),
    ("traffic.truck_share", 0.9),
])
def test_bad_traffic_keys_are_named(setting):
    with pytest.raises(ConfigError, match=setting[0].split(".")[1]):
        with_settings(parse_scenario(FOUR_LANES), (setting,))


def test_directions_must_name_every_lane():
    sc = with_settings(parse_scenario(FOUR_LANES), (("traffic.directions", ["same"]),))
    with pytest.raises(ConfigError, match="traffic.directions"):
        check_buildable(sc)


def test_every_shipped_scenario_has_roadside_and_traffic_beside_the_ego_lane():
    """Traffic in the car's own lane (drawn or an event's) only where the car has adaptive
    cruise: without it the car cannot follow a vehicle ahead."""
    for name in shipped_scenarios():
        sc = load_scenario(name)
        vehicles = traffic_vehicles(sc, sc.build_road())
        assert sc.roadside.trees_per_100m > 0 and sc.roadside.skyline != "none", name
        assert any(v.lane != sc.road.ego_lane for v in vehicles), name
        if not sc.control.acc:
            assert all(v.lane != sc.road.ego_lane for v in vehicles), name


def test_street_lamps_are_lit_at_night_only():
    night = load_scenario("night")
    spec, _, _ = build_spec(night, night.build_road())
    lamps = spec.geom("street_lamp_heads")
    assert lamps is not None and spec.material("street_lamp").emission == 1.0
    assert spec.material("prop_hills").emission < 0.05  # no daylight haze at night
    day = with_settings(night, (("conditions.time_of_day", "day"),))
    spec, _, _ = build_spec(day, day.build_road())
    assert spec.geom("street_lamp_heads") is None


def test_vehicles_glow_at_night_and_trucks_carry_a_textured_box():
    sc = with_settings(load_scenario("night"), (("conditions.vehicles", [
        {"lane": 1, "s_m": 60.0, "speed_mps": -10.0, "length_m": 12.0, "width_m": 2.5,
         "height_m": 3.8}]),))
    spec, _, _ = build_spec(sc, sc.build_road())
    assert spec.geom("cond_vehicle_0_headlight_glow") is not None
    assert spec.geom("cond_vehicle_0_taillight_glow") is not None
    cargo = spec.mesh("cond_vehicle_0_cargo")
    assert cargo is not None and len(cargo.usertexcoord) > 0
    rgb = mujoco.mjtTextureRole.mjTEXROLE_RGB
    assert spec.material("cond_vehicle_0_trailer").textures[rgb] == "cond_vehicle_trailer"


def test_scenery_trees_come_in_several_kinds():
    sc = with_settings(load_scenario("clear_straight"), (("roadside.trees_per_100m", 20.0),))
    spec, _, _ = build_spec(sc, sc.build_road())
    kinds = {prop_kind(g.name) for g in spec.geoms}
    assert "props_conifer" in kinds
    assert sum(n.startswith("props_foliage_") for n in kinds) >= 2
    verts = np.concatenate([np.array(m.uservert).reshape(-1, 3) for m in spec.meshes
                            if prop_kind(m.name) == "props_conifer"])
    assert np.ptp(verts[:, 2]) > 5.0  # conifers stand 7-16 m
