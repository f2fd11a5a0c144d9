"""The intervals and verdicts behind every "better" (lanekeep/scoring/statistics.py), checked
against their textbook definitions and SciPy's own routines: t intervals (on the log scale for
errors), margins of practical relevance, McNemar's exact test, Holm's adjustment and the
stratified pool with Welch-Satterthwaite degrees of freedom."""

import math

import numpy as np
import pytest
from scipy import stats as sps

from lanekeep.scoring import statistics as stats

RMSE = stats.MARGINS["rmse_cm"]  # max(0.1 cm, 5%)


def _t_interval(x) -> tuple[float, float]:
    x = np.asarray(x, dtype=float)
    return sps.t.interval(0.95, len(x) - 1, loc=x.mean(), scale=sps.sem(x))


# --- a metric over seeds ---------------------------------------------------------------------

def test_spread_is_the_t_interval_of_the_mean():
    values = [1.2, 0.9, 1.4, 1.1, 1.0]
    s = stats.spread(values)
    assert s.n == 5 and s.mean == pytest.approx(np.mean(values)) and not s.log_scale
    assert s.sd == pytest.approx(np.std(values, ddof=1))
    assert s.ci95 == pytest.approx(_t_interval(values))
    assert s.center == s.mean


def test_spread_on_the_log_scale_is_exp_of_the_t_interval_of_the_logs():
    values = [1.2, 0.9, 1.4, 1.1, 1.0]
    s = stats.spread(values, log_scale=True)
    lo, hi = _t_interval(np.log(values))
    assert s.log_scale and s.ci95 == pytest.approx((math.exp(lo), math.exp(hi)))
    assert s.center == pytest.approx(sps.gmean(values))
    # mean and sd stay those of the values themselves (the documents' KEY and KEY_sd)
    assert s.mean == pytest.approx(np.mean(values))
    assert s.sd == pytest.approx(np.std(values, ddof=1))


def test_a_per_seed_rmse_interval_never_goes_below_zero():
    """Issue case 3: occlusion's RMSEs over five seeds, two of them bad. The t interval of the
    mean reaches below 0 cm; the log-scale interval stays positive and holds the geometric
    mean."""
    occlusion = [1.6, 1.7, 1.9, 6.7, 11.8]
    assert stats.spread(occlusion).ci95[0] < 0.0  # the old interval: a negative RMSE
    s = stats.spread(occlusion, log_scale=True)
    assert 0.0 < s.ci95[0] < s.center < s.ci95[1]
    assert s.ci95[0] <= min(occlusion) and s.center == pytest.approx(sps.gmean(occlusion))
    for values in ([0.01, 50.0, 0.02], [1e-6, 1e-6, 100.0, 3.0]):
        assert stats.spread(values, log_scale=True).ci95[0] > 0.0


def test_a_zero_error_falls_back_to_the_plain_interval():
    s = stats.spread([0.0, 1.0, 2.0], log_scale=True)
    assert not s.log_scale and s.ci95 == pytest.approx(_t_interval([0.0, 1.0, 2.0]))


def test_spread_leaves_nan_out_and_has_no_interval_below_two_values():
    assert stats.spread([1.0, math.nan, 3.0]).n == 2
    one = stats.spread([2.0, math.nan])
    assert one.mean == 2.0 and one.n == 1 and all(math.isnan(c) for c in one.ci95)
    assert stats.spread([]).n == 0 and math.isnan(stats.spread([]).mean)
    log_one = stats.spread([2.0], log_scale=True)
    assert log_one.center == pytest.approx(2.0) and all(math.isnan(c) for c in log_one.ci95)


# --- margins and the verdict rule ------------------------------------------------------------

def test_margins_are_the_larger_of_a_floor_and_a_share():
    assert RMSE.of(1.0) == 0.1 and RMSE.of(4.0) == pytest.approx(0.2)
    assert RMSE.of(math.nan) == 0.1 and RMSE.text() == "max(0.1, 5%)"
    assert stats.Margin(0.02).text() == "0.02"
    assert stats.margin_for("fused.rmse_cm") == RMSE == stats.margin_for("rmse_cm")
    assert stats.margin_for("hough:track.valid_share") == stats.Margin(0.02)
    assert stats.margin_for("no_such_metric") == stats.margin_for(None) == stats.Margin(0.0)
    assert stats.is_log_scale("hough:track.max_cm") and stats.is_log_scale("car_rms_cm")
    assert not stats.is_log_scale("fused.valid_share") and not stats.is_log_scale("drift_cm")
    assert stats.is_exact("lane_departures") and not stats.is_exact("car_max_cm")


@pytest.mark.parametrize(("lo", "hi", "lower", "higher"), [
    (-0.5, -0.2, "better", "worse"),
    (0.2, 0.5, "worse", "better"),
    (-0.05, 0.05, "equivalent", "equivalent"),
    (-0.5, 0.05, "non-inferior", "non-superior"),
    (-0.05, 0.5, "non-superior", "non-inferior"),
    (-0.5, 0.5, "inconclusive", "inconclusive"),
    (math.nan, math.nan, "inconclusive", "inconclusive"),
])
def test_classify_reads_the_interval_against_the_margin(lo, hi, lower, higher):
    assert stats.classify(lo, hi, 0.1) == lower
    assert stats.classify(lo, hi, 0.1, lower_is_better=False) == higher


# --- paired differences ----------------------------------------------------------------------

def test_paired_difference_uses_the_per_seed_differences():
    a = [1.00, 1.50, 0.80, 1.20]
    b = [1.10, 1.62, 0.85, 1.33]  # a is lower on every seed, by 0.05-0.13
    p = stats.paired(a, b)  # no metric: margin 0, plain differences
    d = np.subtract(a, b)
    assert p.diff == pytest.approx(d.mean()) and p.margin == 0.0
    assert p.ci95 == pytest.approx(_t_interval(d))
    assert p.verdict == "better" and p.n == 4
    # the one-sided tests behind it: Student t on the differences against -+margin
    assert p.p_better == pytest.approx(sps.ttest_1samp(d, 0.0, alternative="less").pvalue)
    assert p.p_worse == pytest.approx(sps.ttest_1samp(d, 0.0, alternative="greater").pvalue)
    # the smallest difference this n detects with 80% power: (t_.975 + t_.8) * se
    assert p.detectable == pytest.approx((sps.t.ppf(0.975, 3) + sps.t.ppf(0.8, 3)) * sps.sem(d))
    # the same values unpaired would overlap: pairing is what makes the verdict
    assert stats.spread(a).ci95[1] > stats.spread(b).ci95[0]
    assert stats.paired(b, a).verdict == "worse"


def test_paired_with_a_margin_tests_against_the_margin():
    a = [1.00, 1.50, 0.80, 1.20]
    b = [1.10, 1.62, 0.85, 1.33]
    d = np.subtract(a, b)
    p = stats.paired(a, b, margin=0.05)  # 0.05-0.13 lower: not all beyond 0.05
    assert p.margin == 0.05 and p.verdict == "non-inferior"
    assert p.p_better == pytest.approx(sps.ttest_1samp(d, -0.05, alternative="less").pvalue)
    assert p.p_worse == pytest.approx(sps.ttest_1samp(d, 0.05, alternative="greater").pvalue)
    # non-inferior: "a - b >= +margin" rejected at 2.5%, the complement of p_worse
    assert p.p_better > stats.ALPHA_ONE_SIDED and p.p_worse > 1 - stats.ALPHA_ONE_SIDED
    assert stats.paired(a, b, margin=0.5).verdict == "equivalent"
    # the verdict agrees with its one-sided tests: better <=> p_better < 2.5%
    assert stats.paired(a, b, margin=0.01).verdict == "better"
    assert stats.paired(a, b, margin=0.01).p_better < stats.ALPHA_ONE_SIDED


def test_paired_on_the_log_scale_is_the_t_interval_of_the_log_ratios():
    a = [1.00, 2.70, 4.60, 1.85, 3.55]
    b = [1.10, 3.00, 5.00, 2.10, 3.90]  # a about 9% lower on every seed
    p = stats.paired(a, b, metric="fused.rmse_cm")
    d = np.log(a) - np.log(b)
    gb = sps.gmean(b)
    lo, hi = _t_interval(d)
    assert p.ratio == pytest.approx(math.exp(d.mean()))
    assert p.ratio_ci95 == pytest.approx((math.exp(lo), math.exp(hi)))
    # given back in cm: b's geometric mean x (ratio - 1), i.e. gmean(a) - gmean(b)
    assert p.diff == pytest.approx(sps.gmean(a) - gb)
    assert p.ci95 == pytest.approx((gb * math.expm1(lo), gb * math.expm1(hi)))
    assert p.margin == pytest.approx(max(0.1, 0.05 * gb))
    m_log = math.log1p(p.margin / gb)  # the margin as a log ratio
    assert p.p_better == pytest.approx(sps.ttest_1samp(d, -m_log, alternative="less").pvalue)
    assert p.p_worse == pytest.approx(sps.ttest_1samp(d, m_log, alternative="greater").pvalue)
    assert hi < -m_log and p.verdict == "better"
    assert stats.paired(b, a, metric="rmse_cm").verdict == "worse"
    # log_scale=True without a metric: the same ratios, against the margin given
    q = stats.paired(a, b, margin=RMSE, log_scale=True)
    assert q.ratio == pytest.approx(p.ratio) and q.verdict == "better"
    d_json = p.as_dict("cm")
    assert d_json["ratio"] == p.ratio and d_json["diff_cm"] == p.diff


def test_a_10cm_regression_in_one_case_is_not_non_inferior():
    """Issue case 1: one seed 10 cm worse, four equal. No claim of non-inferiority or
    equivalence: inconclusive, with the difference this n could detect."""
    for kw in ({}, {"metric": "rmse_cm"}):
        p = stats.paired([10.5, 1, 1, 1, 1], [0.5, 1, 1, 1, 1], **kw)
        assert p.verdict == "inconclusive", kw
        assert p.ci95[1] > 2.0  # the interval holds the mean regression (10 cm / 5 seeds)
        assert math.isfinite(p.detectable) and p.detectable > 2.0


def test_a_uniform_shift_inside_the_margin_is_equivalent():
    """Issue case 1, the other half: +0.006 cm on every seed is equivalent (margin 0.1 cm)."""
    b = [1.0, 3.0, 5.0, 2.0, 4.0]
    p = stats.paired([x + 0.006 for x in b], b, metric="rmse_cm")
    assert p.verdict == "equivalent" and p.margin >= 0.1
    assert -p.margin < p.ci95[0] <= p.ci95[1] < p.margin
    flat = stats.paired([1.006] * 5, [1.0] * 5, metric="rmse_cm")
    assert flat.verdict == "equivalent" and flat.diff == pytest.approx(0.006)


def test_fewer_than_three_pairs_give_no_verdict():
    """Issue case 2: two pairs, however one-sided, are "too few"."""
    p = stats.paired([1, 1], [0, 0])
    assert p.verdict == "too few" and p.n == 2 and p.diff == 1.0
    assert stats.paired([1.0], [2.0]).verdict == "too few"  # one pair: no interval
    assert all(math.isnan(c) for c in stats.paired([1.0], [2.0]).ci95)
    assert stats.paired([], []).verdict == "too few"
    assert stats.paired([2.0, 2.1, 2.2], [1.0, 1.1, 1.2]).verdict == "worse"  # three: a verdict


def test_a_rounding_difference_is_equivalent_not_worse():
    """Issue case 2: a constant 1e-15 cm on five seeds (another kernel, say) has a zero-width
    interval; against the metric's margin it is equivalent, never a claim."""
    b = [1.0, 3.0, 5.0, 2.0, 4.0]
    for a_values, b_values in (([1.0 + 1e-15] * 5, [1.0] * 5), ([x + 1e-15 for x in b], b)):
        p = stats.paired(a_values, b_values, metric="rmse_cm")
        assert p.verdict == "equivalent" and p.p_worse == 1.0 and p.p_better == 1.0
        assert stats.paired(a_values, b_values, metric="drift_cm").verdict == "equivalent"


def test_a_difference_within_the_noise_is_inconclusive():
    rng = np.random.default_rng(3)
    a = rng.normal(1.0, 0.3, 10)
    b = a + rng.normal(0.0, 0.3, 10)  # no true difference
    p = stats.paired(a, b)  # margin 0: the interval straddles 0 (the old "indistinguishable")
    assert p.verdict == "inconclusive" and p.ci95[0] < 0.0 < p.ci95[1]
    assert p.detectable > abs(p.diff)
    # against a 0.1 margin the interval reaches past +0.1 only: no claim either way
    q = stats.paired(a, b, margin=0.1)
    assert -0.1 < q.ci95[0] < 0.0 < 0.1 < q.ci95[1] and q.verdict == "non-superior"


def test_higher_is_better_flips_the_verdict():
    assert stats.paired([0.99, 0.98, 0.99], [0.5, 0.6, 0.55], lower_is_better=False
                        ).verdict == "better"
    assert stats.paired([0.99, 0.98, 0.99], [0.5, 0.6, 0.55], lower_is_better=False,
                        metric="valid_share").verdict == "better"
    assert stats.paired([0.5, 0.6, 0.55], [0.99, 0.98, 0.99], lower_is_better=False
                        ).verdict == "worse"


def test_paired_skips_pairs_with_a_missing_value_and_needs_equal_lengths():
    p = stats.paired([1.0, math.nan, 2.0, 3.0], [1.5, 1.0, 2.4, 3.6])
    assert p.n == 3 and p.dropped == 1
    with pytest.raises(ValueError, match="equal lengths"):
        stats.paired([1.0], [1.0, 2.0])
    # a zero error has no ratio: the plain difference instead
    z = stats.paired([0.0, 1.0, 2.0], [0.5, 1.5, 2.5], metric="rmse_cm")
    assert math.isnan(z.ratio) and z.diff == pytest.approx(-0.5)


# --- departures: McNemar's exact test --------------------------------------------------------

def test_paired_events_is_mcnemars_exact_test_on_the_discordant_seeds():
    a = [True, True, True, False, True, False, True, False]
    b = [False, False, True, False, False, False, True, True]  # a alone: 3, b alone: 1
    p = stats.paired_events(a, b)
    assert p.n == 8 and p.diff == pytest.approx((sum(a) - sum(b)) / 8)
    assert p.p_worse == pytest.approx(sps.binomtest(3, 4, 0.5, alternative="greater").pvalue)
    assert p.p_better == pytest.approx(sps.binomtest(1, 4, 0.5, alternative="greater").pvalue)
    assert p.verdict == "inconclusive" and p.detectable == pytest.approx(6 / 8)
    # six discordant seeds all one way: 2^-6 < 2.5%; five are not enough (2^-5 = 3.1%)
    six = stats.paired_events([True] * 6 + [False] * 2, [False] * 8)
    assert six.verdict == "worse" and six.p_worse == pytest.approx(0.5 ** 6)
    five = stats.paired_events([True] * 5 + [False] * 3, [False] * 8)
    assert five.verdict == "inconclusive" and five.p_worse == pytest.approx(0.5 ** 5)
    assert stats.paired_events([False] * 8, [True] * 6 + [False] * 2).verdict == "better"
    # concordant seeds say nothing: no discordant seed, p = 1 each way
    same = stats.paired_events([True, False, True], [True, False, True])
    assert same.verdict == "inconclusive" and same.p_worse == same.p_better == 1.0
    assert stats.paired_events([True, True], [False, False]).verdict == "too few"
    with pytest.raises(ValueError, match="equal lengths"):
        stats.paired_events([True], [True, False])


def test_rate_interval_is_clopper_pearson_and_zero_is_not_never():
    lo, hi = stats.rate_interval(0, 10)
    assert lo == 0.0 and hi == pytest.approx(1 - 0.025 ** (1 / 10))  # 0.308
    lo, hi = stats.rate_interval(3, 10)
    assert lo == pytest.approx(sps.beta.ppf(0.025, 3, 8))
    assert hi == pytest.approx(sps.beta.ppf(0.975, 4, 7))
    assert all(math.isnan(v) for v in stats.rate_interval(0, 0))


# --- many verdicts: Holm, chance, the stratified pool ----------------------------------------

def test_holm_is_the_step_down_adjustment():
    p = [0.01, 0.04, 0.03, 0.005, math.nan]
    # by hand, m = 4 finite: sorted 0.005*4 = 0.02, 0.01*3 = 0.03, 0.03*2 = 0.06,
    # 0.04*1 = 0.04 -> running maximum 0.06
    assert stats.holm(p)[:4] == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert math.isnan(stats.holm(p)[4])
    assert stats.holm([0.6, 0.5]) == pytest.approx([1.0, 1.0])  # capped at 1
    assert stats.holm([0.01]) == pytest.approx([0.01]) and stats.holm([]) == []
    adjusted = stats.holm([0.001, 0.2, 0.02, 0.5, 0.004])
    assert all(q >= p for q, p in zip(adjusted, [0.001, 0.2, 0.02, 0.5, 0.004], strict=True))


def test_expected_by_chance_is_a_one_sided_level_per_label():
    assert stats.expected_by_chance(40) == pytest.approx(1.0)
    assert stats.expected_by_chance(10) == pytest.approx(0.025 * 10)


def test_pooled_weights_each_label_once_with_welch_satterthwaite_df():
    rng = np.random.default_rng(7)
    items, means, variances, dfs = [], [], [], []
    for n, shift, noise in ((5, 0.3, 0.05), (3, 0.2, 0.2), (8, 0.25, 0.1), (4, 0.35, 0.02)):
        b = rng.uniform(1.0, 3.0, n)
        a = b + shift + rng.normal(0.0, noise, n)
        items.append((list(a), list(b)))
        d = a - b
        means.append(d.mean())
        variances.append(d.var(ddof=1) / n)
        dfs.append(n - 1)
    k = len(items)
    var = sum(variances) / k**2
    df = var**2 / sum((v / k**2) ** 2 / f for v, f in zip(variances, dfs, strict=True))
    half = sps.t.ppf(0.975, df) * math.sqrt(var)
    pool = stats.pooled(items, margin=0.1)
    assert pool.labels == 4 and not pool.log_scale
    assert pool.diff == pytest.approx(np.mean(means))  # each label once, not each pair
    assert pool.df == pytest.approx(df) and min(dfs) <= pool.df <= sum(dfs)
    assert pool.ci95 == pytest.approx((np.mean(means) - half, np.mean(means) + half))
    assert pool.verdict == "worse" and pool.margin == pytest.approx(0.1)
    assert pool.up == 4 and pool.down == 0
    assert pool.sign_p == pytest.approx(sps.binomtest(4, 4, 0.5).pvalue)
    # on the log scale: the geometric mean of the labels' ratios
    logs = stats.pooled(items, metric="rmse_cm")
    ratio = math.exp(np.mean([np.mean(np.log(a) - np.log(b)) for a, b in items]))
    assert logs.log_scale and logs.diff == pytest.approx(ratio)
    assert logs.ci95[0] < logs.diff < logs.ci95[1]
    # fewer than three labels: no verdict; a label with fewer than two pairs is left out
    assert stats.pooled(items[:2], margin=0.1).verdict == "too few"
    assert stats.pooled([*items, ([1.0], [2.0])], margin=0.1).labels == 4
    assert stats.pooled([], margin=0.1).verdict == "too few"


def test_one_noisy_label_does_not_swamp_nine_that_are_each_20_percent_worse():
    """Issue case 4: the stratified pool (ratios, each label once) finds "worse"; the old
    "all" row, every raw pair concatenated, drowned in the noisy label's spread."""
    noisy_a = [150.0, 200.0, 100.0, 250.0, 180.0]
    swings = [60.0, -50.0, 40.0, -30.0, -20.0]  # sd 47 cm
    assert np.std(swings, ddof=1) == pytest.approx(47.4, abs=0.1)
    items = [([a + s for a, s in zip(noisy_a, swings, strict=True)], noisy_a)]
    jitter = [0.01, -0.02, 0.0, 0.015, -0.005]
    for i in range(9):
        b = [(2.0 + 0.3 * i) * f for f in (1.0, 1.3, 0.8, 1.1, 0.9)]
        items.append(([x * 1.2 * (1 + jitter[(i + j) % 5]) for j, x in enumerate(b)], b))
    pool = stats.pooled(items, metric="rmse_cm")
    assert pool.verdict == "worse" and pool.labels == 10
    assert pool.ci95[0] > 1.1 and pool.diff == pytest.approx(1.18, abs=0.01)
    concat_a = [x for a, _ in items for x in a]
    concat_b = [x for _, b in items for x in b]
    assert stats.paired(concat_a, concat_b, margin=RMSE).verdict == "inconclusive"
    verdicts = [stats.paired(a, b, metric="rmse_cm").verdict for a, b in items]
    assert stats.count_verdicts(verdicts)["worse"] == 9
    assert stats.count_verdicts(verdicts)["inconclusive"] == 1


def test_verdicts_are_counted_never_as_raw_wins():
    counts = stats.count_verdicts(["better", "worse", "better", "inconclusive", "too few"])
    assert counts == {"better": 2, "worse": 1, "equivalent": 0, "non-inferior": 0,
                      "non-superior": 0, "inconclusive": 1, "too few": 1}
    assert list(counts) == list(stats.VERDICTS)
    assert stats.counts_text(counts) == "2b 1w 1i 1-"
    assert stats.counts_text(stats.count_verdicts(["equivalent"])) == "0b 0w 1e"
    assert set(stats.LETTERS) == set(stats.VERDICTS)
    assert len(set(stats.LETTERS.values())) == len(stats.VERDICTS)
