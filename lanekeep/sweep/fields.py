"""The plain fields of a sweep file (lanekeep/sweep/spec.py): value ranges, seeds, metric
names and the render size, each checked as strictly as a scenario key (SweepError names the
file and the key), so a typo fails before any episode runs.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

from lanekeep.core.config_io import ConfigError
from lanekeep.scoring import metrics as scoring_metrics
from lanekeep.scoring.metrics import SourceReport

SOURCE_METRICS = tuple(f.name for f in fields(SourceReport))  # one column per source each
# and its length, and its safety among other vehicles (min_ttc_s, min_gap_m, ...)
EPISODE_METRICS = (*scoring_metrics.EPISODE_METRICS, "duration_s", "steps",
                   *scoring_metrics.SAFETY_METRICS)


class SweepError(ConfigError):
    """A sweep file is invalid; the message names the file and the key."""


def values_of(source: str, key: str, spec: Any) -> tuple[Any, ...]:
    where = f"parameters.{key}"
    if isinstance(spec, list):
        if not spec:
            raise SweepError(source, where, "needs at least one value")
        return tuple(spec)
    if not isinstance(spec, dict):
        raise SweepError(source, where, "must be an array of values or a range table "
                                        "{start, stop, num} / {start, stop, step}")
    allowed = {"start", "stop", "num", "step"}
    if not allowed & set(spec):  # TOML read `conditions.rain = [...]` as nested tables
        raise SweepError(source, where, f"a dotted key needs quotes: \"{key}.{next(iter(spec))}"
                                        f"\" = [...]")
    for k in spec:
        if k not in allowed:
            raise SweepError(source, f"{where}.{k}", "unknown key (known keys: num, start, "
                                                     "step, stop)")
    if "start" not in spec or "stop" not in spec or ("num" in spec) == ("step" in spec):
        raise SweepError(source, where, "a range needs start, stop and one of num / step")
    start, stop = spec["start"], spec["stop"]
    for k in ("start", "stop", "step"):
        v = spec.get(k, 1.0)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise SweepError(source, f"{where}.{k}", f"must be a number, got {v!r}")
    if "num" in spec:
        num = spec["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise SweepError(source, f"{where}.num", f"must be an integer >= 1, got {num!r}")
        if num == 1:
            return (start,)
        return tuple(round(start + (stop - start) * i / (num - 1), 12) for i in range(num))
    step = spec["step"]
    if step == 0 or (stop - start) / step < 0:
        raise SweepError(source, f"{where}.step", f"{step!r} never goes from {start!r} "
                                                  f"to {stop!r}")
    count = int(math.floor((stop - start) / step + 1e-9)) + 1
    ints = all(isinstance(v, int) for v in (start, step))
    return tuple(start + i * step if ints else round(start + i * step, 12)
                 for i in range(count))


def seeds_of(source: str, value: Any) -> tuple[int, ...]:
    if isinstance(value, int) and not isinstance(value, bool) and value >= 1:
        return tuple(range(value))
    if (isinstance(value, list) and value and len(set(value)) == len(value)
            and all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in value)):
        return tuple(value)
    raise SweepError(source, "seeds", f"must be a count >= 1 or a list of distinct seeds "
                                      f">= 0, got {value!r}")


def metrics_of(source: str, value: Any) -> tuple[str, ...]:
    known = SOURCE_METRICS + EPISODE_METRICS
    if not isinstance(value, list) or not value or not all(isinstance(m, str) for m in value):
        raise SweepError(source, "metrics", "must be a non-empty array of metric names")
    for i, m in enumerate(value):
        if m not in known:
            raise SweepError(source, f"metrics[{i}]", f"unknown metric {m!r} (known: "
                                                      f"{', '.join(known)})")
    return tuple(dict.fromkeys(value))


def render_of(source: str, value: Any) -> tuple[int, int]:
    if not isinstance(value, dict):
        raise SweepError(source, "render", "must be a table {width, height}")
    for k in value:
        if k not in ("width", "height"):
            raise SweepError(source, f"render.{k}", "unknown key (known keys: height, width)")
    try:
        w, h = value["width"], value["height"]
    except KeyError as err:
        raise SweepError(source, f"render.{err.args[0]}", "required key is missing") from None
    for k, v in (("width", w), ("height", h)):
        if isinstance(v, bool) or not isinstance(v, int) or not 16 <= v <= 4096:
            raise SweepError(source, f"render.{k}", f"must be an integer in 16..4096, got {v!r}")
    return w, h
