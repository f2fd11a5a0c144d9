"""The `[criteria]` table of a scenario: an episode's pass/fail limits and what marks it for the
regression gate (judged by lanekeep/scoring/criteria.py).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import setting

_MARGIN_TEXT = re.compile(r"[a-z_:]+(\.[a-z_]+)?=\d+(\.\d*)?(,\d+(\.\d*)?%)?")


@dataclass(frozen=True)
class CriteriaConfig:
    """Pass/fail limits of an episode (`[criteria]`, judged by lanekeep/scoring/criteria.py); None =
    not checked. An episode that leaves the road, hits another vehicle or stops early fails
    whatever these say."""

    max_lane_departures: int | None = setting(None, "Pass limit: times a wheel crossed an "
                                              "ego-lane boundary.",
                                              allowed=">= 0; unset = not checked")
    max_car_lateral_error_m: float | None = setting(
        None, "Pass limit: the car's largest |true offset|.", allowed="> 0; unset = not checked")
    max_fused_rmse_m: float | None = setting(None, "Pass limit: offset RMSE of the MMAE output.",
                                             allowed="> 0; unset = not checked")
    # Not a limit: marks a two-mode scenario for the regression gate (lanekeep/report/
    # regression.py): an episode with a fused RMSE above it is a bad episode.
    bad_episode_fused_rmse_m: float | None = setting(
        None, "Not a pass limit: marks a two-mode scenario (markings hidden on some drives); an "
        "episode whose fused RMSE exceeds it is a bad episode, and the regression gate (`bench "
        "--baseline`) compares the rate of bad episodes instead of the RMSE.",
        allowed="> 0; unset = one mode")
    # Not a limit: this scenario's own margins of practical relevance for the regression gate
    # (`bench --baseline`), "METRIC=ABS[,REL%]" each, e.g. "car_max_cm=2" (cm) for a noisy one;
    # the command line's `--margin` wins.
    margins: tuple[str, ...] = setting((), "Not a pass limit: this scenario's margins of "
                                       "practical relevance for the regression gate (`bench "
                                       '--baseline`), each "METRIC=ABS[,REL%]" as `--margin` '
                                       "takes them (docs/statistics.md#margins); the command "
                                       "line's win.", allowed="METRIC=ABS[,REL%] each")
    # Ends the episode as off road once the car's centre is this far (m) from the ego lane's
    # centre; None: only when all four wheels are off the paved surface (always checked).
    off_road_distance_m: float | None = setting(
        None, "End the episode as off road once the car's centre is this far from the ego lane's "
        "centre.", allowed="> 0; unset = only when all wheels leave the pavement")

    def __post_init__(self):
        if self.max_lane_departures is not None and not self.max_lane_departures >= 0:
            raise InvalidValue("max_lane_departures",
                               f"must be >= 0, got {self.max_lane_departures}")
        for text in self.margins:
            if not _MARGIN_TEXT.fullmatch(text):
                raise InvalidValue("margins", f"{text!r}: expected METRIC=ABS[,REL%], e.g. "
                                              "fused.rmse_cm=0.2,5%")
        for key in ("max_car_lateral_error_m", "max_fused_rmse_m", "bad_episode_fused_rmse_m",
                    "off_road_distance_m"):
            value = getattr(self, key)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise InvalidValue(key, f"must be a number > 0 (m), got {value}")
