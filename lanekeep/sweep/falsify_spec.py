"""Falsification specs: a sweep file whose parameters may be ranges, and an objective.

    name = "sharp_turn_falsify"
    base = "sharp_turn_shade.toml"
    seconds = 8.0
    render = { width = 320, height = 180 }
    [parameters]
    "target_speed_mps" = { low = 10.0, high = 22.0 }            # a continuous range
    "conditions.vehicles[0].s_m" = { low = 20, high = 80, integer = true }
    "control.controller" = ["pid", "stanley"]                   # a choice
    [objective]                                                  # optional: criteria overrides
    max_car_lateral_error_m = 0.5

The plain sweep keys (`name`, `base`, `seeds`, `seconds`, `metrics`, `render`) mean what they
mean in a sweep, and the file goes through the sweep's own parser (lanekeep/sweep/spec.py) with
each range standing as its two ends, so every key, index and end value is checked by the
scenario loader before anything runs.

Each candidate is a whole scenario table: the base's, with the parameters and the seed set,
`duration_s` = `seconds` and `[criteria]` = the objective's. That table is what runs and what a
failing case's TOML holds, so `lanekeep run FILE` judges it by the same criteria and length.
As `run --seconds` does (lanekeep/scoring/criteria.py `for_run`), a run shorter than the base's
duration drops the base's fused-RMSE limit (calibrated on whole episodes) unless the objective
sets it.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lanekeep.scenario.keys import parse_key, scenario_table
from lanekeep.scenario.schema import scenario_from_dict
from lanekeep.sweep.falsify_objective import OBJECTIVE_KEYS, objective_of
from lanekeep.sweep.fields import SweepError
from lanekeep.sweep.spec import SweepSpec, parse_sweep

RANGE_KEYS = ("low", "high", "integer")


@dataclass(frozen=True)
class Dimension:
    """One searched parameter: a choice among values, or a float / integer range."""

    key: str  # dotted scenario key
    kind: str  # "choice", "float" or "int"
    choices: tuple[Any, ...] = ()  # choice: the values
    low: float = 0.0  # float / int: both ends included
    high: float = 0.0
    base: Any = None  # the base scenario's value: where shrinking heads

    def describe(self) -> str:
        if self.kind == "choice":
            return f"{self.key} in {list(self.choices)}"
        return f"{self.key} in [{self.low:g}, {self.high:g}]" + (
            " (integer)" if self.kind == "int" else "")


@dataclass(frozen=True)
class FalsifySpec:
    sweep: SweepSpec  # base, seeds, seconds, metrics, render; parameters = the ranges' ends
    dimensions: tuple[Dimension, ...]
    criteria: dict  # the [criteria] table every candidate is judged by

    @property
    def name(self) -> str:
        return self.sweep.name

    @property
    def source(self) -> str:
        return self.sweep.source

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(d.key for d in self.dimensions)

    def table(self, values: tuple[Any, ...], seed: int) -> dict:
        """The whole scenario table of a candidate (module docstring)."""
        table = self.sweep.cell_table(values, seed)
        if self.sweep.seconds is not None:
            table["duration_s"] = self.sweep.seconds
        table["criteria"] = copy.deepcopy(self.criteria)
        return table

    def fingerprint(self) -> str:
        """What an `--out` folder must have been searched with to resume there."""
        text = json.dumps({"sweep": self.sweep.fingerprint(),
                           "dimensions": [[d.key, d.kind, list(d.choices), d.low, d.high]
                                          for d in self.dimensions],
                           "criteria": self.criteria}, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()


def table_id(table: dict) -> str:
    """A candidate episode's identity: the hash of its whole scenario table (what resuming
    and the shrinking's cache recognise)."""
    text = json.dumps(table, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _number(source: str, where: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SweepError(source, where, f"must be a number, got {value!r}")
    return value


def _dimension(source: str, key: str, value: Any) -> tuple[Dimension, list]:
    """A parameter of the file as a Dimension, and the values the sweep parser checks."""
    where = f"parameters.{key}"
    if isinstance(value, list):
        if not value:
            raise SweepError(source, where, "needs at least one value")
        return Dimension(key, "choice", choices=tuple(value)), value
    if not isinstance(value, dict):
        raise SweepError(source, where, "must be an array of values (a choice) or a range "
                                        "{ low, high } (integer = true for whole numbers)")
    if not set(value) & set(RANGE_KEYS):  # TOML read an unquoted dotted key as tables
        raise SweepError(source, where, f"a dotted key needs quotes: \"{key}.{next(iter(value))}"
                                        f"\" = {{ low = ..., high = ... }}")
    for k in value:
        if k not in RANGE_KEYS:
            raise SweepError(source, f"{where}.{k}", f"unknown key (known keys: "
                                                     f"{', '.join(RANGE_KEYS)})")
    for k in ("low", "high"):
        if k not in value:
            raise SweepError(source, f"{where}.{k}", "required key is missing")
    integer = value.get("integer", False)
    if not isinstance(integer, bool):
        raise SweepError(source, f"{where}.integer", f"must be true or false, got {integer!r}")
    low = _number(source, f"{where}.low", value["low"])
    high = _number(source, f"{where}.high", value["high"])
    if not low < high:
        raise SweepError(source, where, f"low must be < high, got {low!r} and {high!r}")
    if integer:
        for k, v in (("low", low), ("high", high)):
            if v != int(v):
                raise SweepError(source, f"{where}.{k}", f"must be a whole number with "
                                                         f"integer = true, got {v!r}")
        return Dimension(key, "int", low=int(low), high=int(high)), [int(low), int(high)]
    return Dimension(key, "float", low=float(low), high=float(high)), [float(low), float(high)]


def _base_value(base_table: dict, source: str, key: str) -> Any:
    """The base scenario's value at `key`, its default where the file leaves it out."""
    full = scenario_table(scenario_from_dict(base_table, source))
    node: Any = full
    for part in parse_key(key):
        node = node[part]
    return node


def parse_falsify(text: str, source: str = "<string>") -> FalsifySpec:
    """A falsification spec from TOML text (SweepError naming the file and key)."""
    import tomli_w

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SweepError(source, "", f"invalid TOML: {err}") from None
    objective = data.pop("objective", None)
    params = data.get("parameters")
    dims, ends = [], {}
    if isinstance(params, dict):
        for key, value in params.items():
            dim, values = _dimension(source, key, value)
            dims.append(dim)
            ends[key] = values
        data["parameters"] = ends
    sweep = parse_sweep(tomli_w.dumps(data), source)  # base, keys, every end value checked
    criteria = dict(sweep.base_table.get("criteria", {}))
    short = sweep.seconds is not None and sweep.seconds < _base_value(
        sweep.base_table, source, "duration_s")
    if short and "max_fused_rmse_m" not in (objective or {}):
        criteria.pop("max_fused_rmse_m", None)
    criteria = objective_of(source, objective, criteria)
    criteria = {k: v for k, v in criteria.items() if k in OBJECTIVE_KEYS and v is not None}
    dims = [Dimension(d.key, d.kind, d.choices, d.low, d.high,
                      _base_value(sweep.base_table, source, d.key)) for d in dims]
    return FalsifySpec(sweep, tuple(dims), criteria)


def load_falsify(path: str | Path) -> FalsifySpec:
    path = Path(path)
    if not path.is_file():
        raise SweepError(str(path), "", "no such falsify file")
    return parse_falsify(path.read_text(encoding="utf-8"), source=str(path))

