"""Sweep files: a base scenario, parameters addressed by dotted keys, seeds; expanded to cells.

A researcher's question ("how does the fused error grow with rain and curvature, over 20
seeds?") is a grid of episodes. The file names the grid; each cell is the base scenario's TOML
table with the parameters set, read by the same strict loader as a scenario file
(`lanekeep.scenario.schema.scenario_from_dict`), so a cell can hold nothing a file could not.
A cell's seed N is `Scenario.seed = N`, as `lanekeep run --seed N` and `bench` take it, and its
nominal seed is the base file's own `seed` (`SweepSpec.nominal_seed`): on that seed the cell
drives the file's start and traffic, on any other it draws them (lanekeep/scenario/nuisance.py).

    base = "heavy_rain"                # shipped name, or a path relative to this file
    seeds = 4                          # seeds 0..3, or a list [3, 7]
    seconds = 10.0                     # simulated seconds of each episode (default: the base's)
    metrics = ["rmse_cm", "car_rms_cm"]
    render = { width = 320, height = 180 }   # optional camera size for speed
    [parameters]
    "conditions.rain" = { start = 0.0, stop = 1.0, num = 3 }
    "road.segments[2].curvature_1pm" = [0.005, 0.01]
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import itertools
import json
import math
import tomllib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lanekeep.core.config_io import ConfigError
from lanekeep.scenario.keys import check_key, parse_key, set_key
from lanekeep.scenario.schema import Scenario, load_scenario, scenario_from_dict
from lanekeep.scoring.metrics import EpisodeReport
from lanekeep.sweep.fields import (
    EPISODE_METRICS,
    SOURCE_METRICS,
    SweepError,
    metrics_of,
    render_of,
    seeds_of,
    values_of,
)

KNOWN_KEYS = ("name", "base", "parameters", "seeds", "seconds", "metrics", "render")


@dataclass(frozen=True)
class Parameter:
    key: str  # dotted key into the scenario table, e.g. "road.segments[1].curvature_1pm"
    values: tuple[Any, ...]


@dataclass(frozen=True)
class Cell:
    """One episode of the sweep: the parameters' values (in the file's order) and a seed."""

    cell_id: str  # stable hash of parameters + seed: what resuming recognises
    values: tuple[Any, ...]
    seed: int
    table: dict  # the scenario's TOML table with everything set
    nominal_seed: int  # the base file's own seed: the cell's nominal drive (module docstring)


@dataclass(frozen=True)
class SweepSpec:
    name: str
    source: str  # the sweep file
    base: str
    base_table: dict
    parameters: tuple[Parameter, ...]
    seeds: tuple[int, ...]
    seconds: float | None
    metrics: tuple[str, ...]
    render: tuple[int, int] | None

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(p.key for p in self.parameters)

    @property
    def nominal_seed(self) -> int:
        """The base file's own seed (the schema's 0 when it gives none): a cell on it drives
        the file's start and traffic, as `lanekeep run BASE` does."""
        return int(self.base_table.get("seed", 0))

    def fingerprint(self) -> str:
        """What must match for `--out` to resume: the file's content and the base scenario."""
        text = json.dumps({"name": self.name, "base": self.base_table,
                           "parameters": [[p.key, list(p.values)] for p in self.parameters],
                           "seeds": list(self.seeds), "seconds": self.seconds,
                           "metrics": list(self.metrics), "render": self.render},
                          sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()

    def cells(self) -> list[Cell]:
        """Every (parameter values, seed) combination, the last parameter varying fastest."""
        out = []
        for values in itertools.product(*(p.values for p in self.parameters)):
            for seed in self.seeds:
                out.append(Cell(cell_id(self.keys, values, seed), values, seed,
                                self.cell_table(values, seed), self.nominal_seed))
        return out

    def cell_table(self, values: tuple[Any, ...], seed: int) -> dict:
        table = copy.deepcopy(self.base_table)
        for key, value in zip(self.keys, values, strict=True):
            set_key(table, parse_key(key), copy.deepcopy(value))
        table["seed"] = seed
        if self.render is not None:
            camera = table.setdefault("camera", {})
            camera["width"], camera["height"] = self.render
        return table


def cell_id(keys: tuple[str, ...], values: tuple[Any, ...], seed: int) -> str:
    text = json.dumps({"parameters": dict(zip(keys, values, strict=True)), "seed": seed},
                      sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def cell_scenario(table: dict, source: str, nominal_seed: int) -> Scenario:
    """A cell's scenario through the scenario files' loader (ScenarioError names the key),
    its nominal seed the base file's (`SweepSpec.nominal_seed`): built in memory, it would
    otherwise be 0, and seed N would draw another drive in a sweep than in `bench`."""
    return dataclasses.replace(scenario_from_dict(table, source), nominal_seed=nominal_seed)


def _base(source: str, base: Any) -> tuple[str, dict]:
    """The base scenario's raw TOML table (a path is relative to the sweep file)."""
    if not isinstance(base, str) or not base:
        raise SweepError(source, "base", "must name a shipped scenario or a .toml file")
    ref: str | Path = base
    if base.endswith(".toml") or "/" in base:
        ref = Path(base) if Path(base).is_absolute() else Path(source).parent / base
    try:
        scenario = load_scenario(ref)
    except ConfigError as err:
        raise SweepError(source, "base", " ".join(str(err).split())) from None
    return base, tomllib.loads(Path(scenario.source).read_text(encoding="utf-8"))


def parse_sweep(text: str, source: str = "<string>") -> SweepSpec:
    """A sweep from TOML text, every cell checked by the scenario loader (SweepError)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SweepError(source, "", f"invalid TOML: {err}") from None
    for key in data:
        if key not in KNOWN_KEYS:
            raise SweepError(source, key, f"unknown key (known keys: {', '.join(KNOWN_KEYS)})")
    if "base" not in data:
        raise SweepError(source, "base", "required key is missing")
    base, base_table = _base(source, data["base"])
    params = data.get("parameters", {})
    if not isinstance(params, dict) or not params:
        raise SweepError(source, "parameters", "needs at least one parameter to sweep")
    parameters = []
    for key, spec in params.items():
        try:
            check_key(key, base_table, seed_rule="use `seeds`")
        except ValueError as err:
            raise SweepError(source, f"parameters.{key}", str(err)) from None
        parameters.append(Parameter(key, values_of(source, key, spec)))
    seconds = data.get("seconds")
    if seconds is not None and (isinstance(seconds, bool) or not isinstance(seconds, (int, float))
                                or not math.isfinite(seconds) or seconds <= 0):
        raise SweepError(source, "seconds", f"must be a number > 0, got {seconds!r}")
    name = data.get("name", Path(source).stem)
    if not isinstance(name, str) or not name:
        raise SweepError(source, "name", "must be a non-empty string")
    spec = SweepSpec(
        name=name, source=source, base=base, base_table=base_table,
        parameters=tuple(parameters), seeds=seeds_of(source, data.get("seeds", 1)),
        seconds=None if seconds is None else float(seconds),
        metrics=metrics_of(source, data.get("metrics", list(SOURCE_METRICS + EPISODE_METRICS))),
        render=None if "render" not in data else render_of(source, data["render"]))
    check_values(spec)
    return spec


def one_at_a_time(spec: SweepSpec) -> Iterator[tuple[Parameter, Any, tuple[Any, ...]]]:
    """(parameter, value, every parameter's value) for each value of each parameter, the
    others at their first value: what a check that names the bad value's parameter tries."""
    for i, p in enumerate(spec.parameters):
        for value in p.values:
            yield p, value, tuple(value if j == i else q.values[0]
                                  for j, q in enumerate(spec.parameters))


def check_values(spec: SweepSpec) -> None:
    """Every parameter value through the scenario loader, one parameter at a time on the
    base (a bad value names its parameter), then every combination (cross-field rules)."""
    for p, value, values in one_at_a_time(spec):
        _load(spec, values, f"parameters.{p.key}", f"value {value!r}")
    for values in itertools.product(*(p.values for p in spec.parameters)):
        _load(spec, values, "parameters", f"cell {dict(zip(spec.keys, values, strict=True))}")


def _load(spec: SweepSpec, values: tuple, key: str, what: str) -> Scenario:
    try:
        scenario = cell_scenario(spec.cell_table(values, spec.seeds[0]), spec.source,
                                 spec.nominal_seed)
    except ConfigError as err:
        raise SweepError(spec.source, key, f"{what} makes an invalid scenario: "
                                           f"{err.key}: {err.message}") from None
    if spec.seconds is not None and round(spec.seconds / scenario.control_period_s) < 1:
        raise SweepError(spec.source, "seconds", f"{spec.seconds:g} s is less than one control "
                                                 f"step ({scenario.control_period_s:g} s)")
    return scenario


def check_world(spec: SweepSpec,
                table: Callable[[tuple[Any, ...], int], dict] | None = None) -> None:
    """Each parameter value, one at a time on the base, through the scenario's one validation
    path (lanekeep/loop/checks.py `check_scenario`: the world's cross-field checks, detector
    and controller names) before any worker starts: a bad value is one line naming its
    parameter (exit 2). `table(values, seed)` makes a candidate's scenario table (a
    falsification's, lanekeep/sweep/falsify_spec.py `FalsifySpec.table`); the sweep's cell
    table by default. Slower than `check_values` (30-160 ms a value): `lanekeep sweep` and
    `lanekeep falsify` call it, parsing does not."""
    from lanekeep.loop.checks import check_scenario

    table = table or spec.cell_table
    for p, value, values in one_at_a_time(spec):
        scenario = cell_scenario(table(values, spec.seeds[0]), spec.source, spec.nominal_seed)
        try:
            check_scenario(scenario, spec.seconds)
        except ConfigError as err:
            raise SweepError(spec.source, f"parameters.{p.key}",
                             f"value {value!r} makes an invalid scenario: "
                             f"{' '.join(str(err).split())}") from None


def load_sweep(path: str | Path) -> SweepSpec:
    path = Path(path)
    if not path.is_file():
        raise SweepError(str(path), "", "no such sweep file")
    return parse_sweep(path.read_text(encoding="utf-8"), source=str(path))


def report_metrics(report: EpisodeReport, metrics: tuple[str, ...]) -> dict[str, Any]:
    """The kept metrics of a report: episode ones by name, per-source ones as "METRIC@SOURCE"
    (e.g. "rmse_cm@fused", "rmse_cm@hough:track")."""
    out: dict[str, Any] = {}
    for m in metrics:
        if m in EPISODE_METRICS:
            out[m] = getattr(report, m)
        else:
            for source, values in report.sources.items():
                out[f"{m}@{source}"] = getattr(values, m)
    return out
