"""The reference's independence measure (lanekeep/scoring/independence.py) on synthetic errors
whose truth is known: the controls of issue #58 (independent AR(1) errors pass; a shared bias,
shared failures fail; a common curvature term is partialled out), the textbook definitions
behind each term, the edge cases, and the intervals' coverage.

    .venv/bin/python tests/scoring/test_independence.py   # prints the controls' figures
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from lanekeep.scoring import independence as ind

PHI = 0.95  # the autocorrelation of a step's error with the last one's
SD_M = 0.02  # each error's standard deviation
STEPS = 300  # one episode: 30 s at 0.1 s
SEEDS = 30  # episodes pooled: 5 are too few to show |r| < 0.2 at this PHI (see below)
CONTROLS = ("independent", "shared_bias", "shared_failures", "curvature")


def ar1(rng: np.random.Generator, n: int = STEPS, phi: float = PHI, sd_m: float = SD_M
        ) -> np.ndarray:
    """A stationary AR(1) series: e(k) = phi e(k-1) + w(k), sd `sd_m` from the first step."""
    w = rng.normal(0.0, sd_m * math.sqrt(1.0 - phi * phi), n)
    w[0] = rng.normal(0.0, sd_m)
    return lfilter([1.0], [1.0, -phi], w)


def curvature_profile(rng: np.random.Generator, n: int = STEPS) -> np.ndarray:
    """A road of left and right turns up to 1/50 m (1/m), a random phase each episode."""
    t = np.arange(n)
    return 0.02 * np.sin(2.0 * np.pi * t / 150.0 + rng.uniform(0.0, 2.0 * np.pi))


def control_episodes(kind: str, seeds: int = SEEDS, seed: int = 58) -> list[tuple]:
    """(e_src, e_ref, curvature) per episode of one synthetic control."""
    rng = np.random.default_rng(seed)
    episodes = []
    for _ in range(seeds):
        src, ref, kappa = ar1(rng), ar1(rng), curvature_profile(rng)
        if kind == "shared_bias":  # a 5 cm bias in both
            src, ref = src + 0.05, ref + 0.05
        elif kind == "shared_failures":  # the same 5% of steps: +30 cm in both
            spikes = rng.random(STEPS) < 0.05
            src, ref = src + 0.30 * spikes, ref + 0.30 * spikes
        elif kind == "curvature":  # both follow the turns (2 and 1.5 m^2 per 1/m)
            src, ref = src + 2.0 * kappa, ref + 1.5 * kappa
        elif kind != "independent":
            raise ValueError(kind)
        episodes.append((src, ref, kappa))
    return episodes


def control_verdict(kind: str, seeds: int = SEEDS) -> ind.IndependenceVerdict:
    return ind.independence_verdict(kind, control_episodes(kind, seeds), rng=1)


def verdict_line(v: ind.IndependenceVerdict) -> str:
    """r [interval] (raw r), shared bias cm [interval], lift [interval] (failures), pass."""
    ok, why = v.passes()
    lo, hi = v.corr_ci95
    blo, bhi = v.shared_bias_ci95_m
    llo, lhi = v.cofailure_lift_ci95
    return (f"{v.source:<16} r {v.corr:+.3f} [{lo:+.3f}, {hi:+.3f}] (raw {v.raw_corr:+.3f}); "
            f"bias {100 * v.shared_bias_m:+.2f} cm [{100 * blo:+.2f}, {100 * bhi:+.2f}]; "
            f"lift {v.cofailure_lift:.2f} [{llo:.2f}, {lhi:.2f}] {v.failures}; "
            f"n_eff {v.n_eff:.0f} of {v.n_steps}; {'PASS' if ok else 'FAIL: ' + '; '.join(why)}")



# --- the synthetic controls of issue #58 -----------------------------------------------------

def test_independent_errors_pass_where_a_naive_r_cries_wolf():
    episodes = control_episodes("independent")
    verdict = ind.independence_verdict("a", episodes, rng=1)
    ok, why = verdict.passes()
    assert ok, why
    lo, hi = verdict.corr_ci95
    assert -ind.CORR_BOUND < lo < 0 < hi < ind.CORR_BOUND
    assert abs(verdict.shared_bias_m) < 0.01 and verdict.n_seeds == SEEDS
    # the problem being fixed: a plain Pearson r per episode strays past 0.15 in about half
    naive = [abs(np.corrcoef(src, ref)[0, 1]) for src, ref, _ in episodes]
    assert np.mean(np.greater(naive, 0.15)) > 0.3


def test_too_few_independent_episodes_fail_as_not_shown():
    """Five episodes of 300 strongly autocorrelated steps hold ~110 effective samples: the
    interval is too wide to show |r| < 0.2, and the verdict says so instead of passing."""
    verdict = control_verdict("independent", seeds=5)
    lo, hi = verdict.corr_ci95
    assert lo < 0 < hi and hi - lo > 2 * 0.15
    ok, why = verdict.passes()
    assert not ok and any("correlation not shown" in w for w in why)


def test_a_shared_bias_fails_on_the_bias_term_alone():
    verdict = control_verdict("shared_bias")
    ok, why = verdict.passes()
    assert not ok and len(why) == 1 and why[0].startswith("shared bias")
    assert verdict.shared_bias_m == pytest.approx(0.05, abs=0.005)
    assert verdict.shared_bias_ci95_m[0] > 0.04
    assert verdict.mean_src_m == pytest.approx(0.05, abs=0.005)
    # the correlation is blind to it: the same as without the bias
    assert verdict.corr == pytest.approx(control_verdict("independent").corr)


def test_shared_failures_fail_on_the_lift_and_the_correlation():
    verdict = control_verdict("shared_failures")
    ok, why = verdict.passes()
    assert not ok
    assert any(w.startswith("co-failure lift") for w in why)
    assert any(w.startswith("correlation") and "beyond" in w for w in why)
    assert verdict.cofailure_lift > 10 and verdict.cofailure_lift_ci95[0] > ind.LIFT_BOUND


def test_a_common_curvature_term_is_partialled_out():
    episodes = control_episodes("curvature")
    verdict = ind.independence_verdict("d", episodes, rng=1)
    ok, why = verdict.passes()
    assert ok, why
    assert verdict.raw_corr > 0.5  # what the plain correlation would have said
    src, ref, kappa = (np.concatenate(s) for s in zip(*episodes, strict=True))
    assert abs(ind.partial_corr(src, ref, kappa)) < 0.1 < 0.5 < ind.pearson(src, ref)
    # the co-error too: 2 x 1.5 x mean(kappa^2) ~ (2.5 cm)^2 before, noise after
    assert ind.shared_bias_m(src, ref) > 0.02 > 0.01 > abs(ind.shared_bias_m(src, ref, kappa))


def test_independent_failures_have_a_lift_near_one():
    """At tau = 1.5 sd (13% of steps fail, each side), independence reads a lift of ~1."""
    verdict = ind.independence_verdict("a", control_episodes("independent"), tau_m=0.03,
                                       rng=1)
    both, src, ref = verdict.failures
    assert src > 500 and ref > 500
    assert 0.7 < verdict.cofailure_lift < 1.3 and verdict.passes()[0]


# --- each term against its definition --------------------------------------------------------

def test_partial_corr_is_the_textbook_partial_correlation():
    rng = np.random.default_rng(0)
    z = rng.normal(size=400)
    x, y = z + rng.normal(size=400), 0.5 * z + rng.normal(size=400)
    rxy, rxz, ryz = (np.corrcoef(a, b)[0, 1] for a, b in ((x, y), (x, z), (y, z)))
    expected = (rxy - rxz * ryz) / math.sqrt((1 - rxz**2) * (1 - ryz**2))
    assert ind.partial_corr(x, y, z) == pytest.approx(expected, abs=1e-12)
    assert ind.partial_corr(x, y) == pytest.approx(rxy, abs=1e-12)  # no curvature: Pearson


def test_steps_without_both_errors_are_left_out():
    rng = np.random.default_rng(1)
    x, y, z = rng.normal(size=(3, 200))
    x_gappy, y_gappy = x.copy(), y.copy()
    x_gappy[:20], y_gappy[50:60] = np.nan, np.nan
    keep = np.ones(200, bool)
    keep[:20] = keep[50:60] = False
    assert ind.partial_corr(x_gappy, y_gappy, z) == pytest.approx(
        ind.partial_corr(x[keep], y[keep], z[keep]))
    assert ind.failure_counts(x_gappy, y_gappy, 1.0)[3] == 170


def test_a_constant_curvature_partials_out_nothing_but_the_mean():
    rng = np.random.default_rng(2)
    x, y = rng.normal(size=(2, 100))
    arc = np.full(100, 0.02)
    assert ind.partial_corr(x, y, arc) == pytest.approx(ind.pearson(x, y), abs=1e-12)
    assert ind.shared_bias_m(x + 1.0, y + 1.0, arc) == pytest.approx(
        ind.shared_bias_m(x + 1.0, y + 1.0))


def test_shared_bias_reads_the_bias_in_metres_with_its_sign():
    ones = np.ones(50)
    assert ind.shared_bias_m(0.05 * ones, 0.05 * ones) == pytest.approx(0.05)
    assert ind.shared_bias_m(0.05 * ones, -0.05 * ones) == pytest.approx(-0.05)
    assert ind.shared_bias_m(0.04 * ones, 0.01 * ones) == pytest.approx(0.02)  # sqrt(4 cm x 1)
    assert math.isnan(ind.shared_bias_m([math.nan], [0.0]))


def test_cofailure_lift_counts():
    # 10 steps: the source fails on 0-3, the reference on 2-6
    src = np.array([0.2, 0.2, 0.2, 0.2, 0, 0, 0, 0, 0, 0])
    ref = np.array([0, 0, 0.2, 0.2, -0.2, -0.2, -0.2, 0, 0, 0])
    assert ind.failure_counts(src, ref, 0.1) == (2, 4, 5, 10)
    assert ind.cofailure_lift(src, ref, 0.1) == pytest.approx((2 / 4) / (5 / 10))
    assert math.isnan(ind.cofailure_lift(src, 0 * ref, 0.1))  # the reference never fails
    assert math.isnan(ind.cofailure_lift(0 * src, ref, 0.1))  # the source never fails


def test_bartlett_n_eff_of_white_and_ar1_series():
    rng = np.random.default_rng(3)
    n = 5000
    assert ind.bartlett_n_eff(*rng.normal(size=(2, n))) == pytest.approx(n, rel=0.1)
    x, y = ar1(rng, n, 0.5, 1.0), ar1(rng, n, 0.5, 1.0)
    # 1 + 2 sum 0.25^k = (1 + 0.25) / (1 - 0.25)
    assert ind.bartlett_n_eff(x, y) == pytest.approx(n * 0.75 / 1.25, rel=0.15)


def test_block_length_grows_with_the_memory():
    rng = np.random.default_rng(4)
    assert ind.block_length(rng.normal(size=300)) <= 3
    slow = ind.block_length(ar1(rng))
    assert 15 <= slow <= math.ceil(3 * math.sqrt(STEPS))
    idx = ind.block_indices(300, slow, 50, rng)
    assert idx.shape == (50, 300) and idx.min() >= 0 and idx.max() < 300
    assert np.all(np.diff(idx[:, :slow], axis=1) == 1)  # a block is consecutive steps


def test_fisher_pool_weighs_by_n_eff_minus_three():
    r, lo_hi = ind.fisher_pool([0.1, 0.3], [13.0, 33.0])
    z = (10 * math.atanh(0.1) + 30 * math.atanh(0.3)) / 40
    assert r == pytest.approx(math.tanh(z))
    assert lo_hi == pytest.approx((math.tanh(z - ind.Z95 / math.sqrt(40)),
                                   math.tanh(z + ind.Z95 / math.sqrt(40))))
    assert math.isnan(ind.fisher_pool([0.1], [3.0])[0])  # no information at all


# --- edge cases ------------------------------------------------------------------------------

@pytest.mark.parametrize("steps", [0, ind.MIN_STEPS - 1])
def test_too_few_common_steps_give_a_nan_verdict_that_fails(steps):
    src = np.full(100, np.nan)
    src[:steps] = 0.01
    verdict = ind.independence_verdict("a", [(src, np.zeros(100), np.zeros(100))])
    assert verdict.n_seeds == 0 and math.isnan(verdict.corr)
    assert math.isnan(verdict.shared_bias_m)
    ok, why = verdict.passes()
    assert not ok and why[0].startswith("too few common steps")


def test_a_constant_reference_fails_as_not_shown():
    rng = np.random.default_rng(5)
    verdict = ind.independence_verdict("a", [(ar1(rng), np.full(STEPS, 0.01))] * 3)
    assert math.isnan(verdict.corr) and verdict.n_seeds == 3
    ok, why = verdict.passes()
    assert not ok and "correlation not shown: no interval (nan)" in why


def test_a_single_long_episode_is_its_own_pool():
    rng = np.random.default_rng(6)
    src, ref = rng.normal(0, 0.02, size=(2, 2000))
    verdict = ind.independence_verdict("a", [(src, ref)], rng=1)
    (episode,) = verdict.episodes
    assert verdict.n_seeds == 1 and verdict.corr == pytest.approx(episode.corr)
    assert verdict.corr_bartlett_ci95 == pytest.approx(episode.corr_bartlett_ci95)
    assert verdict.passes()[0]


def test_the_same_generator_seed_gives_the_same_verdict():
    episodes = control_episodes("independent", seeds=3)
    a, b = (ind.independence_verdict("a", episodes, rng=7) for _ in range(2))
    assert a.corr_bootstrap_ci95 == b.corr_bootstrap_ci95
    assert a.to_dict()["n_steps"] == 3 * STEPS


# --- coverage of the intervals ---------------------------------------------------------------

def test_the_intervals_cover_zero_for_independent_ar1_pairs():
    """Over 100 independent AR(1) pairs (PHI = 0.95), 95% intervals: Bartlett's holds 0 in 90
    (its sample autocorrelations are biased low, so n_eff reads ~23 against 15.4), the block
    bootstrap's in 78 (~5 blocks of ~29 steps an episode): why the verdict takes their hull."""
    rng = np.random.default_rng(8)
    bartlett = bootstrap = hull = 0
    for _ in range(100):
        episode, _ = ind.episode_independence(ar1(rng), ar1(rng), boots=500, rng=rng)
        (blo, bhi), (tlo, thi) = episode.corr_bartlett_ci95, episode.corr_ci95
        bartlett += blo <= 0 <= bhi
        bootstrap += tlo <= 0 <= thi
        hull += min(blo, tlo) <= 0 <= max(bhi, thi)
    assert bartlett >= 88 and hull >= 88 and bootstrap >= 75


if __name__ == "__main__":
    for kind in CONTROLS:
        print(verdict_line(control_verdict(kind)))
    print(verdict_line(control_verdict("independent", seeds=5)))
