"""Does the rear reference err independently of the front sources it judges? (paper 001, #58)

The MMAE (estimators/mmae.py) weighs each front model by its agreement with the rear camera's
reference: a reference that errs with a model cannot tell when that model is wrong. From the
per-step errors of a source and of the reference (each estimate minus the truth at its own
look-ahead, NaN where it had none; the steps where both are finite count), three terms:

  - the error correlation with the road's curvature partialled out (a turn drives both errors,
    taken at different look-aheads, without either judge or judged being at fault). Errors are
    strongly autocorrelated, so a Pearson r over one episode's 200 steps is mostly noise: per
    episode a moving-block bootstrap interval and Bartlett's effective sample size n_eff; across
    episodes (independent seeds) Fisher's z pooled with weights n_eff - 3;
  - the shared bias sign(m) sqrt(|m|), m the mean co-error mean(e_src e_ref) (curvature's part
    taken out, the means kept): a 5 cm bias in both reads 5 cm, which a correlation misses;
  - the co-failure lift P(|e_ref| > tau | |e_src| > tau) / P(|e_ref| > tau): does the judge
    fail with the judged more often than it fails anyway?

A verdict can fail honestly: each interval-judged term passes only when its whole 95% interval
lies inside the bound, so too little data fails as "not shown". docs/statistics.md says why,
and how the measure does on synthetic controls (tests/scoring/test_independence.py).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

# A gross error of one step: the shipped scenarios' limit on the fused output's RMSE
# (criteria.max_fused_rmse_m = 0.10): an error the loop may not even average.
TAU_M = 0.10
CORR_BOUND = 0.2
BIAS_BOUND_M = 0.01
LIFT_BOUND = 1.5
MIN_STEPS = 20  # common steps an episode needs to count at all
BOOTSTRAPS = 1000
Z95 = 1.959963984540054  # the normal's 97.5% quantile
SPREAD_FLOOR_M2 = 1e-12  # errors in metres: a spread under a micrometre is none (as metrics')
Interval = tuple[float, float]
NO_INTERVAL: Interval = (math.nan, math.nan)


def common_steps(e_src, e_ref, curvature=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The steps where both errors (and the curvature, if given; else 0) are finite."""
    src, ref = np.asarray(e_src, dtype=float), np.asarray(e_ref, dtype=float)
    kappa = np.zeros_like(src) if curvature is None else np.asarray(curvature, dtype=float)
    if src.ndim != 1 or src.shape != ref.shape or src.shape != kappa.shape:
        raise ValueError(f"aligned 1-D series needed, got shapes {src.shape}, {ref.shape}, "
                         f"{kappa.shape}")
    ok = np.isfinite(src) & np.isfinite(ref) & np.isfinite(kappa)
    return src[ok], ref[ok], kappa[ok]


def curvature_residuals(error: np.ndarray, curvature: np.ndarray) -> np.ndarray:
    """The error less its least-squares fit on [1, curvature]. The curvature is centred so that
    a constant one (a straight, one arc) leaves an all-zero column: the residual is then the
    error less its mean, as for a plain correlation."""
    kappa = curvature - curvature.mean()
    design = np.column_stack([np.ones_like(kappa), kappa])
    coef, *_ = np.linalg.lstsq(design, error, rcond=None)
    return error - design @ coef


def pearson(x: np.ndarray, y: np.ndarray) -> float:
    """Pearson's r; NaN under three steps or without spread."""
    if len(x) < 3:
        return math.nan
    xc, yc = x - x.mean(), y - y.mean()
    sxx, syy = float(xc @ xc), float(yc @ yc)
    if min(sxx, syy) <= len(x) * SPREAD_FLOOR_M2:
        return math.nan
    return float(xc @ yc) / math.sqrt(sxx * syy)


def partial_corr(e_src, e_ref, curvature=None) -> float:
    """r of the two errors with curvature partialled out, over their common steps."""
    src, ref, kappa = common_steps(e_src, e_ref, curvature)
    if len(src) < 3:
        return math.nan
    return pearson(curvature_residuals(src, kappa), curvature_residuals(ref, kappa))


def autocorrelation(x: np.ndarray) -> np.ndarray:
    """rho(0..n-1), the biased (divide by n, positive semi-definite) estimator, by FFT."""
    n = len(x)
    xc = x - x.mean()
    spectrum = np.fft.rfft(xc, 2 * n)
    acov = np.fft.irfft(spectrum * np.conj(spectrum), 2 * n)[:n] / n
    return acov / acov[0] if acov[0] > SPREAD_FLOOR_M2 else np.zeros(n)


def bartlett_n_eff(x: np.ndarray, y: np.ndarray, max_lag: int | None = None) -> float:
    """n / (1 + 2 sum_k rho_x(k) rho_y(k)), k = 1..max_lag (default n // 5, Pyper & Peterman
    1998): under independence var(r) ~ 1 / n_eff (Bartlett 1935). Capped at n: never more
    information than steps."""
    n = len(x)
    lags = n // 5 if max_lag is None else min(max_lag, n - 1)
    rx, ry = autocorrelation(x), autocorrelation(y)
    inflation = 1.0 + 2.0 * float(rx[1:lags + 1] @ ry[1:lags + 1])
    return n if inflation <= 1.0 else n / inflation


def block_length(*series: np.ndarray) -> int:
    """The moving-block bootstrap's block (steps): Politis & White (2004, with Patton, Politis
    & White 2009's correction), b = (2 G^2 / D)^(1/3) n^(1/3), D = 4/3 g(0)^2, from a flat-top
    lag window; the longest over `series` (a pair's dependence lasts as long as its longest
    memory), within [1, min(3 sqrt(n), n / 3)]."""
    n = len(series[0])
    cap = max(1, math.ceil(min(3.0 * math.sqrt(n), n / 3.0)))
    k_n = max(5, math.ceil(math.sqrt(math.log10(n))))
    m_max = math.ceil(math.sqrt(n)) + k_n
    bound = 2.0 * math.sqrt(math.log10(n) / n)
    best = 1
    for x in series:
        rho = autocorrelation(x)
        acov = rho * float(np.var(x))
        small = np.abs(rho[1:]) < bound  # small[j]: |rho(j + 1)| is insignificant
        m = next((m for m in range(m_max + 1) if small[m:m + k_n].all()), m_max)
        big_m = min(2 * m, m_max, n - 1)
        if big_m == 0 or acov[0] <= SPREAD_FLOOR_M2:
            continue
        k = np.arange(1, big_m + 1)
        t = k / big_m
        weight = np.where(t <= 0.5, 1.0, 2.0 * (1.0 - t))  # the flat-top window
        g = acov[0] + 2.0 * float(weight @ acov[k])
        big_g = 2.0 * float(weight @ (k * acov[k]))
        if g > 0:
            best = max(best, round((2.0 * big_g**2 / (4.0 / 3.0 * g**2)) ** (1 / 3) * n ** (1 / 3)))
    return int(min(max(best, 1), cap))


def block_indices(n: int, block: int, boots: int, rng: np.random.Generator) -> np.ndarray:
    """(boots, n) step indices: moving blocks of `block` steps, drawn with replacement."""
    blocks = math.ceil(n / block)
    starts = rng.integers(0, n - block + 1, size=(boots, blocks))
    return (starts[:, :, None] + np.arange(block)).reshape(boots, -1)[:, :n]


def rows_pearson(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Pearson's r of each row pair (NaN for a row without spread)."""
    xc = x - x.mean(axis=1, keepdims=True)
    yc = y - y.mean(axis=1, keepdims=True)
    sxx, syy = (xc * xc).sum(axis=1), (yc * yc).sum(axis=1)
    ok = np.minimum(sxx, syy) > x.shape[1] * SPREAD_FLOOR_M2
    return np.where(ok, (xc * yc).sum(axis=1) / np.sqrt(np.where(ok, sxx * syy, 1.0)), np.nan)


def signed_root(m: float) -> float:
    """sign(m) sqrt(|m|): a mean co-error (m^2) back in metres."""
    return math.copysign(math.sqrt(abs(m)), m) if math.isfinite(m) else math.nan


def shared_bias_m(e_src, e_ref, curvature=None) -> float:
    """sign(m) sqrt(|m|), m = mean(e_src e_ref) over the common steps, with curvature's part of
    each error (its slope, not its mean) taken out first when given: a shared 5 cm bias reads
    5 cm, independent zero-mean errors ~0. m = cov + mean_src mean_ref: a correlation of the
    errors reads here too, in metres."""
    src, ref, kappa = common_steps(e_src, e_ref, curvature)
    if len(src) == 0:
        return math.nan
    a = curvature_residuals(src, kappa) + src.mean()
    b = curvature_residuals(ref, kappa) + ref.mean()
    return signed_root(float(np.mean(a * b)))


def failure_counts(e_src, e_ref, tau_m: float = TAU_M) -> tuple[int, int, int, int]:
    """(both, src, ref, steps): steps with |e| > tau, over the common steps."""
    src, ref, _ = common_steps(e_src, e_ref)
    fs, fr = np.abs(src) > tau_m, np.abs(ref) > tau_m
    return int((fs & fr).sum()), int(fs.sum()), int(fr.sum()), len(src)


def lift_of(both: float, src: float, ref: float, steps: float) -> float:
    """P(ref fails | src fails) / P(ref fails); NaN without a failure of either."""
    if src <= 0 or ref <= 0:
        return math.nan
    return (both / src) / (ref / steps)


def cofailure_lift(e_src, e_ref, tau_m: float = TAU_M) -> float:
    """P(|e_ref| > tau | |e_src| > tau) / P(|e_ref| > tau) over the common steps: 1 when the
    reference fails as often with the source as without; NaN when either never fails."""
    return lift_of(*failure_counts(e_src, e_ref, tau_m))


def fisher_pool(corrs: Sequence[float], n_effs: Sequence[float]) -> tuple[float, Interval]:
    """Fisher's z pooled over independent episodes, weights n_eff - 3 (var z ~ 1 / (n_eff -
    3)): the seeds are independent, and within one the autocorrelation shrinks the information
    to n_eff. The pooled r and its 95% interval; NaN without an episode of n_eff > 3."""
    r, n = np.asarray(corrs, dtype=float), np.asarray(n_effs, dtype=float)
    keep = np.isfinite(r) & (n > 3)
    if not keep.any():
        return math.nan, NO_INTERVAL
    w = n[keep] - 3.0
    z = float(w @ np.arctanh(np.clip(r[keep], -0.999999, 0.999999))) / float(w.sum())
    half = Z95 / math.sqrt(float(w.sum()))
    return math.tanh(z), (math.tanh(z - half), math.tanh(z + half))


def percentile_interval(replicates: np.ndarray) -> Interval:
    """The bootstrap's 95% percentile interval; none when over half the replicates have no
    value (no spread, no failure in the resample)."""
    finite = replicates[np.isfinite(replicates)]
    if len(finite) == 0 or len(finite) < len(replicates) / 2:
        return NO_INTERVAL
    lo, hi = np.percentile(finite, [2.5, 97.5])
    return float(lo), float(hi)


@dataclass(frozen=True)
class EpisodeIndependence:
    """One episode (seed) of one source against the reference."""

    steps: int  # common steps
    corr: float  # partial r (curvature out)
    corr_ci95: Interval  # moving-block bootstrap, percentile
    corr_bartlett_ci95: Interval  # Fisher z with Bartlett's n_eff
    raw_corr: float  # plain Pearson r, curvature kept: what `reference_error_corr` reports
    n_eff: float
    block_steps: int
    co_error_m2: float  # m = mean(e_src e_ref), curvature's slope out
    mean_src_m: float
    mean_ref_m: float
    failures: tuple[int, int, int]  # steps over tau: (both, src, ref)


@dataclass(frozen=True)
class Replicates:
    """One episode's bootstrap replicates, kept for the pool: r, sum of co-errors, failure
    counts (both, src, ref) per resample."""

    corr: np.ndarray  # (boots,)
    co_error_sum_m2: np.ndarray  # (boots,)
    failures: np.ndarray  # (boots, 3)


def episode_independence(e_src, e_ref, curvature=None, tau_m: float = TAU_M,
                         boots: int = BOOTSTRAPS, rng: np.random.Generator | int = 0
                         ) -> tuple[EpisodeIndependence, Replicates] | None:
    """One episode's figures and its bootstrap replicates; None under MIN_STEPS common steps.
    The blocks resample the pairs of curvature residuals (and, with the same indices, the
    co-errors and failures): what is dependent within a block stays together."""
    src, ref, kappa = common_steps(e_src, e_ref, curvature)
    n = len(src)
    if n < MIN_STEPS:
        return None
    rng = np.random.default_rng(rng)
    x, y = curvature_residuals(src, kappa), curvature_residuals(ref, kappa)
    a, b = x + src.mean(), y + ref.mean()
    r, n_eff, block = pearson(x, y), bartlett_n_eff(x, y), block_length(x, y)
    idx = block_indices(n, block, boots, rng)
    fail_src, fail_ref = np.abs(src) > tau_m, np.abs(ref) > tau_m
    replicates = Replicates(
        corr=rows_pearson(x[idx], y[idx]),
        co_error_sum_m2=(a * b)[idx].sum(axis=1),
        failures=np.stack([(fail_src & fail_ref)[idx].sum(axis=1), fail_src[idx].sum(axis=1),
                           fail_ref[idx].sum(axis=1)], axis=1))
    episode = EpisodeIndependence(
        steps=n, corr=r, corr_ci95=percentile_interval(replicates.corr),
        corr_bartlett_ci95=fisher_pool([r], [n_eff])[1], raw_corr=pearson(src, ref),
        n_eff=n_eff, block_steps=block, co_error_m2=float(np.mean(a * b)),
        mean_src_m=float(src.mean()), mean_ref_m=float(ref.mean()),
        failures=(int((fail_src & fail_ref).sum()), int(fail_src.sum()), int(fail_ref.sum())))
    return episode, replicates


@dataclass(frozen=True)
class IndependenceVerdict:
    """One source against the reference, pooled over episodes (seeds). The judged correlation
    interval `corr_ci95` is the hull of Bartlett's and the block bootstrap's: both are too
    narrow in their own way at a few blocks per episode (a biased sample autocorrelation, too
    few blocks), so the verdict takes the wider end of each side."""

    source: str
    corr: float  # pooled partial r: Fisher z, weights n_eff - 3
    corr_ci95: Interval  # judged: the hull of the two below
    corr_bartlett_ci95: Interval
    corr_bootstrap_ci95: Interval
    raw_corr: float  # pooled the same way, curvature kept
    shared_bias_m: float  # sign(m) sqrt(|m|), m the mean co-error over all common steps
    shared_bias_ci95_m: Interval
    mean_src_m: float
    mean_ref_m: float
    cofailure_lift: float  # NaN when either never failed
    cofailure_lift_ci95: Interval
    failures: tuple[int, int, int]  # steps over tau: (both, src, ref)
    tau_m: float
    n_eff: float  # sum over the episodes
    n_steps: int
    n_seeds: int  # episodes with MIN_STEPS common steps
    episodes: tuple[EpisodeIndependence, ...] = ()

    def passes(self, corr_bound: float = CORR_BOUND, bias_bound_m: float = BIAS_BOUND_M,
               lift_bound: float = LIFT_BOUND) -> tuple[bool, tuple[str, ...]]:
        """(passed, why not). Correlation and shared bias pass only when their whole 95%
        interval lies inside +-bound; the lift when it is under its bound, or undefined
        because the source or the reference never failed (then nothing failed together).
        The lift is judged on its value: its interval, from a handful of failures, would fail
        the rarely failing pairs, the better ones."""
        if self.n_seeds == 0:
            return False, (f"too few common steps: no episode with {MIN_STEPS}",)
        reasons = []
        reasons += _interval_reason("correlation", self.corr, self.corr_ci95, corr_bound, "")
        reasons += _interval_reason("shared bias", 100 * self.shared_bias_m,
                                    _scaled(self.shared_bias_ci95_m, 100), 100 * bias_bound_m,
                                    " cm")
        both, src, ref = self.failures
        if self.cofailure_lift >= lift_bound:
            reasons.append(f"co-failure lift {self.cofailure_lift:.2f} >= {lift_bound:g} "
                           f"({both} of {src} source failures met a reference failure; the "
                           f"reference failed {ref} times in {self.n_steps} steps)")
        return not reasons, tuple(reasons)

    def to_dict(self) -> dict:
        return asdict(self)


def _scaled(interval: Interval, factor: float) -> Interval:
    return interval[0] * factor, interval[1] * factor


def _interval_reason(name: str, value: float, interval: Interval, bound: float, unit: str
                     ) -> list[str]:
    lo, hi = interval
    shown = f"{value:.2f}{unit} [{lo:.2f}, {hi:.2f}]"
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return [f"{name} not shown: no interval ({value:.2f}{unit})"]
    if lo > bound or hi < -bound:
        return [f"{name} {shown} beyond +-{bound:g}{unit}"]
    if lo < -bound or hi > bound:
        return [f"{name} not shown inside +-{bound:g}{unit}: {shown} reaches past it"]
    return []


def independence_verdict(source: str, episodes: Sequence[tuple], tau_m: float = TAU_M,
                         boots: int = BOOTSTRAPS, rng: np.random.Generator | int = 0
                         ) -> IndependenceVerdict:
    """The verdict over `episodes`, each (e_src, e_ref) or (e_src, e_ref, curvature), aligned
    per step (m, 1/m; NaN where a series has none). The bootstrap pools episode by episode
    (stratified: each resample draws blocks within every episode), with the pool's own
    weights."""
    rng = np.random.default_rng(rng)
    done = [d for d in (episode_independence(*e, tau_m=tau_m, boots=boots, rng=rng)
                        for e in episodes) if d is not None]
    if not done:
        return IndependenceVerdict(
            source, math.nan, NO_INTERVAL, NO_INTERVAL, NO_INTERVAL, math.nan, math.nan,
            NO_INTERVAL, math.nan, math.nan, math.nan, NO_INTERVAL, (0, 0, 0), tau_m, 0.0, 0, 0)
    eps = tuple(e for e, _ in done)
    reps = [r for _, r in done]
    corrs, n_effs = [e.corr for e in eps], [e.n_eff for e in eps]
    corr, bartlett = fisher_pool(corrs, n_effs)
    steps = np.array([e.steps for e in eps], dtype=float)
    weight = np.array([n - 3.0 if math.isfinite(r) and n > 3 else 0.0
                       for r, n in zip(corrs, n_effs, strict=True)])
    if weight.sum() > 0:
        z = np.stack([np.arctanh(np.clip(r.corr, -0.999999, 0.999999)) for r in reps])
        z = np.where(weight[:, None] > 0, z, 0.0)
        bootstrap = _tanh(percentile_interval(weight @ z / weight.sum()))
    else:
        bootstrap = NO_INTERVAL
    judged = ((min(bartlett[0], bootstrap[0]), max(bartlett[1], bootstrap[1]))
              if all(map(math.isfinite, bartlett + bootstrap)) else NO_INTERVAL)
    m_boot = sum(r.co_error_sum_m2 for r in reps) / steps.sum()
    m_lo, m_hi = percentile_interval(m_boot)
    both, src, ref = (int(v) for v in np.sum([e.failures for e in eps], axis=0))
    fails = sum(r.failures for r in reps).astype(float)
    with np.errstate(divide="ignore", invalid="ignore"):
        lift_boot = np.where((fails[:, 1] > 0) & (fails[:, 2] > 0),
                             fails[:, 0] / fails[:, 1] / (fails[:, 2] / steps.sum()), np.nan)
    return IndependenceVerdict(
        source=source, corr=corr, corr_ci95=judged, corr_bartlett_ci95=bartlett,
        corr_bootstrap_ci95=bootstrap,
        raw_corr=fisher_pool([e.raw_corr for e in eps], n_effs)[0],
        shared_bias_m=signed_root(float(steps @ [e.co_error_m2 for e in eps]) / steps.sum()),
        shared_bias_ci95_m=(signed_root(m_lo), signed_root(m_hi)),
        mean_src_m=float(steps @ [e.mean_src_m for e in eps]) / steps.sum(),
        mean_ref_m=float(steps @ [e.mean_ref_m for e in eps]) / steps.sum(),
        cofailure_lift=lift_of(both, src, ref, steps.sum()),
        cofailure_lift_ci95=percentile_interval(lift_boot), failures=(both, src, ref),
        tau_m=tau_m, n_eff=float(sum(n_effs)), n_steps=int(steps.sum()), n_seeds=len(eps),
        episodes=eps)


def _tanh(interval: Interval) -> Interval:
    return math.tanh(interval[0]), math.tanh(interval[1])
