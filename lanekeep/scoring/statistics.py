"""Spread and verdicts over seeds: the intervals behind every "better" lanekeep prints.

Why these intervals:
  - a metric's mean over seeds gets Student's t interval (mean +- t(0.975, n-1) * sd / sqrt(n)).
    Benches run 3-10 seeds; at such n a bootstrap percentile interval is too narrow (it cannot
    reach beyond the values seen: with 3 seeds it covers far less than 95%), while t is exact
    for normal errors and robust enough for the roughly symmetric per-seed RMSEs we measure;
  - a paired comparison (two sources or two methods on the same scenario and seed) takes the
    per-seed differences and gives their mean the same t interval. Pairing removes what the
    seed does to both (the drive, the start, the noise), which is most of the spread;
  - a rate (episodes with a lane departure) gets the Clopper-Pearson exact binomial interval:
    0 of 10 is [0, 0.31], not "never".

A verdict is "better" or "worse" only when the 95% interval of the difference excludes zero;
otherwise "indistinguishable" (also with fewer than two pairs, where no interval exists). With
many pairs compared at once, about one in twenty differences that are truly zero still gets a
verdict: read a count of verdicts with that in mind (docs/statistics.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

VERDICTS = ("better", "worse", "indistinguishable")
CONFIDENCE = 0.95


@dataclass(frozen=True)
class Spread:
    """A metric over seeds: mean, sample standard deviation, the mean's 95% t interval and the
    number of finite values (NaN values, e.g. a source with no estimate, are left out)."""

    mean: float
    sd: float
    ci95: tuple[float, float]
    n: int


@dataclass(frozen=True)
class Paired:
    """A paired difference (a - b per seed, averaged), its 95% interval and the verdict for a
    (lower is better unless the metric says otherwise)."""

    diff: float
    ci95: tuple[float, float]
    verdict: str
    n: int

    def as_dict(self, unit: str = "cm") -> dict:
        """The JSON form: {"diff_<unit>": x, "ci95": [lo, hi], "verdict": v, "n": n}."""
        key = f"diff_{unit}" if unit else "diff"
        return {key: self.diff, "ci95": list(self.ci95), "verdict": self.verdict, "n": self.n}


NAN_PAIR = (math.nan, math.nan)


def t_quantile(n: int) -> float:
    """t(0.975) with n - 1 degrees of freedom (NaN below two values)."""
    if n < 2:
        return math.nan
    from scipy.stats import t

    return float(t.ppf(0.5 + CONFIDENCE / 2.0, n - 1))


def spread(values: Sequence[float]) -> Spread:
    """Mean, sd and the t interval of the finite `values` (NaNs where fewer than two)."""
    x = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    n = len(x)
    if n == 0:
        return Spread(math.nan, math.nan, NAN_PAIR, 0)
    mean = float(x.mean())
    if n == 1:
        return Spread(mean, math.nan, NAN_PAIR, 1)
    sd = float(x.std(ddof=1))
    half = t_quantile(n) * sd / math.sqrt(n)
    return Spread(mean, sd, (mean - half, mean + half), n)


def verdict(ci95: tuple[float, float], lower_is_better: bool = True) -> str:
    """"better" when the whole interval of (a - b) says a is better, "worse" when it says a is
    worse, else "indistinguishable" (also for an undefined interval)."""
    lo, hi = ci95
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return "indistinguishable"
    if hi < 0.0:
        return "better" if lower_is_better else "worse"
    if lo > 0.0:
        return "worse" if lower_is_better else "better"
    return "indistinguishable"


def paired(a: Sequence[float], b: Sequence[float], lower_is_better: bool = True) -> Paired:
    """a - b over the pairs where both are finite: mean, t interval, verdict for a."""
    if len(a) != len(b):
        raise ValueError(f"paired values need equal lengths, got {len(a)} and {len(b)}")
    diffs = [x - y for x, y in zip(a, b, strict=True)
             if x is not None and y is not None and math.isfinite(x) and math.isfinite(y)]
    s = spread(diffs)
    return Paired(s.mean, s.ci95, verdict(s.ci95, lower_is_better), s.n)


def rate_interval(k: int, n: int) -> tuple[float, float]:
    """Clopper-Pearson exact 95% interval of a rate k / n (NaNs for n = 0)."""
    if n == 0:
        return NAN_PAIR
    from scipy.stats import binomtest

    ci = binomtest(k, n).proportion_ci(confidence_level=CONFIDENCE, method="exact")
    return float(ci.low), float(ci.high)


def count_verdicts(verdicts: Sequence[str]) -> dict[str, int]:
    """{"better": b, "worse": w, "indistinguishable": i} of `verdicts`."""
    return {v: sum(1 for x in verdicts if x == v) for v in VERDICTS}
