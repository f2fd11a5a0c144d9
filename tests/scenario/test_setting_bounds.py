"""The values a reader of docs/scenario_format.md sees are the values the loader accepts: every
key documented with bounds or choices at its field (lanekeep/core/setting.py) is refused just
outside them, with one line naming the dotted key, and accepted at its ends."""

from __future__ import annotations

import math

import pytest

from lanekeep.core.setting import BOUNDS, CHOICES
from lanekeep.scenario.keys import scenario_table, set_key
from lanekeep.scenario.reference import walk
from lanekeep.scenario.schema import Scenario, ScenarioError, load_scenario, scenario_from_dict

BASE = load_scenario("case1_building_shadows")  # conditions.shadows[0] exists
ARRAYS = {"conditions.shadows[]": "conditions.shadows[0]", "road.segments[]": "road.segments[0]",
          "traffic.events[]": "traffic.events[0]"}
EVENT = {"kind": "lead_brake", "at_time_s": 1.0}  # a valid event for the traffic.events keys
CHECKED = [(path, f) for path, f, _ in walk(Scenario)
           if (BOUNDS in f.metadata or CHOICES in f.metadata)
           and not path.startswith(("conditions.vehicles[]", "road.markings[]"))]
# Ends that another key's rule refuses on the base (van_share + truck_share <= 1).
CROSS_FIELD = ("traffic.van_share", "traffic.truck_share")


def _key(path: str) -> str:
    for array, first in ARRAYS.items():
        path = path.replace(array, first)
    return path


def _table(key: str, value) -> dict:
    table = scenario_table(BASE)
    if key.startswith("traffic.events[0]"):
        table.setdefault("traffic", {})["events"] = [dict(EVENT)]
    path: list = []
    for part in key.split("."):
        name, _, index = part.partition("[")
        path.append(name)
        if index:
            path.append(int(index.rstrip("]")))
    set_key(table, path, value)
    return table


def _outside(f) -> list:
    if CHOICES in f.metadata:
        return ["no_such_choice"]
    low, high = f.metadata[BOUNDS]
    if isinstance(low, int) and isinstance(high, int):
        return [low - 1, high + 1]
    step = max(high - low, 1.0) * 1e-3
    return [low - step, high + step, math.nan]


def test_the_bounded_keys_are_many():
    assert len(CHECKED) >= 40, [p for p, _ in CHECKED]


@pytest.mark.parametrize(("path", "f"), CHECKED, ids=[p for p, _ in CHECKED])
def test_a_value_outside_the_documented_range_is_refused_naming_the_key(path, f):
    key = _key(path)
    for value in _outside(f):
        with pytest.raises(ScenarioError) as err:
            scenario_from_dict(_table(key, value), "probe.toml")
        assert key in str(err.value) and "\n" not in str(err.value), str(err.value)


ENDS = [(p, f) for p, f in CHECKED if BOUNDS in f.metadata and p not in CROSS_FIELD]


@pytest.mark.parametrize(("path", "f"), ENDS, ids=[p for p, _ in ENDS])
def test_the_ends_of_the_documented_range_are_accepted(path, f):
    for value in f.metadata[BOUNDS]:
        scenario_from_dict(_table(_key(path), value), "probe.toml")
