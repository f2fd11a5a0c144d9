"""Spread and verdicts over seeds: the intervals and margins behind every "better" lanekeep
prints.

Why these intervals:
  - a metric's mean over seeds gets Student's t interval (mean +- t(0.975, n-1) * sd / sqrt(n)).
    Benches run 3-10 seeds; at such n a bootstrap percentile interval is too narrow, while t is
    exact for normal errors. Errors such as an RMSE are positive and skewed (a few bad seeds),
    so for them (LOG_SCALE) the interval is taken on the log scale and given back in cm: the
    interval of the geometric mean, never below zero;
  - a paired comparison (two sources or two methods on the same scenario and seed) takes the
    per-seed differences (log ratios on the log scale) and gives their mean the same t
    interval. Pairing removes what the seed does to both, which is most of the spread;
  - a rate (episodes with a lane departure) gets the Clopper-Pearson exact interval, and two
    runs' departures per seed are compared by McNemar's exact test on the discordant seeds.

Why margins: a difference is worth a claim only when it is larger than what matters to a
user. Each metric has a declared margin of practical relevance delta (MARGINS: max of an
absolute floor and a share of the reference's size). The verdict for a (against b):
  better        the whole 95% interval of a - b lies below -delta
  worse         the whole interval lies above +delta
  equivalent    the interval lies inside (-delta, +delta)
  non-inferior  the interval lies below +delta (a is not worse by delta, maybe not better)
  non-superior  the interval lies above -delta
  inconclusive  the interval reaches past both: this n cannot tell; `detectable` says how large
                a difference it would detect (80% power)
  too few       fewer than MIN_PAIRS pairs: no verdict at all
Each verdict is a pair of one-sided tests at 2.5% (p_worse, p_better), so that a family of
them (one per scenario) can be Holm-adjusted (`holm`) and pooled (`pooled`) honestly.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

CONFIDENCE = 0.95
ALPHA_ONE_SIDED = (1.0 - CONFIDENCE) / 2.0  # each side of the 95% interval
POWER = 0.8  # for the smallest detectable difference
MIN_PAIRS = 3
VERDICTS = ("better", "worse", "equivalent", "non-inferior", "non-superior", "inconclusive",
            "too few")
CLAIMS = ("better", "worse")  # the verdicts that claim a difference


@dataclass(frozen=True)
class Margin:
    """A margin of practical relevance: max(absolute, relative * |the reference's size|), in
    the metric's unit."""

    absolute: float
    relative: float = 0.0

    def of(self, reference: float) -> float:
        size = abs(reference) if math.isfinite(reference) else 0.0
        return max(self.absolute, self.relative * size)

    def text(self) -> str:
        return (f"max({self.absolute:g}, {100 * self.relative:g}%)" if self.relative
                else f"{self.absolute:g}")


# The declared margins (docs/statistics.md#margins), by a metric's field name. Lateral errors:
# 1 mm or 5%, whichever is larger (1 mm is below what a camera at 720 rows resolves at 10 m,
# 5% is a tenth of the spread between seeds); the car: 2 mm or 5%; a maximum is noisier (one
# step): 5 mm or 5%; a valid share: 2 points; counts: one event or 10%; a correlation: 0.05.
MARGINS: dict[str, Margin] = {
    "rmse_cm": Margin(0.1, 0.05), "ade_cm": Margin(0.1, 0.05), "fde_cm": Margin(0.2, 0.05),
    "drift_cm": Margin(0.1, 0.05), "max_cm": Margin(0.5, 0.05),
    "car_rms_cm": Margin(0.2, 0.05), "car_max_cm": Margin(0.5, 0.05),
    "valid_share": Margin(0.02), "mmae_switches": Margin(1.0, 0.1),
    "reference_repairs": Margin(1.0, 0.1), "no_estimate_s": Margin(0.1, 0.05),
    "lane_departures": Margin(0.0), "failed": Margin(0.0), "reference_error_corr": Margin(0.05),
    # safety among other vehicles: a hard braking as the counts above; a collision is an
    # event (exact); the smallest TTC 0.5 s or 10% (a driver's reaction time is ~1 s); the
    # smallest gap 0.5 m or 5%
    "hard_braking_events": Margin(1.0, 0.1), "collisions": Margin(0.0),
    "min_ttc_s": Margin(0.5, 0.1), "min_gap_m": Margin(0.5, 0.05),
    # open-loop detector scores (lanekeep eval): 0.02 of AP, F1 or IoU and 2 points of the
    # valid share, a tenth of the spread between conditions; the ego offset error as the
    # lateral errors above
    "ap": Margin(0.02), "f1": Margin(0.02), "iou": Margin(0.02), "iou_ego": Margin(0.02),
    "valid": Margin(0.02), "offset_err_cm": Margin(0.1, 0.05),
}
# Positive and skewed: intervals and comparisons on the log scale (ratios).
LOG_SCALE = frozenset({"rmse_cm", "ade_cm", "fde_cm", "max_cm", "car_rms_cm", "car_max_cm"})
# Counted per episode as happened or not: exact tests (McNemar for pairs).
EXACT = frozenset({"lane_departures", "failed", "collisions"})
NAN_PAIR = (math.nan, math.nan)


def margin_for(metric: str | None) -> Margin:
    """The declared margin of a metric key ("fused.rmse_cm", "car_rms_cm"); 0 if undeclared."""
    if metric is None:
        return Margin(0.0)
    return MARGINS.get(metric.rpartition(".")[2], Margin(0.0))


def is_log_scale(metric: str | None) -> bool:
    return metric is not None and metric.rpartition(".")[2] in LOG_SCALE


def is_exact(metric: str | None) -> bool:
    return metric is not None and metric.rpartition(".")[2] in EXACT


@dataclass(frozen=True)
class Spread:
    """A metric over seeds: mean, sample sd, a 95% interval and the number of finite values.
    On the log scale `ci95` is the geometric mean's interval and `center` the geometric mean;
    otherwise `center` is the mean and `ci95` its t interval."""

    mean: float
    sd: float
    ci95: tuple[float, float]
    n: int
    center: float = math.nan
    log_scale: bool = False


def _finite(values: Sequence[float | None]) -> np.ndarray:
    return np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=float)


def t_quantile(n: int, q: float = 0.5 + CONFIDENCE / 2.0) -> float:
    """The q quantile of t with n - 1 degrees of freedom (NaN below two values)."""
    if n < 2:
        return math.nan
    from scipy.stats import t

    return float(t.ppf(q, n - 1))


def spread(values: Sequence[float | None], log_scale: bool = False) -> Spread:
    """Mean, sd and the 95% interval of the finite `values` (NaN intervals below two). With
    `log_scale` (positive values) the interval is the geometric mean's."""
    x = _finite(values)
    n = len(x)
    if n == 0:
        return Spread(math.nan, math.nan, NAN_PAIR, 0, math.nan, log_scale)
    mean = float(x.mean())
    if log_scale and np.all(x > 0):
        logs = np.log(x)
        center = float(math.exp(logs.mean()))
        if n == 1:
            return Spread(mean, math.nan, NAN_PAIR, 1, center, True)
        half = t_quantile(n) * float(logs.std(ddof=1)) / math.sqrt(n)
        ci = (math.exp(logs.mean() - half), math.exp(logs.mean() + half))
        return Spread(mean, float(x.std(ddof=1)), ci, n, center, True)
    if n == 1:
        return Spread(mean, math.nan, NAN_PAIR, 1, mean)
    sd = float(x.std(ddof=1))
    half = t_quantile(n) * sd / math.sqrt(n)
    return Spread(mean, sd, (mean - half, mean + half), n, mean)


@dataclass(frozen=True)
class Paired:
    """a - b over the seeds where both are finite: the difference in the metric's unit, its
    95% interval, the margin and the verdict for a, with the one-sided p-values behind it.

    On the log scale `ratio` (a / b, geometric mean over seeds) and `ratio_ci95` are the
    analysis; `diff` and `ci95` give them back in the unit, as b's geometric mean times
    (ratio - 1). `detectable`: the smallest |difference| this n finds with 80% power, given
    the spread seen. `dropped`: pairs left out for a missing value."""

    diff: float
    ci95: tuple[float, float]
    verdict: str
    n: int
    margin: float = 0.0
    p_worse: float = math.nan
    p_better: float = math.nan
    detectable: float = math.nan
    ratio: float = math.nan
    ratio_ci95: tuple[float, float] = NAN_PAIR
    dropped: int = 0

    def as_dict(self, unit: str = "cm") -> dict:
        """The JSON form: {"diff_<unit>", "ci95", "verdict", "n", "margin", "p_worse",
        "p_better", "detectable", "dropped"} (+ "ratio", "ratio_ci95" on the log scale)."""
        key = f"diff_{unit}" if unit else "diff"
        out = {key: self.diff, "ci95": list(self.ci95), "verdict": self.verdict, "n": self.n,
               "margin": self.margin, "p_worse": self.p_worse, "p_better": self.p_better,
               "detectable": self.detectable, "dropped": self.dropped}
        if math.isfinite(self.ratio):
            out.update(ratio=self.ratio, ratio_ci95=list(self.ratio_ci95))
        return out


def classify(lo: float, hi: float, margin: float, lower_is_better: bool = True) -> str:
    """The verdict for a from the 95% interval [lo, hi] of a - b and the margin (>= 0)."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return "inconclusive"
    up, down = ("worse", "better") if lower_is_better else ("better", "worse")
    if lo > margin:
        return up
    if hi < -margin:
        return down
    if lo > -margin and hi < margin:
        return "equivalent"
    if hi < margin:
        return "non-inferior" if lower_is_better else "non-superior"
    if lo > -margin:
        return "non-superior" if lower_is_better else "non-inferior"
    return "inconclusive"


def _one_sided(mean: float, se: float, df: float, margin: float) -> tuple[float, float]:
    """p of "a - b > +margin" being chance (H0: a - b <= margin) and of "a - b < -margin"
    (H0: a - b >= -margin), Student's t with `df`."""
    from scipy.stats import t

    if se == 0.0:  # identical differences on every seed: certain, on these seeds
        return (0.0 if mean > margin else 1.0), (0.0 if mean < -margin else 1.0)
    return (float(t.sf((mean - margin) / se, df)), float(t.cdf((mean + margin) / se, df)))


def paired(a: Sequence[float], b: Sequence[float], lower_is_better: bool = True,
           margin: Margin | float | None = None, log_scale: bool = False,
           metric: str | None = None) -> Paired:
    """a - b over the pairs where both are finite (and positive, on the log scale): the
    verdict for a against `margin` (default: the `metric`'s declared one, else 0). `metric`
    also chooses the log scale for the metrics in LOG_SCALE."""
    if len(a) != len(b):
        raise ValueError(f"paired values need equal lengths, got {len(a)} and {len(b)}")
    if margin is None:
        margin = margin_for(metric)
    if isinstance(margin, (int, float)):
        margin = Margin(float(margin))
    log_scale = log_scale or is_log_scale(metric)
    pairs = [(float(x), float(y)) for x, y in zip(a, b, strict=True)
             if x is not None and y is not None and math.isfinite(x) and math.isfinite(y)]
    dropped = len(a) - len(pairs)
    if log_scale and any(x <= 0 or y <= 0 for x, y in pairs):
        log_scale = False  # a zero error: no ratio; the plain difference instead
    n = len(pairs)
    if n == 0:
        return Paired(math.nan, NAN_PAIR, "too few", 0, math.nan, dropped=dropped)
    xs, ys = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
    if log_scale:
        base = float(np.exp(np.log(ys).mean()))  # b's geometric mean: the unit's scale
        delta = margin.of(base)
        d = np.log(xs) - np.log(ys)
        m_scale = math.log1p(delta / base) if base > 0 else 0.0
    else:
        base = float(ys.mean())
        delta = margin.of(base)
        d = xs - ys
        m_scale = delta
    mean = float(d.mean())
    if n < 2:
        back = base * math.expm1(mean) if log_scale else mean
        return Paired(back, NAN_PAIR, "too few", n, delta, dropped=dropped,
                      ratio=math.exp(mean) if log_scale else math.nan)
    sd = float(d.std(ddof=1))
    se = sd / math.sqrt(n)
    half = t_quantile(n) * se
    lo, hi = mean - half, mean + half
    p_up, p_down = _one_sided(mean, se, n - 1, m_scale)
    p_worse, p_better = (p_up, p_down) if lower_is_better else (p_down, p_up)
    detect = (t_quantile(n) + t_quantile(n, POWER)) * se
    verdict = classify(lo, hi, m_scale, lower_is_better) if n >= MIN_PAIRS else "too few"
    if log_scale:
        return Paired(base * math.expm1(mean), (base * math.expm1(lo), base * math.expm1(hi)),
                      verdict, n, delta, p_worse, p_better, base * math.expm1(detect),
                      math.exp(mean), (math.exp(lo), math.exp(hi)), dropped)
    return Paired(mean, (lo, hi), verdict, n, delta, p_worse, p_better, detect, dropped=dropped)


def paired_events(a: Sequence[bool], b: Sequence[bool]) -> Paired:
    """Whether an event (a lane departure) happened in a's episode and in b's, per seed:
    McNemar's exact test on the discordant seeds. `diff` is the difference of the rates;
    better / worse when the discordant seeds lean one way beyond chance (one-sided 2.5%),
    else inconclusive (equivalence needs a margin on a rate, which few seeds cannot meet)."""
    if len(a) != len(b):
        raise ValueError(f"paired values need equal lengths, got {len(a)} and {len(b)}")
    n = len(a)
    only_a = sum(1 for x, y in zip(a, b, strict=True) if x and not y)
    only_b = sum(1 for x, y in zip(a, b, strict=True) if y and not x)
    diff = (only_a - only_b) / n if n else math.nan
    if n < MIN_PAIRS:
        return Paired(diff, NAN_PAIR, "too few", n)
    from scipy.stats import binomtest

    k = only_a + only_b
    p_worse = float(binomtest(only_a, k, 0.5, alternative="greater").pvalue) if k else 1.0
    p_better = float(binomtest(only_b, k, 0.5, alternative="greater").pvalue) if k else 1.0
    verdict = ("worse" if p_worse < ALPHA_ONE_SIDED else
               "better" if p_better < ALPHA_ONE_SIDED else "inconclusive")
    # the smallest all-one-way discordant count that would be a verdict: 2^-k < 2.5% at k = 6
    return Paired(diff, NAN_PAIR, verdict, n, 0.0, p_worse, p_better,
                  detectable=6 / n if n >= 6 else math.nan)


def rate_interval(k: int, n: int) -> tuple[float, float]:
    """Clopper-Pearson exact 95% interval of a rate k / n (NaNs for n = 0)."""
    if n == 0:
        return NAN_PAIR
    from scipy.stats import binomtest

    ci = binomtest(k, n).proportion_ci(confidence_level=CONFIDENCE, method="exact")
    return float(ci.low), float(ci.high)


def holm(p_values: Sequence[float]) -> list[float]:
    """Holm's step-down adjusted p-values (NaN stays NaN): a family of one-sided tests, one
    per scenario, keeps its chance of any false claim at the level."""
    order = sorted((p, i) for i, p in enumerate(p_values) if math.isfinite(p))
    m, running = len(order), 0.0
    out = [math.nan] * len(p_values)
    for rank, (p, i) in enumerate(order):
        running = max(running, min(1.0, (m - rank) * p))
        out[i] = running
    return out


def expected_by_chance(labels: int) -> float:
    """How many of `labels` independent verdicts of one kind (better, or worse) chance alone
    gives where no label truly differs by its margin: at most 2.5% of them."""
    return ALPHA_ONE_SIDED * labels


@dataclass(frozen=True)
class Pooled:
    """Per-label paired differences pooled with equal weight per label (each scenario counts
    once): mean, 95% interval with Welch-Satterthwaite degrees of freedom, verdict against
    the labels' mean margin, and the sign test over the labels' own means. On the log scale
    the numbers are ratios (geometric mean of the labels' ratios)."""

    diff: float
    ci95: tuple[float, float]
    verdict: str
    labels: int
    df: float
    margin: float
    log_scale: bool
    sign_p: float
    up: int
    down: int


def pooled(items: Sequence[tuple[Sequence[float], Sequence[float]]],
           lower_is_better: bool = True, metric: str | None = None,
           margin: Margin | float | None = None) -> Pooled:
    """Stratified pooling of paired comparisons, one (a values, b values) per label: each
    label's mean difference (log ratio on the log scale) with its own standard error, averaged
    with equal weights; labels with fewer than two pairs are left out."""
    if margin is None:
        margin = margin_for(metric)
    if isinstance(margin, (int, float)):
        margin = Margin(float(margin))
    log_scale = is_log_scale(metric)
    means, variances, dfs, margins = [], [], [], []
    for a, b in items:
        pairs = [(x, y) for x, y in zip(a, b, strict=True)
                 if x is not None and y is not None and math.isfinite(x) and math.isfinite(y)]
        use_log = log_scale and all(x > 0 and y > 0 for x, y in pairs)
        if len(pairs) < 2:
            continue
        xs, ys = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
        if log_scale and not use_log:
            continue  # a label with a zero error cannot join a pool of ratios
        d = np.log(xs) - np.log(ys) if log_scale else xs - ys
        base = float(np.exp(np.log(ys).mean())) if log_scale else float(ys.mean())
        delta = margin.of(base)
        means.append(float(d.mean()))
        variances.append(float(d.var(ddof=1)) / len(d))
        dfs.append(len(d) - 1)
        margins.append(math.log1p(delta / base) if log_scale else delta)
    k = len(means)
    if k == 0:
        return Pooled(math.nan, NAN_PAIR, "too few", 0, math.nan, math.nan, log_scale,
                      math.nan, 0, 0)
    mean = sum(means) / k
    var = sum(variances) / k**2
    df = (var**2 / sum((v / k**2) ** 2 / f for v, f in zip(variances, dfs, strict=True))
          if var > 0 else float(sum(dfs)))
    from scipy.stats import binomtest, t

    half = float(t.ppf(0.5 + CONFIDENCE / 2.0, df)) * math.sqrt(var)
    m_scale = sum(margins) / k
    lo, hi = mean - half, mean + half
    verdict = classify(lo, hi, m_scale, lower_is_better) if k >= MIN_PAIRS else "too few"
    up, down = sum(1 for x in means if x > 0), sum(1 for x in means if x < 0)
    sign_p = float(binomtest(up, up + down, 0.5).pvalue) if up + down else 1.0
    if log_scale:
        return Pooled(math.exp(mean), (math.exp(lo), math.exp(hi)), verdict, k, df,
                      math.exp(m_scale), True, sign_p, up, down)
    return Pooled(mean, (lo, hi), verdict, k, df, m_scale, False, sign_p, up, down)


def count_verdicts(verdicts: Sequence[str]) -> dict[str, int]:
    """{verdict: count} over VERDICTS (every one present, zeros too)."""
    return {v: sum(1 for x in verdicts if x == v) for v in VERDICTS}


LETTERS = {"better": "b", "worse": "w", "equivalent": "e", "non-inferior": "n",
           "non-superior": "s", "inconclusive": "i", "too few": "-"}
LEGEND = ("b better, w worse (beyond the margin), e equivalent (within it), n non-inferior, "
          "s non-superior, i inconclusive, - too few seeds")


def counts_text(counts: dict[str, int]) -> str:
    """"2b 0w 1e 3i": the verdict counts that occur (better and worse always), by letter."""
    shown = [v for v in VERDICTS if v in CLAIMS or counts.get(v)]
    return " ".join(f"{counts.get(v, 0)}{LETTERS[v]}" for v in shown)
