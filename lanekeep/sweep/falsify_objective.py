"""The objective of a falsification search: a robustness margin that is negative exactly when
the drive fails its criteria.

Why a margin and not pass/fail: a search needs to know how close a passing drive came to
failing, so it can head there. The margin is read from the verdicts the episode was judged by
(lanekeep/scoring/criteria.py), so "margin < 0" and "`lanekeep run` exits 1" are one fact:

  - a limit L on a value v (`car_lateral_error_m`, `fused_rmse_m`): the normalised slack
    (L - v) / L: 1 at v = 0, 0 at the limit, negative past it (-1 at twice the limit);
  - `lane_departures` (a count, limit L >= 0): (L + 0.5 - n) / (L + 0.5): +1 for none under a
    limit of 0, -1 for one departure; the car's lateral error gives the continuous signal;
  - a value the episode does not have (a fused RMSE with no estimate) and an episode that did
    not complete (off the road, unstable): -1;
  - the margin is the smallest of these; its criterion is the binding one.

The criteria are the base scenario's `[criteria]`, with the spec's `[objective]` table in place
of any of its keys (the same keys: `max_lane_departures`, `max_car_lateral_error_m`,
`max_fused_rmse_m`, `off_road_distance_m`), e.g. `max_car_lateral_error_m = 0.3` to search for
drives that come within 0.3 m of the lane's edge of tolerance.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

from lanekeep.core.config_io import InvalidValue
from lanekeep.scenario.criteria import CriteriaConfig
from lanekeep.sweep.fields import SweepError

OBJECTIVE_KEYS = tuple(f.name for f in fields(CriteriaConfig))
NOT_COMPLETED = -1.0  # the margin of a drive that stopped early or has no value to judge


def objective_of(source: str, value: Any, base_criteria: dict) -> dict:
    """The criteria table the candidates are judged by: the base's `[criteria]` with the
    spec's `[objective]` keys in place (SweepError naming the key when one is bad)."""
    if value is None:
        value = {}
    if not isinstance(value, dict):
        raise SweepError(source, "objective", "must be a table of criteria limits (keys: "
                                              f"{', '.join(OBJECTIVE_KEYS)})")
    for key in value:
        if key not in OBJECTIVE_KEYS:
            raise SweepError(source, f"objective.{key}",
                             f"unknown key (known keys: {', '.join(OBJECTIVE_KEYS)})")
    merged = {**base_criteria, **value}
    try:
        CriteriaConfig(**merged)
    except InvalidValue as err:
        raise SweepError(source, f"objective.{err.key}", err.message) from None
    except TypeError as err:  # a base [criteria] key the schema lacks: its loader says so
        raise SweepError(source, "objective", str(err)) from None
    if not any(merged.get(k) is not None for k in OBJECTIVE_KEYS if k != "off_road_distance_m"):
        raise SweepError(source, "objective", "no criterion to search against: the base "
                                              "scenario has no [criteria] limit; set one here")
    return merged


def slack(verdict: dict) -> float:
    """One verdict's normalised slack (module docstring): >= 0 exactly when it passed."""
    name, limit, value = verdict["name"], verdict["limit"], verdict["value"]
    if name == "status":
        return math.inf if verdict["passed"] else NOT_COMPLETED
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return NOT_COMPLETED
    if name == "lane_departures":
        return (limit + 0.5 - value) / (limit + 0.5)
    return (limit - value) / limit


def margin_of(report: dict | None) -> tuple[float | None, str]:
    """(margin, binding criterion) of a judged report (EpisodeReport.to_dict()); (None, "")
    for an episode that raised (no report)."""
    if report is None:
        return None, ""
    verdicts = report.get("criteria") or ()
    if not verdicts:
        raise ValueError("the report was not judged: no criteria verdicts")
    worst = min(verdicts, key=slack)
    value = slack(worst)
    return (1.0, "") if math.isinf(value) else (float(value), worst["name"])
