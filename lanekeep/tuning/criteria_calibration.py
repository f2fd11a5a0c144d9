"""Calibrate the shipped scenarios' fused-RMSE limits on tuning seeds.

    lanekeep bench --seed 1000 --seeds 5 --json tuning.json
    python -m lanekeep.tuning.criteria_calibration tuning.json            # the table only
    python -m lanekeep.tuning.criteria_calibration tuning.json --write    # and rewrite [criteria]

A scenario's `max_fused_rmse_m` used to be "twice one measured run": a loop could get much
worse and still pass. Here the limit is a statistical bound on what the loop as shipped does on
a seed nobody looked at, measured over K tuning seeds (>= TUNING_SEEDS_START; the bench scores
seeds below it, so the limit is never fitted on the episodes it then judges). The rule is
`fused_rmse_limit_m`; `criteria_block` writes it into a scenario file together with the numbers
it came from, `rewrite_criteria` puts the block in place of the file's own.

The command reads a `bench --seeds N --json` file run on tuning seeds with the scenarios as
shipped (no --front-detectors, --set, --mode, --weights, --seconds), and prints per scenario the
number of seeds K, the mean and sd of the fused RMSE over them, the file's limit and the new
one: the upper 99.9% prediction bound of one new seed's RMSE, rounded up to 0.1 cm. With
--write each shipped scenario's block from its "# Pass/fail" comment to the end of the file is
replaced by one saying the rule, this command, the date and the numbers, then `[criteria]` with
the new max_fused_rmse_m (no departure and the 0.5 m car error are geometry, kept). Scenarios
that are not shipped are shown, never written. A file that is not such a bench, or refused by
the rule: one line, exit 2. tools/calibrate_criteria.py runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import re
import sys
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lanekeep.scenario.schema import (
    Scenario,
    ScenarioError,
    load_scenario,
    parse_scenario,
    shipped_scenarios,
)
from lanekeep.tuning.scenarios import TUNING_SEEDS_START

MIN_SEEDS = 3  # two values give an sd, but t(0.999, 1) = 318: a limit no regression meets
PREDICTION_LEVEL = 0.999  # one-sided: a new seed's RMSE exceeds the limit ~0.1% of the time
STEP_CM = 0.1  # limits are rounded up to this
MAX_CAR_LATERAL_ERROR_M = 0.5  # geometry, not a measurement: see GEOMETRY
GEOMETRY = "half the 1.04 m between a wheel and the line: 3.7 m lane, 1.62 m track"
MARKER = "# Pass/fail"  # the first line of a scenario file's criteria block
WIDTH = 98  # comment lines are wrapped to this, as the shipped files are


@dataclass(frozen=True)
class Calibration:
    """What one scenario's bench over tuning seeds says, and the fused RMSE limit it gives."""

    scenario: str
    seeds: tuple[int, ...]
    mean_cm: float  # fused RMSE over the seeds
    sd_cm: float  # its sample sd (ddof 1)
    limit_m: float  # fused_rmse_limit_m of the seeds' values
    car_max_cm_max: float  # the car's largest |offset| from the lane centre, over every seed
    departures_max: int  # the most lane departures of one seed
    duration_s_min: float  # the shortest episode (a `bench --seconds` run is no calibration)


def fused_rmse_limit_m(values_cm: Sequence[float]) -> float:
    """The limit of one new seed's fused RMSE (m) from K tuning seeds' values (cm).

    mean + t(0.999, K-1) * sd * sqrt(1 + 1/K): the upper one-sided 99.9% normal prediction
    bound for one more draw, rounded UP to the next 0.1 cm. If a seed's RMSE is normal, an
    episode of the loop as calibrated fails it ~0.1% of the time, so a bench of 48 episodes
    (16 scenarios x 3 seeds) fails spuriously ~5% of the time (1 - 0.999^48), while a
    regression beyond the bound fails it (at K = 5 the margin is 7.9 sd: a limit to catch a
    gross regression, such as examples/sabotage.py's 5 cm bias, not a small one: that is what
    paired comparisons over seeds are for). With few seeds the sd itself is uncertain: the t
    quantile (not the normal's 3.09) widens the bound for that, and sqrt(1 + 1/K) adds the
    uncertainty of the mean. The values are per seed: a `bench --json` document's
    `episodes[i].sources.fused.rmse_cm`, never the document's mean.

    Raises ValueError for fewer than MIN_SEEDS values or a value that is not finite.
    """
    from scipy.stats import t

    values = [float(v) for v in values_cm]
    k = len(values)
    if k < MIN_SEEDS:
        raise ValueError(f"{k} seeds: the limit needs at least {MIN_SEEDS}")
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"a fused RMSE that is not a number in {values}")
    mean = sum(values) / k
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (k - 1))
    bound_cm = mean + float(t.ppf(PREDICTION_LEVEL, k - 1)) * sd * math.sqrt(1.0 + 1.0 / k)
    steps = math.ceil(round(bound_cm / STEP_CM, 9))  # round(): 1.2 / 0.1 is 11.999999999999998
    return round(steps * STEP_CM / 100.0, 6)


def _label_calibration(label: str, doc: Any) -> Calibration:
    """One label's Calibration; ValueError (one line, naming the label) when it is none."""
    if not isinstance(doc, Mapping) or not isinstance(doc.get("episodes"), list):
        raise ValueError(f"{label}: not a `bench --seeds N --json` document (no 'episodes')")
    changed = {k: v for k, v in (doc.get("overrides") or {}).items() if v not in (None, [], ())}
    if doc.get("mode") is not None:
        changed["mode"] = doc["mode"]
    if changed:
        raise ValueError(f"{label}: ran with {changed}: calibrate the scenario as shipped")
    episodes = doc["episodes"]
    try:
        seeds = tuple(int(e["seed"]) for e in episodes)
    except (TypeError, KeyError, ValueError):
        raise ValueError(f"{label}: an episode without a seed") from None
    scored = sorted(s for s in seeds if s < TUNING_SEEDS_START)
    if scored:
        raise ValueError(f"{label}: seeds {scored} are scored by the bench (tuning seeds are "
                         f">= {TUNING_SEEDS_START}: bench --seed {TUNING_SEEDS_START})")
    if len(seeds) < MIN_SEEDS:
        raise ValueError(f"{label}: {len(seeds)} seeds, at least {MIN_SEEDS} needed "
                         f"(bench --seeds {MIN_SEEDS} or more)")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"{label}: a seed repeats in {list(seeds)}")
    values = []
    for episode, seed in zip(episodes, seeds, strict=True):
        if not episode.get("completed") or episode.get("status", "completed") != "completed":
            raise ValueError(f"{label}: seed {seed} did not complete "
                             f"({episode.get('status') or episode.get('stop_reason')})")
        rmse = (episode.get("sources", {}).get("fused") or {}).get("rmse_cm")
        if rmse is None or not math.isfinite(rmse):
            raise ValueError(f"{label}: seed {seed} has no fused RMSE")
        values.append(float(rmse))
    mean = sum(values) / len(values)
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (len(values) - 1))
    car_max = [e.get("car_max_cm") for e in episodes]
    return Calibration(
        scenario=str(doc.get("scenario") or label), seeds=seeds, mean_cm=mean, sd_cm=sd,
        limit_m=fused_rmse_limit_m(values),
        car_max_cm_max=max(math.inf if c is None else float(c) for c in car_max),
        departures_max=max(int(e.get("lane_departures", 0)) for e in episodes),
        duration_s_min=min(float(e.get("duration_s", 0.0)) for e in episodes))


def calibrate(bench_doc: Any) -> dict[str, Calibration]:
    """Each scenario's Calibration, by name, from a `bench --seeds N --json` file's content
    (label -> document); the model-only loops ("SCENARIO@MODEL") are left out: the criteria
    judge the scenario's own loop.

    Raises ValueError (one line) for a file that is not such a document, or a scenario whose
    seeds include one the bench scores (< TUNING_SEEDS_START), that has fewer than MIN_SEEDS
    seeds, an episode that did not complete or has no fused RMSE, or that ran with the command
    line's changes (other detectors, controller, --set, --mode, --weights): a limit measured
    on another loop, or on the bench's own seeds, would judge nothing.
    """
    if not isinstance(bench_doc, Mapping) or not bench_doc:
        raise ValueError("not a `bench --json` file (expected one document per scenario)")
    found: dict[str, Calibration] = {}
    for label, doc in bench_doc.items():
        if "@" in str(label):
            continue
        cal = _label_calibration(str(label), doc)
        if cal.scenario in found:
            raise ValueError(f"{label}: scenario {cal.scenario!r} appears twice")
        found[cal.scenario] = cal
    if not found:
        raise ValueError("no scenario in the file (only model-only loops)")
    return found


def check_full_length(cal: Calibration, scenario: Scenario) -> None:
    """ValueError when an episode was cut short (`bench --seconds`): the RMSE of a few seconds
    is not that of the scenario the limit will judge."""
    if cal.duration_s_min < scenario.duration_s - scenario.control_period_s / 2.0:
        raise ValueError(f"{cal.scenario}: an episode ran {cal.duration_s_min:g} s of the "
                         f"scenario's {scenario.duration_s:g} s (bench without --seconds)")


def geometry_note(text: str) -> str:
    """The "(half the ... track)" explanation of the car-error limit in a scenario file's
    criteria comment (lane widths differ between files), else GEOMETRY."""
    lines = text.splitlines()
    start = next((i for i, line in enumerate(lines) if line.startswith(MARKER)), None)
    if start is None:
        return GEOMETRY
    comment = " ".join(line.lstrip("#").strip() for line in lines[start:]
                       if line.startswith("#"))
    found = re.search(r"\((half the [^()]*? track)\)", comment)
    return found.group(1) if found else GEOMETRY


def _seed_text(seeds: Sequence[int]) -> str:
    ordered = sorted(seeds)
    if ordered == list(range(ordered[0], ordered[0] + len(ordered))):
        return f"{ordered[0]}-{ordered[-1]}"
    return ", ".join(str(s) for s in ordered)


def _comment(text: str) -> list[str]:
    return textwrap.wrap(text, WIDTH - 2, initial_indent="# ", subsequent_indent="# ",
                         break_on_hyphens=False)


def criteria_block(cal: Calibration, command: str, date: str, geometry: str = GEOMETRY) -> str:
    """The TOML text from the "# Pass/fail" line to the end of a scenario file: the rule, how
    it was made (the command, the date, the seeds) and the numbers it was made from, then the
    `[criteria]` table. `geometry` explains the car-error limit (geometry_note of the file)."""
    departures = ("0 departures" if cal.departures_max == 0
                  else f"up to {cal.departures_max} departures (a loop the limits fail)")
    lines = [
        *_comment("Pass/fail (lanekeep/scoring/criteria.py; `run` / `bench` exit 1 when one "
                  "is not met)."),
        *_comment(f"Calibrated {date} on K = {len(cal.seeds)} tuning seeds "
                  f"({_seed_text(cal.seeds)}; the bench scores 0-{TUNING_SEEDS_START - 1}) by"),
        f"#   {command}",
        *_comment(f"Measured: fused RMSE {cal.mean_cm:.2f} cm mean, {cal.sd_cm:.2f} cm sd over "
                  f"the seeds; car max up to {cal.car_max_cm_max:.1f} cm; {departures}."),
        *_comment(f"Limits: no departure; the car within {MAX_CAR_LATERAL_ERROR_M:g} m of the "
                  f"lane centre ({geometry}); fused RMSE at most the upper 99.9% "
                  f"prediction bound of one new seed's, mean + t(0.999, K-1) sd sqrt(1 + 1/K), "
                  f"rounded up to 0.1 cm (lanekeep/tuning/criteria_calibration.py): a seed of "
                  f"this loop fails it ~0.1% of the time."),
        "[criteria]",
        "max_lane_departures = 0",
        f"max_car_lateral_error_m = {MAX_CAR_LATERAL_ERROR_M}",
        f"max_fused_rmse_m = {cal.limit_m:.3f}",
    ]
    return "\n".join(lines) + "\n"


def rewrite_criteria(path: str | Path, block: str) -> Scenario:
    """Replace everything from the "# Pass/fail" line to the end of the scenario file `path`
    with `block`, and return the scenario as it now loads. The new text is checked before it is
    written: a block that does not parse leaves the file as it was.

    Raises ValueError when the file has no "# Pass/fail" line (ScenarioError, a ValueError,
    when the result does not load).
    """
    path = Path(path)
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines(keepends=True)
    start = next((i for i, line in enumerate(lines) if line.startswith(MARKER)), None)
    if start is None:
        raise ValueError(f"{path}: no {MARKER!r} line to replace from")
    new = "".join(lines[:start]) + block
    parse_scenario(new, source=str(path))  # raises before the file is touched
    path.write_text(new, encoding="utf-8")
    return load_scenario(path)


class InputError(Exception):
    """A user error of the command line: one line, exit 2."""


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bench_json", type=Path,
                        help="the file of `lanekeep bench --seed 1000 --seeds N --json FILE`")
    parser.add_argument("--write", action="store_true",
                        help="rewrite each shipped scenario's criteria block with its new limit")
    parser.add_argument("--date", default=None, metavar="YYYY-MM-DD",
                        help="the date the block records (default: today)")
    return parser.parse_args(argv)


def _date(text: str | None) -> str:
    if text is None:
        return datetime.date.today().isoformat()
    try:
        return datetime.date.fromisoformat(text).isoformat()
    except ValueError:
        raise InputError(f"--date {text!r}: not a date YYYY-MM-DD") from None


def _load(path: Path) -> dict[str, Calibration]:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as err:
        raise InputError(f"{path}: {err.strerror or err}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise InputError(f"{path}: not JSON ({err})") from None
    try:
        return calibrate(doc)
    except ValueError as err:
        raise InputError(f"{path}: {err}") from None


def command_of(cal: Calibration, path: Path, scenarios: list[str]) -> str:
    """The commands that make this calibration again (the bench's scenarios named unless they
    are all the shipped ones, which a bare `bench` runs)."""
    names = "" if sorted(scenarios) == shipped_scenarios() else " " + " ".join(scenarios)
    return (f"lanekeep bench{names} --seed {min(cal.seeds)} --seeds {len(cal.seeds)} "
            f"--json {path.name} && python tools/calibrate_criteria.py {path.name} --write")


def _cm(limit_m: float | None) -> str:
    return "-" if limit_m is None else f"{100.0 * limit_m:.1f}"


def run(args: argparse.Namespace) -> int:
    date = _date(args.date)
    cals = _load(args.bench_json)
    shipped = set(shipped_scenarios())
    scenarios = {}
    for name, cal in cals.items():
        if name in shipped:
            scenarios[name] = load_scenario(name)
            try:
                check_full_length(cal, scenarios[name])
            except ValueError as err:
                raise InputError(f"{args.bench_json}: {err}") from None
    width = max(8, *(len(n) for n in cals))
    print(f"{'scenario':<{width}}  {'K':>3}  {'mean cm':>8}  {'sd cm':>6}  {'old cm':>6}  "
          f"{'new cm':>6}")
    for name, cal in cals.items():
        old = scenarios[name].criteria.max_fused_rmse_m if name in scenarios else None
        note = "" if name in scenarios else "  (not shipped: never written)"
        print(f"{name:<{width}}  {len(cal.seeds):>3}  {cal.mean_cm:>8.2f}  {cal.sd_cm:>6.2f}  "
              f"{_cm(old):>6}  {_cm(cal.limit_m):>6}{note}")
        if cal.departures_max > 0 or cal.car_max_cm_max > 100.0 * MAX_CAR_LATERAL_ERROR_M:
            print(f"calibrate_criteria: warning: {name} already fails on its tuning seeds "
                  f"({cal.departures_max} departures, car max {cal.car_max_cm_max:.1f} cm)",
                  file=sys.stderr)
    if not args.write:
        return 0
    for name, scenario in scenarios.items():
        cal = cals[name]
        path = Path(scenario.source)
        block = criteria_block(cal, command_of(cal, args.bench_json, list(cals)), date,
                               geometry_note(path.read_text(encoding="utf-8")))
        try:
            rewrite_criteria(path, block)
        except (ValueError, ScenarioError) as err:
            raise InputError(str(err)) from None
        print(f"wrote {path}: max_fused_rmse_m {scenario.criteria.max_fused_rmse_m} -> "
              f"{cal.limit_m:.3f}")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        return run(args)
    except InputError as err:
        print(f"calibrate_criteria: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
