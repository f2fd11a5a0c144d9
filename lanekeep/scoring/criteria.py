"""Pass/fail judgement of an episode: a scenario's `[criteria]`
(lanekeep.scenario.criteria.CriteriaConfig),
overridden by `run` / `bench` options, against its report.

Why: a CI job needs an exit code, not a table to read. Each limit is optional (None = not
checked) except one: an episode that did not complete (the car left the road, it hit another
vehicle, the physics blew up, it was stopped) fails, whatever its numbers say, since a partial
episode's metrics describe only the part that was driven; so a collision always fails.

Verdicts are in SI units (m), like the scenario's keys; the report's table shows cm elsewhere.
"""

from __future__ import annotations

import argparse
import dataclasses
import math

from lanekeep.core.config_io import ConfigError, InvalidValue
from lanekeep.scenario.criteria import CriteriaConfig
from lanekeep.scoring.metrics import EpisodeReport, Verdict

# Command-line option -> CriteriaConfig field (the options override the scenario file's table).
OPTIONS = {
    "--max-departures": "max_lane_departures",
    "--max-lateral-error": "max_car_lateral_error_m",
    "--max-fused-rmse": "max_fused_rmse_m",
    "--off-road-distance": "off_road_distance_m",
}
_HELP = {
    "max_lane_departures": ("N", int, "fail when a wheel crossed an ego-lane boundary more than "
                                      "N times"),
    "max_car_lateral_error_m": ("M", float, "fail when the car's largest true offset from the "
                                            "lane centre exceeds M metres"),
    "max_fused_rmse_m": ("M", float, "fail when the MMAE output's offset RMSE exceeds M metres"),
    "off_road_distance_m": ("M", float, "end the episode as off road once the car is M metres "
                                        "from the lane centre (always: all four wheels off the "
                                        "paved surface)"),
}


def add_options(parser: argparse.ArgumentParser) -> None:
    """The criteria options of `run` and `bench`; each overrides the scenario's [criteria]."""
    group = parser.add_argument_group(
        "pass/fail criteria", "override the scenario's [criteria] table; exit code 1 when one "
                              "is not met (an episode that left the road or hit another "
                              "vehicle always fails)")
    for option, key in OPTIONS.items():
        metavar, kind, text = _HELP[key]
        group.add_argument(option, dest=key, metavar=metavar, type=kind, default=None, help=text)


def overrides_from_args(args: argparse.Namespace) -> dict[str, float | int]:
    """The criteria given on the command line, checked: ConfigError naming the option when a
    value is out of range (exit 2, before anything runs)."""
    given = {key: getattr(args, key) for key in OPTIONS.values()
             if getattr(args, key, None) is not None}
    try:
        CriteriaConfig(**given)
    except InvalidValue as err:
        option = next(opt for opt, key in OPTIONS.items() if key == err.key)
        raise ConfigError("", option, err.message) from None
    return given


def with_overrides(config: CriteriaConfig, overrides: dict | None) -> CriteriaConfig:
    """`config` with the command line's values in place of the file's."""
    return dataclasses.replace(config, **overrides) if overrides else config


def _at_most(name: str, limit: float | int | None, value: float | int | None
             ) -> Verdict | None:
    if limit is None:
        return None
    known = value is not None and not (isinstance(value, float) and math.isnan(value))
    return Verdict(name, limit, value if known else None, known and value <= limit)


def evaluate(report: EpisodeReport, config: CriteriaConfig) -> tuple[Verdict, ...]:
    """The verdicts of `report` under `config`: "status" always (it must be "completed"),
    then each limit that is set. A fused RMSE with no valid estimate at all fails."""
    fused = report.sources.get("fused")
    checks = [
        ("lane_departures", config.max_lane_departures, report.lane_departures),
        ("car_lateral_error_m", config.max_car_lateral_error_m, report.car_max_cm / 100.0),
        ("fused_rmse_m", config.max_fused_rmse_m,
         None if fused is None else fused.rmse_cm / 100.0),
    ]
    verdicts = [Verdict("status", "completed", report.status, report.status == "completed")]
    verdicts += [v for v in (_at_most(*check) for check in checks) if v is not None]
    return tuple(verdicts)


def judge(report: EpisodeReport, config: CriteriaConfig) -> EpisodeReport:
    """`report` carrying its verdicts (`report.passed`, the table's and the JSON's criteria)."""
    return dataclasses.replace(report, criteria=evaluate(report, config))


def for_run(config: CriteriaConfig, overrides: dict | None, full_length: bool
            ) -> CriteriaConfig:
    """The criteria a run is judged by: the file's with the command line's in place, less the
    file's fused RMSE limit when the run is cut short on purpose (`full_length` False:
    `--seconds` below the scenario's duration). That limit is calibrated on whole episodes
    (`python -m lanekeep.tuning.criteria_calibration`), and the first seconds, while the
    trackers settle, weigh far more in a short run. A limit given on the command line is judged
    whatever the length."""
    judged = with_overrides(config, overrides)
    if not full_length and "max_fused_rmse_m" not in (overrides or {}):
        judged = dataclasses.replace(judged, max_fused_rmse_m=None)
    return judged


def failure_message(report: EpisodeReport) -> str:
    """One line naming each failed criterion with its value and limit ("" if all passed)."""
    parts = []
    for v in report.failed_criteria():
        if v.name == "status":
            parts.append(f"status {v.value}" + (f" ({report.stop_reason})"
                                                if report.stop_reason else ""))
        else:
            value = "none" if v.value is None else f"{v.value:.4g}"
            parts.append(f"{v.name} {value} > {v.limit:g}")
    return "; ".join(parts)
