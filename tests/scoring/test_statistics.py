"""The intervals and verdicts behind every "better" (lanekeep/scoring/statistics.py), checked
against their textbook definitions and SciPy's own routines."""

import math

import numpy as np
import pytest
from scipy import stats as sps

from lanekeep.scoring import statistics as stats


def test_spread_is_the_t_interval_of_the_mean():
    values = [1.2, 0.9, 1.4, 1.1, 1.0]
    s = stats.spread(values)
    lo, hi = sps.t.interval(0.95, len(values) - 1, loc=np.mean(values), scale=sps.sem(values))
    assert s.n == 5 and s.mean == pytest.approx(np.mean(values))
    assert s.sd == pytest.approx(np.std(values, ddof=1))
    assert s.ci95 == pytest.approx((lo, hi))


def test_spread_leaves_nan_out_and_has_no_interval_below_two_values():
    assert stats.spread([1.0, math.nan, 3.0]).n == 2
    one = stats.spread([2.0, math.nan])
    assert one.mean == 2.0 and one.n == 1 and all(math.isnan(c) for c in one.ci95)
    assert stats.spread([]).n == 0 and math.isnan(stats.spread([]).mean)


def test_paired_difference_uses_the_per_seed_differences():
    a = [1.00, 1.50, 0.80, 1.20]
    b = [1.10, 1.62, 0.85, 1.33]  # a is lower on every seed, by 0.05-0.13
    p = stats.paired(a, b)
    d = np.subtract(a, b)
    assert p.diff == pytest.approx(d.mean())
    assert p.ci95 == pytest.approx(sps.t.interval(0.95, 3, loc=d.mean(), scale=sps.sem(d)))
    assert p.verdict == "better" and p.n == 4
    # the same values unpaired would overlap: pairing is what makes the verdict
    assert stats.spread(a).ci95[1] > stats.spread(b).ci95[0]
    assert stats.paired(b, a).verdict == "worse"


def test_a_difference_within_the_noise_is_indistinguishable():
    rng = np.random.default_rng(3)
    a = rng.normal(1.0, 0.3, 10)
    b = a + rng.normal(0.0, 0.3, 10)  # no true difference
    assert stats.paired(a, b).verdict == "indistinguishable"
    assert stats.paired([1.0], [2.0]).verdict == "indistinguishable"  # one pair: no interval


def test_higher_is_better_flips_the_verdict():
    assert stats.paired([0.99, 0.98, 0.99], [0.5, 0.6, 0.55], lower_is_better=False
                        ).verdict == "better"


def test_paired_skips_pairs_with_a_missing_value_and_needs_equal_lengths():
    p = stats.paired([1.0, math.nan, 2.0, 3.0], [1.5, 1.0, 2.4, 3.6])
    assert p.n == 3
    with pytest.raises(ValueError, match="equal lengths"):
        stats.paired([1.0], [1.0, 2.0])


def test_rate_interval_is_clopper_pearson_and_zero_is_not_never():
    lo, hi = stats.rate_interval(0, 10)
    assert lo == 0.0 and hi == pytest.approx(1 - 0.025 ** (1 / 10))  # 0.308
    lo, hi = stats.rate_interval(3, 10)
    assert lo == pytest.approx(sps.beta.ppf(0.025, 3, 8))
    assert hi == pytest.approx(sps.beta.ppf(0.975, 4, 7))
    assert all(math.isnan(v) for v in stats.rate_interval(0, 0))


def test_verdicts_are_counted_never_as_raw_wins():
    assert stats.count_verdicts(["better", "worse", "better", "indistinguishable"]) == {
        "better": 2, "worse": 1, "indistinguishable": 1}
