"""Pass/fail limits of the shipped scenarios, calibrated on tuning seeds.

A scenario's `max_fused_rmse_m` used to be "twice one measured run": a loop could get much
worse and still pass. Here the limit is a statistical bound on what the loop as shipped does on
a seed nobody looked at, measured over K tuning seeds (>= TUNING_SEEDS_START; the bench scores
seeds below it, so the limit is never fitted on the episodes it then judges):

    lanekeep bench --seed 1000 --seeds 5 --json tuning.json
    python tools/calibrate_criteria.py tuning.json --write

The rule is `fused_rmse_limit_m`; `criteria_block` writes it into a scenario file together with
the numbers it came from, `rewrite_criteria` puts the block in place of the file's own.
"""

from __future__ import annotations

import math
import re
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lanekeep.scenario.schema import Scenario, load_scenario, parse_scenario
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
