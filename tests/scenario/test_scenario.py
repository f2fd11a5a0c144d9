"""Scenario files: shipped registry, strict parsing, useful errors."""

import math
from pathlib import Path

import pytest

from lanekeep.scenario.schema import (
    Scenario,
    ScenarioError,
    load_scenario,
    parse_scenario,
    shipped_scenarios,
)
from lanekeep.scoring.truth import lane_truth

SHIPPED = shipped_scenarios()
REQUIRED = {  # the foundation's three, the paper's five cases, and the harder conditions
    "clear_straight", "clear_curve", "sharp_turn", "s_bend",
    "case1_building_shadows", "case2_sharp_turn", "case3_mild_turn_shade_bumps",
    "case4_half_shade_straight", "case5_wet_rain_turn",
    "night", "fog", "snow", "heavy_rain", "worn_markings", "occlusion", "highway_multilane",
}

MINIMAL = """
name = "tiny"
description = "a test"
[road]
[[road.segments]]
kind = "straight"
length_m = 100
"""


def test_shipped_list():
    assert SHIPPED == sorted(SHIPPED)
    assert REQUIRED <= set(SHIPPED)
    assert len(SHIPPED) >= 14


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_scenario_loads_and_builds(name):
    scenario = load_scenario(name)
    assert isinstance(scenario, Scenario) and scenario.name == name
    assert scenario.description and scenario.source.endswith(f"{name}.toml")
    road = scenario.build_road()
    assert road.length_m == pytest.approx(scenario.road.length_m)
    # Long enough to drive the whole episode at the target speed, with 50 m to spare.
    needed = scenario.start.s_m + scenario.duration_s * scenario.target_speed_mps + 50.0
    assert road.length_m >= needed
    # The car starts centred in its lane.
    truth = lane_truth(road, *scenario.start_pose(road), scenario.road.ego_lane)
    assert truth.offset_m == pytest.approx(scenario.start.offset_m, abs=1e-9)
    assert len(road.marking_pieces()) > 0
    assert load_scenario(scenario.source) == scenario  # by path too


def test_shipped_radii():
    curvatures = {
        name: max(abs(seg.curvature_1pm) for seg in load_scenario(name).road.segments)
        for name in SHIPPED
    }
    assert curvatures["clear_straight"] == 0.0
    assert 1.0 / curvatures["clear_curve"] == pytest.approx(150.0)
    assert 1.0 / curvatures["sharp_turn"] == pytest.approx(40.0)
    s_bend = load_scenario("s_bend").road.segments
    assert any(s.kind == "clothoid" and s.curvature_1pm * s.end_curvature_1pm < 0 for s in s_bend)


def test_defaults_and_int_as_float():
    scenario = parse_scenario(MINIMAL)
    assert scenario.road.segments[0].length_m == 100.0
    assert isinstance(scenario.road.segments[0].length_m, float)
    assert scenario.road.n_lanes == 2 and scenario.target_speed_mps == 15.0
    assert scenario.conditions.time_of_day == "day" and scenario.conditions.fog == 0.0
    assert [m.kind for m in scenario.build_road().markings] == ["solid", "dashed", "solid"]
    x, y, yaw = scenario.start_pose()
    assert (x, y, yaw) == pytest.approx((10.0, -1.85, 0.0))


def _error(text: str, tmp_path: Path) -> str:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(path) in str(info.value)
    return str(info.value)


@pytest.mark.parametrize(
    "extra, key",
    [
        ("[road.extra]\nx = 1", "road.extra"),
        ("[start]\nspeeed_mps = 3", "start.speeed_mps"),
        ("[conditions]\nfogg = 0.2", "conditions.fogg"),
        ("[[road.segments]]\nkind = 'arc'\nlenght_m = 30", "road.segments[1].lenght_m"),
    ],
)
def test_unknown_key_names_key_and_file(extra, key, tmp_path):
    message = _error(MINIMAL + extra, tmp_path)
    assert key in message and "unknown key" in message


@pytest.mark.parametrize(
    "text, key",
    [
        (MINIMAL.replace('"tiny"', "3"), "name"),
        (MINIMAL.replace("length_m = 100", "length_m = '100'"), "road.segments[0].length_m"),
        ("seed = 1.5" + MINIMAL, "seed"),
        (MINIMAL.replace("[road]", "[road]\nn_lanes = true"), "road.n_lanes"),
        ("duration_s = true" + MINIMAL, "duration_s"),
        (MINIMAL + "[camera]\nshadows = 1", "camera.shadows"),
        (MINIMAL + "[[road.markings]]\ncolour = [1, 1]", "road.markings[0].colour"),
    ],
)
def test_wrong_type_names_key(text, key, tmp_path):
    message = _error(text, tmp_path)
    assert f"{key}: expected" in message


@pytest.mark.parametrize(
    "text, key",
    [
        (MINIMAL.replace("length_m = 100", "length_m = -1"), "road.segments[0].length_m"),
        (MINIMAL.replace("'straight'", "'loop'").replace('"straight"', '"loop"'), "kind"),
        (MINIMAL.replace("[road]", "[road]\nn_lanes = 6"), "road.n_lanes"),
        (MINIMAL.replace("[road]", "[road]\nego_lane = 2"), "road.ego_lane"),
        (MINIMAL + "[[road.markings]]\nkind = 'solid'", "road.markings"),
        (MINIMAL + "[conditions]\ntime_of_day = 'noon'", "conditions.time_of_day"),
        (MINIMAL + "[conditions]\nfog = 2", "conditions.fog"),
        (MINIMAL + "[camera]\nantialias_samples = 3", "camera.antialias_samples"),
        (MINIMAL + "[estimation]\nreference_std_m = 0", "estimation.reference_std_m"),
        (MINIMAL + "[estimation]\nmmae_prior = 'flat'", "estimation.mmae_prior"),
        (MINIMAL.replace('name = "tiny"', ""), "name"),
    ],
)
def test_bad_value_names_key(text, key, tmp_path):
    assert key in _error(text, tmp_path)


def test_unknown_name_and_bad_toml(tmp_path):
    with pytest.raises(ScenarioError, match="clear_straight"):
        load_scenario("no_such_scenario")
    assert "invalid TOML" in _error("name = ", tmp_path)
    with pytest.raises(ScenarioError, match="source"):
        parse_scenario(MINIMAL + "source = 'x'")


def test_worn_markings_follow_the_seed():
    text = MINIMAL + "".join(
        f"[[road.markings]]\nkind = '{kind}'\n" for kind in ("worn", "dashed", "worn")
    )
    a = parse_scenario(text).build_road().marking_pieces()
    b = parse_scenario("seed = 7" + text).build_road().marking_pieces()
    assert a == parse_scenario(text).build_road().marking_pieces()
    assert a != b
    assert math.isclose(
        sum(p.s_end_m - p.s_start_m for p in a if p.boundary == 1), 27.0
    )  # 9 dashes of 3 m


@pytest.mark.parametrize("samples", [0, 4])
def test_antialias_samples_reach_the_renderer(samples, tmp_path):
    from lanekeep.world.build import build

    path = tmp_path / "aa.toml"
    path.write_text(MINIMAL + f"[camera]\nantialias_samples = {samples}\n")
    assert build(load_scenario(str(path))).model.vis.quality.offsamples == samples
