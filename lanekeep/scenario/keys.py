"""Dotted keys into a scenario's TOML table ("road.segments[1].curvature_1pm"), and changing a
scenario by them.

A sweep's parameters (lanekeep/sweep/spec.py) and the command line's `--set KEY=VALUE`
(`lanekeep run`, `lanekeep bench`) name scenario keys as docs/scenario_format.md writes them.
Both set them in the scenario's table and read the table back with the scenario files' own
loader (`scenario_from_dict`), so a change can hold nothing a file could not, and a bad one
fails with the message a file would give.
"""

from __future__ import annotations

import copy
import dataclasses
import re
import tomllib
import types
import typing
from typing import Any

from lanekeep.scenario.estimation import DEFAULT_FRONT_DETECTORS
from lanekeep.scenario.schema import Scenario, ScenarioError, scenario_from_dict

_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")


def parse_key(key: str) -> list[str | int]:
    """"road.segments[1].curvature_1pm" -> ["road", "segments", 1, "curvature_1pm"]."""
    path: list[str | int] = []
    for part in key.split("."):
        match = _TOKEN.fullmatch(part)
        if match is None:
            raise ValueError(f"not a dotted key: {key!r}")
        path.append(match.group(1))
        path.extend(int(i) for i in re.findall(r"\[(\d+)\]", match.group(2)))
    return path


def check_key(key: str, base_table: dict | None, *, seed_rule: str) -> None:
    """That `key` names a field of Scenario (walking its dataclasses) whose array indices
    exist in the base scenario; raises ValueError saying which part does not. The key `seed`
    is refused with `seed_rule` (each caller has its own way to set it). `base_table` None
    checks the names only (before a scenario is loaded)."""
    path = parse_key(key)
    tp: Any = Scenario
    node: Any = base_table
    for depth, part in enumerate(path):
        here = key if depth == len(path) - 1 else str(part)
        if isinstance(part, int):
            if typing.get_origin(tp) is not tuple:
                raise ValueError(f"{here!r} is not an array in a scenario")
            if base_table is not None and (not isinstance(node, list) or part >= len(node)):
                count = len(node) if isinstance(node, list) else 0
                raise ValueError(f"index [{part}] does not exist in the base scenario "
                                 f"(it has {count})")
            tp = typing.get_args(tp)[0]
            node = node[part] if base_table is not None else None
            continue
        tp = _table_type(tp)
        if not dataclasses.is_dataclass(tp):
            raise ValueError(f"{part!r} is inside a value, not a table")
        names = {f.name for f in dataclasses.fields(tp) if f.metadata.get("toml", True)}
        if part not in names or part == "seed" and tp is Scenario:
            rule = f" ({seed_rule})" if part == "seed" else ""
            raise ValueError(f"{part!r} is not a scenario key{rule}")
        tp = typing.get_type_hints(tp)[part]
        node = node.get(part) if isinstance(node, dict) else None


def _table_type(tp: Any) -> Any:
    """The table type of an optional table (`T | None` -> T); any other type unchanged."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        inner = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(inner) == 1 and dataclasses.is_dataclass(inner[0]):
            return inner[0]
    return tp


def set_key(table: dict, path: list[str | int], value: Any) -> None:
    """Set `value` at `path`, creating the tables on the way that the base leaves out."""
    node: Any = table
    for part, nxt in zip(path[:-1], path[1:], strict=True):
        if isinstance(part, int):
            node = node[part]
        else:
            if node.get(part) is None:  # an optional table the base leaves unset
                node[part] = [] if isinstance(nxt, int) else {}
            node = node[part]
    node[path[-1]] = value


def scenario_table(scenario: Scenario) -> dict:
    """The table a scenario file would hold for `scenario` (what `scenario_from_dict` reads
    back to an equal scenario): a scenario changed in memory (`--mode`, `--front-detectors`)
    has no file whose table could be edited instead."""
    return _table(scenario)


def _table(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _table(getattr(value, f.name)) for f in dataclasses.fields(value)
                if f.metadata.get("toml", True)}
    if isinstance(value, (tuple, list)):
        return [_table(v) for v in value]
    return value


def parse_setting(text: str) -> tuple[str, Any]:
    """"KEY=VALUE" -> (key, value), the value read as a TOML value ("0.3", "true",
    '["hough", "lanenet"]', '"text"') or, when it is none, as the bare string, so that
    `estimation.output=select` needs no quotes on a command line."""
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ValueError(f"expected KEY=VALUE (a dotted scenario key, e.g. "
                         f"estimation.mmae_prior=uniform), got {text!r}")
    raw = raw.strip()
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key, value


def with_settings(scenario: Scenario, settings: tuple[tuple[str, Any], ...]) -> Scenario:
    """`scenario` with each (dotted key, value) set, in order, read back by the scenario files'
    loader; the fields no file holds (`source`) are kept. Raises ScenarioError naming the
    scenario's file and the key: a key the scenario has not (or `seed`, which has its own
    option), or a value a file could not hold."""
    if not settings:
        return scenario
    table = scenario_table(scenario)
    for key, value in settings:
        try:
            check_key(key, table, seed_rule="use --seed")
        except ValueError as err:
            raise ScenarioError(scenario.source, key, str(err)) from None
        set_key(table, parse_key(key), copy.deepcopy(value))  # values are shared by episodes
    if not any(key == "estimation" or key.startswith("estimation.front_detectors")
               for key, _ in settings):
        _mode_defaults(scenario, table)
    changed = scenario_from_dict(table, scenario.source)
    # what no file holds (`source`, ...) stays the scenario's: it is the same scenario, changed
    return dataclasses.replace(changed, **{
        f.name: getattr(scenario, f.name) for f in dataclasses.fields(scenario)
        if not f.metadata.get("toml", True)})


def _mode_defaults(scenario: Scenario, table: dict) -> None:
    """Front models that are the old estimation mode's defaults become the new mode's, as in a
    file that names no `front_detectors` (and as `--mode` does): `estimation.mode=paper` runs
    the paper's two models unless the settings name the models too."""
    est = table.get("estimation")
    if not isinstance(est, dict) or est.get("mode") == scenario.estimation.mode:
        return
    if est.get("front_detectors") == list(DEFAULT_FRONT_DETECTORS[scenario.estimation.mode]):
        del est["front_detectors"]
