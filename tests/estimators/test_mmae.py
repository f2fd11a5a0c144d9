"""MMAE: equivalence with a direct computation, floor, switching, reference repair, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from lanekeep.estimators import MMAE, MMAEConfig, ReferenceRepair, apply_probability_floor

DT_S = 0.1


def _floor_direct(p: np.ndarray, floor: float) -> np.ndarray:
    """Independent floor: fix the m smallest at the floor for the first m that keeps the rest."""
    p = p / p.sum()
    order = np.argsort(p)
    for m in range(len(p) + 1):
        out = np.empty_like(p)
        low, rest = order[:m], order[m:]
        out[low] = floor
        out[rest] = p[rest] / p[rest].sum() * (1.0 - floor * m)
        if np.all(out[rest] >= floor):
            return out
    raise AssertionError("unreachable")


def _direct_step(prior, residuals, variances, cfg: MMAEConfig) -> np.ndarray:
    """Product of Gaussian densities and priors, normalised, floor applied (no logs)."""
    present = np.isfinite(residuals)
    psi = variances + cfg.reference_std_m**2
    f = np.exp(-0.5 * residuals**2 / psi) / np.sqrt(2.0 * np.pi * psi)
    f[~present] = f[present].min() * np.exp(-cfg.missing_model_log_penalty)
    posterior = f * prior
    return _floor_direct(posterior / posterior.sum(), cfg.probability_floor)


def test_log_space_probabilities_equal_direct_computation_over_200_steps() -> None:
    rng = np.random.default_rng(42)
    cfg = MMAEConfig(probability_floor=1e-3, jump_threshold_m=1e9)  # no repair: pure eq. 4
    n = 3
    mmae = MMAE(n, cfg)
    direct = np.full(n, 1.0 / n)
    previous = None
    n_updates = n_missing_model = 0
    for k in range(200):
        sigma = rng.uniform(0.01, 0.1, n)
        z = rng.normal(0.0, 0.3, n)
        variances = sigma**2
        ref = float(rng.normal(0.0, 0.3))
        offsets: list[float | None] = list(z)
        if k % 17 == 5:
            offsets[k % n] = None
        ref_in = None if k % 23 == 7 else ref
        out = mmae.step(ref_in, offsets, variances)
        if previous is not None and ref_in is not None:
            prev_z, prev_var = previous
            residuals = ref - prev_z  # eq. 2 with the previous step's offsets
            direct = _direct_step(direct, residuals, prev_var, cfg)
            np.testing.assert_allclose(out.residuals_m, residuals, rtol=0, atol=1e-15)
            n_updates += 1
            n_missing_model += int((~np.isfinite(residuals)).any())
        assert out.updated == (previous is not None and ref_in is not None)
        np.testing.assert_allclose(out.probabilities, direct, rtol=0, atol=1e-9)
        prev_z = np.array([np.nan if o is None else o for o in offsets])
        previous = (prev_z, np.where(np.isfinite(prev_z), variances, np.nan))
    assert n_updates > 180 and n_missing_model >= 10
    assert direct.max() < 0.999  # the comparison exercised unsaturated probabilities


def test_probabilities_sum_to_one_and_stay_within_floor_and_one() -> None:
    rng = np.random.default_rng(1)
    floor = 1e-3
    mmae = MMAE(4, MMAEConfig(probability_floor=floor))
    hit_floor = 0
    for _ in range(500):
        scale = 10.0 ** rng.uniform(-3, 2)  # residuals from 1 mm to 100 m
        out = mmae.step(rng.normal(0, scale), rng.normal(0, scale, 4), rng.uniform(0, 0.01, 4))
        p = out.probabilities
        assert p.sum() == pytest.approx(1.0, abs=1e-12)
        assert np.all(p >= floor - 1e-15) and np.all(p <= 1.0)
        hit_floor += int(np.isclose(p, floor).any())
    assert hit_floor > 100  # the floor was active, not just never reached


@pytest.mark.parametrize(
    ("p", "floor", "expected"),
    [
        ([1.0, 0.0, 0.0], 0.1, [0.8, 0.1, 0.1]),
        ([0.5, 0.5], 0.1, [0.5, 0.5]),
        ([0.88, 0.105, 0.015], 0.1, [0.8, 0.1, 0.1]),  # rescaling pushes 0.105 under it too
        ([0.85, 0.12, 0.03], 0.1, [0.85 * 0.9 / 0.97, 0.12 * 0.9 / 0.97, 0.1]),
        ([0.7, 0.29, 0.01], 0.05, [0.95 * 0.7 / 0.99, 0.95 * 0.29 / 0.99, 0.05]),
    ],
)
def test_floor_is_exact(p: list[float], floor: float, expected: list[float]) -> None:
    out = apply_probability_floor(np.array(p), floor)
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out, _floor_direct(np.array(p), floor), rtol=0, atol=1e-12)


def _switching_run(seed: int) -> tuple[int, int, np.ndarray]:
    """Model 1 (index 0) biased by 50 cm over steps 20..39; model 2 carries a steady 10 cm bias.

    Both models have 3 cm noise; the reference (2 cm noise) sees the road one step late (eq. 2).
    Returns the steps the selection takes to leave model 1 after step 20 and to return after 40.
    """
    rng = np.random.default_rng(seed)
    mmae = MMAE(2, MMAEConfig(reference_std_m=0.02))
    truth = 0.3 * np.sin(2.0 * np.pi * np.arange(61) * DT_S / 6.0)
    selected = []
    for k in range(1, 61):
        z1 = truth[k] + 0.03 * rng.standard_normal() + (0.5 if 20 <= k < 40 else 0.0)
        z2 = truth[k] + 0.03 * rng.standard_normal() + 0.10
        ref = truth[k - 1] + 0.02 * rng.standard_normal()
        selected.append(mmae.step(ref, [z1, z2], [0.03**2, 0.03**2]).selected)
    sel = np.array([-1, *selected])  # index = step
    leave = next(k for k in range(20, 61) if sel[k] != 0) - 20
    back = next((k for k in range(40, 61) if sel[k] == 0), 10**6) - 40
    return leave, back, sel


def test_selection_leaves_a_biased_model_within_3_steps_and_returns_within_5() -> None:
    leave, back, sel = _switching_run(seed=2024)
    assert np.all(sel[10:20] == 0)  # healthy model 1 is the choice before the bias
    assert leave <= 3, leave
    assert np.all(sel[20 + leave : 40] == 1)  # and stays away while biased
    assert back <= 5, back


def test_switching_latencies_over_seeds() -> None:
    runs = np.array([_switching_run(seed)[:2] for seed in range(100)])
    assert runs[:, 0].max() <= 3  # the one-step delay of eq. 2 is the floor of the latency
    assert np.mean(runs[:, 1] <= 5) >= 0.95, np.bincount(np.minimum(runs[:, 1], 20))


def test_reference_jumps_are_flagged_and_repaired() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(200) * DT_S
    truth = 0.4 * np.sin(2.0 * np.pi * t / 5.0)
    measured = truth + 0.02 * rng.standard_normal(len(t))
    jumps = {30: 0.3, 75: -0.6, 120: 0.4, 121: 0.45, 160: -1.5}
    for k, j in jumps.items():
        measured[k] += j
    repair = ReferenceRepair(jump_threshold_m=0.20)
    outputs, flags = [], []
    for z in measured:
        out, flagged = repair(z)
        outputs.append(out)
        flags.append(flagged)
    last_good = {k: max(j for j in range(k) if j not in jumps) for k in jumps}
    assert all(abs(measured[k] - measured[last_good[k]]) > 0.2 for k in jumps)  # real jumps
    assert sorted(np.flatnonzero(flags)) == sorted(jumps)
    for k in (30, 75, 160):  # single spikes: average of measured and extrapolated (§3)
        expected = 0.5 * (measured[k] + 2.0 * measured[k - 1] - measured[k - 2])
        assert outputs[k] == pytest.approx(expected, abs=1e-12)
    err_raw = np.abs(measured - truth)[list(jumps)]
    err_out = np.abs(np.array(outputs) - truth)[list(jumps)]
    assert np.all(err_out < 0.6 * err_raw), (err_out, err_raw)
    # the step after a spike is trusted again: a spike does not echo
    assert not flags[31] and outputs[31] == measured[31]


@pytest.mark.parametrize(
    ("amplitude_m", "period_s"),
    [(0.5, 6.0), (1.0, 8.0), (0.3, 2.5)],
    ids=["weave", "drift", "fast"],
)
def test_smooth_reference_is_never_flagged(amplitude_m: float, period_s: float) -> None:
    rng = np.random.default_rng(4)
    t = np.arange(3000) * DT_S
    z = amplitude_m * np.sin(2.0 * np.pi * t / period_s) + 0.02 * rng.standard_normal(len(t))
    assert np.max(np.abs(np.diff(z))) > 0.08  # realistic, not trivially slow
    mmae = MMAE(2)
    for zk in z:
        out = mmae.step(zk, [zk, zk], [1e-3, 1e-3])
        assert not out.reference_repaired
        assert out.reference_m == zk


def test_sustained_failure_is_repaired_and_a_standing_change_is_accepted() -> None:
    repair = ReferenceRepair(jump_threshold_m=0.20, max_repair_steps=5)
    for k in range(10):
        assert repair(0.01 * k) == (0.01 * k, False)
    flagged = [repair(0.8)[1] for _ in range(5)]  # 0.8 m for 5 steps: a failure
    assert all(flagged)
    assert repair(0.15) == (0.15, False)  # back near the road: trusted again
    outs = [repair(3.5) for _ in range(7)]  # a lane change: repaired 5 steps, then accepted
    assert [f for _, f in outs] == [True] * 5 + [False] * 2
    assert outs[-1][0] == 3.5


def test_missed_reference_leaves_probabilities_unchanged() -> None:
    mmae = MMAE(3)
    mmae.step(0.0, [0.0, 0.2, 0.5], [1e-3] * 3)
    before = mmae.step(0.0, [0.0, 0.2, 0.5], [1e-3] * 3).probabilities
    for bad in (None, np.nan, np.inf):
        out = mmae.step(bad, [0.0, 0.2, 0.5], [1e-3] * 3)
        assert not out.updated and out.reference_m is None
        assert np.array_equal(out.probabilities, before)


def test_missing_model_loses_probability_and_recovers() -> None:
    mmae = MMAE(3, MMAEConfig(reference_std_m=0.02))
    offsets = [0.0, 0.10, 0.20]
    for _ in range(5):
        out = mmae.step(0.0, offsets, [4e-4] * 3)
    assert out.selected == 0
    for _ in range(6):  # model 0 reports nothing (NaN, inf, None): never selected
        for bad in (None, np.nan, np.inf):
            out = mmae.step(0.0, [bad, 0.10, 0.20], [4e-4] * 3)
            assert out.selected != 0 and np.isfinite(out.fused_offset_m)
            assert np.all(np.isfinite(out.probabilities))
    assert out.probabilities[0] == pytest.approx(1e-3)
    back = [mmae.step(0.0, offsets, [4e-4] * 3).selected for _ in range(5)]
    assert 0 in back, back  # selected again within 5 steps of reporting
    assert back.index(0) <= 3, back


def test_no_model_offset_gives_no_output_offset() -> None:
    out = MMAE(2).step(0.1, [None, np.nan], [1e-3, 1e-3])
    assert out.selected_offset_m is None and out.fused_offset_m is None
    assert np.all(np.isnan(out.residuals_m))


def test_one_step_delay_compares_with_the_previous_offsets() -> None:
    mmae = MMAE(2)
    first = mmae.step(0.3, [0.1, 0.2], [1e-3, 1e-3])
    assert not first.updated  # nothing from k-1 yet
    out = mmae.step(0.35, [5.0, 6.0], [1e-3, 1e-3])
    np.testing.assert_allclose(out.residuals_m, [0.25, 0.15], atol=1e-15)  # eq. 2
    assert out.fused_offset_m == pytest.approx(np.dot(out.probabilities, [5.0, 6.0]))
    assert out.selected_offset_m == [5.0, 6.0][out.selected]


def test_distance_aligned_mode_compares_the_same_road_position() -> None:
    rng = np.random.default_rng(8)
    speed, lag = 15.0, 3.75  # the reference sees road 2.5 steps behind the front models
    road = lambda s: 0.4 * np.sin(2.0 * np.pi * s / 40.0)  # noqa: E731 (offset along the road)
    aligned = MMAE(2, MMAEConfig(residual_mode="distance_aligned", reference_lag_m=lag))
    delayed = MMAE(2)
    res_a, res_d = [], []
    for k in range(200):
        s = speed * DT_S * k
        z = road(s) + np.array([0.0, 0.3])  # model 2 is 30 cm off
        ref = road(s - lag) + 0.01 * rng.standard_normal()
        out_a = aligned.step(ref, list(z), [1e-4, 1e-4], s_m=s)
        out_d = delayed.step(ref, list(z), [1e-4, 1e-4])
        if k >= 3:
            res_a.append(out_a.residuals_m[0])
            res_d.append(out_d.residuals_m[0])
        else:
            assert not out_a.updated  # history does not reach s - lag yet
    rms_a, rms_d = np.sqrt(np.mean(np.square(res_a))), np.sqrt(np.mean(np.square(res_d)))
    assert rms_a < 0.02 < rms_d, (rms_a, rms_d)  # interpolation error and noise only
    assert out_a.selected == 0 and out_a.probabilities[0] > 0.99
    with pytest.raises(ValueError, match="s_m"):
        aligned.step(0.0, [0.0, 0.0], [1e-4, 1e-4])


def test_same_step_mode_compares_the_offsets_it_is_given_now() -> None:
    """The closed loop aligns the models' offsets itself (odometry); the MMAE then compares
    them with this step's reference: r_n = z_ref(k) - z_n(k)."""
    mmae = MMAE(2, MMAEConfig(residual_mode="same_step"))
    out = mmae.step(0.10, [0.12, 0.40], [1e-4, 1e-4])
    np.testing.assert_allclose(out.residuals_m, [0.10 - 0.12, 0.10 - 0.40])
    assert out.updated and out.selected == 0


def test_a_prior_sets_the_starting_probabilities_and_the_reset_returns_to_it() -> None:
    mmae = MMAE(3, MMAEConfig(residual_mode="same_step"), prior=[6.0, 3.0, 1.0])
    np.testing.assert_allclose(mmae.probabilities, [0.6, 0.3, 0.1])
    mmae.step(0.0, [0.0, 0.05, 0.1], [1e-4] * 3)  # evidence moves them ...
    assert not np.allclose(mmae.probabilities, [0.6, 0.3, 0.1])
    mmae.reset()  # ... and a reset starts again from the prior
    np.testing.assert_allclose(mmae.probabilities, [0.6, 0.3, 0.1])
    np.testing.assert_allclose(MMAE(2).probabilities, [0.5, 0.5])  # no prior: equal
    for bad in ([1.0, 1.0], [1.0, 0.0, 1.0], [1.0, np.nan, 1.0]):
        with pytest.raises(ValueError, match="prior"):
            MMAE(3, prior=bad)
