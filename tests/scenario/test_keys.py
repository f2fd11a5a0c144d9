"""Dotted scenario keys (lanekeep/scenario/keys.py): a scenario back to its table, `--set`'s
KEY=VALUE, and changing a scenario by keys with the checks a file gets."""

from dataclasses import fields, replace

import pytest

from lanekeep.loop.overrides import PluginOverrides
from lanekeep.scenario.keys import (
    check_key,
    parse_key,
    parse_setting,
    scenario_table,
    with_settings,
)
from lanekeep.scenario.schema import (
    DEFAULT_FRONT_DETECTORS,
    Scenario,
    ScenarioError,
    load_scenario,
    scenario_from_dict,
    shipped_scenarios,
)


@pytest.mark.parametrize("name", shipped_scenarios())
def test_the_table_reads_back_to_the_same_scenario(name):
    scenario = load_scenario(name)
    table = scenario_table(scenario)
    assert "source" not in table
    memory_only = {f.name: f.default for f in fields(Scenario) if not f.metadata.get("toml", True)}
    assert scenario_from_dict(table, "memory") == replace(scenario, **{**memory_only,
                                                                       "source": "memory"})


def test_parse_key():
    assert parse_key("road.segments[1].curvature_1pm") == ["road", "segments", 1,
                                                           "curvature_1pm"]
    with pytest.raises(ValueError, match="not a dotted key"):
        parse_key("road..n_lanes")


def test_check_key_without_a_table_checks_names_only():
    check_key("road.segments[99].length_m", None, seed_rule="x")
    with pytest.raises(ValueError, match="'nope' is not a scenario key"):
        check_key("estimation.nope", None, seed_rule="x")
    with pytest.raises(ValueError, match=r"is not a scenario key \(use --seed\)"):
        check_key("seed", None, seed_rule="use --seed")


@pytest.mark.parametrize(("text", "key", "value"), [
    ("estimation.output=select", "estimation.output", "select"),  # a bare word: a string
    ("estimation.output='select'", "estimation.output", "select"),
    ("conditions.rain=0.3", "conditions.rain", 0.3),
    ("road.n_lanes=3", "road.n_lanes", 3),
    ("camera.shadows=true", "camera.shadows", True),
    ('estimation.front_detectors=["hough","lanenet"]', "estimation.front_detectors",
     ["hough", "lanenet"]),
    (" start.offset_m = -0.5 ", "start.offset_m", -0.5),
    ("description=a=b", "description", "a=b"),  # the first "=" splits
    ("description=", "description", ""),
])
def test_parse_setting_types_the_value(text, key, value):
    got = parse_setting(text)
    assert got == (key, value)
    assert type(got[1]) is type(value)


@pytest.mark.parametrize("text", ["estimation.output", "=select", " =1", ""])
def test_parse_setting_needs_a_key_and_an_equals_sign(text):
    with pytest.raises(ValueError, match="expected KEY=VALUE"):
        parse_setting(text)


def test_with_settings_changes_the_values_and_keeps_the_rest():
    scenario = load_scenario("case1_building_shadows")
    changed = with_settings(scenario, (("estimation.mmae_prior", "uniform"),
                                       ("estimation.output", "select"),
                                       ("road.segments[0].length_m", 123.0)))
    assert changed.estimation.mmae_prior == "uniform"
    assert changed.estimation.output == "select"
    assert changed.road.segments[0].length_m == 123.0
    assert changed.source == scenario.source
    memory_only = [f.name for f in fields(Scenario) if not f.metadata.get("toml", True)]
    assert all(getattr(changed, n) == getattr(scenario, n) for n in memory_only)
    assert changed == replace(
        scenario,
        estimation=replace(scenario.estimation, mmae_prior="uniform", output="select"),
        road=replace(scenario.road, segments=(replace(scenario.road.segments[0],
                                                      length_m=123.0),
                                              *scenario.road.segments[1:])))
    assert with_settings(scenario, ()) is scenario


def test_with_settings_applies_in_order():
    scenario = load_scenario("clear_straight")
    changed = with_settings(scenario, (("conditions.rain", 0.2), ("conditions.rain", 0.7)))
    assert changed.conditions.rain == 0.7


def test_a_new_mode_brings_its_own_front_models_unless_they_are_named():
    """As in a file without `front_detectors` (and as `--mode`): the mode's default models."""
    scenario = load_scenario("clear_straight")
    assert scenario.estimation.front_detectors == DEFAULT_FRONT_DETECTORS["default"]
    paper = with_settings(scenario, (("estimation.mode", "paper"),))
    assert paper.estimation.front_detectors == DEFAULT_FRONT_DETECTORS["paper"]
    named = with_settings(scenario, (("estimation.mode", "paper"),
                                     ("estimation.front_detectors", ["hough", "lanenet"])))
    assert named.estimation.front_detectors == ("hough", "lanenet")
    back = with_settings(paper, (("estimation.mode", "default"),))
    assert back.estimation.front_detectors == DEFAULT_FRONT_DETECTORS["default"]


@pytest.mark.parametrize(("key", "value", "message"), [
    ("estimation.nope", 1, "'nope' is not a scenario key"),
    ("road.segments[9].length_m", 10.0, "index [9] does not exist"),
    ("estimation.output", "bogus", "must be one of"),
    ("conditions.rain", "lots", "expected a number"),
])
def test_a_bad_setting_is_the_scenario_error_naming_the_key(key, value, message):
    scenario = load_scenario("clear_straight")
    with pytest.raises(ScenarioError) as caught:
        with_settings(scenario, ((key, value),))
    assert caught.value.key == key
    assert caught.value.source == scenario.source
    assert message in caught.value.message


def test_seed_is_refused():
    with pytest.raises(ScenarioError, match="use --seed") as caught:
        with_settings(load_scenario("clear_straight"), (("seed", 3),))
    assert caught.value.key == "seed"


def test_a_shared_value_is_not_changed_by_a_later_setting():
    """`bench` applies the same settings to every scenario: a table value set by one must not
    be edited in place by the next key."""
    rain = {"rain": 0.5}
    settings = (("conditions", rain), ("conditions.fog", 0.2))
    first = with_settings(load_scenario("clear_straight"), settings)
    assert (first.conditions.rain, first.conditions.fog) == (0.5, 0.2)
    assert rain == {"rain": 0.5}


def test_plugin_overrides_apply_the_settings_last():
    overrides = PluginOverrides(front_detectors=("hough",),
                                settings=(("estimation.front_detectors", ["lanenet"]),))
    scenario = overrides.apply(load_scenario("clear_straight"))
    assert scenario.estimation.front_detectors == ("lanenet",)


def test_plugin_overrides_name_the_settings_in_a_bad_values_error():
    overrides = PluginOverrides(settings=(("estimation.output", "bogus"),))
    with pytest.raises(ScenarioError, match='--set estimation.output="bogus"') as caught:
        overrides.apply(load_scenario("clear_straight"))
    assert caught.value.key == "estimation.output"
