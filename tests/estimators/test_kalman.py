"""LaneTracker: consistency (NIS), noise reduction, ego-motion coasting, gate, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from lanekeep.estimators.kalman import (
    LaneTracker,
    TrackerConfig,
    UpdateStatus,
    cv_process_noise,
    cv_transition,
    ego_motion_transform,
)

DT_S = 0.1
RADIUS_M = 150.0
SPEED_MPS = 15.0


def _psd(cfg: TrackerConfig) -> tuple[float, float, float]:
    return (cfg.c0_accel_psd_m2ps3, cfg.c1_accel_psd_ps3, cfg.c2_accel_psd_pm2ps3)


def _simulate_cv(cfg: TrackerConfig, n_steps: int, seed: int, one_d: bool = False) -> dict:
    """Truth drawn from the tracker's own model (known Q and R); returns NIS and errors."""
    rng = np.random.default_rng(seed)
    f, q = cv_transition(DT_S), cv_process_noise(DT_S, _psd(cfg))
    x = np.array([-1.8, 0.01, 1e-3, 0.0, 0.0, 0.0])
    tracker = LaneTracker(cfg)
    nis, err_track, err_raw = [], [], []
    for k in range(n_steps):
        x = f @ x + rng.multivariate_normal(np.zeros(6), q)
        tracker.predict(DT_S)
        if one_d:
            z = -x[0] + cfg.offset_measurement_std_m * rng.standard_normal()
            result = tracker.update_offset(z)
            raw = -z
        else:
            z = x[:3] + rng.multivariate_normal(np.zeros(3), cfg.coefficient_r)
            result = tracker.update_coefficients(z)
            raw = z[0]
        if k >= 20:  # past the start-up transient
            nis.append(result.nis)
            err_track.append(tracker.lateral_m() - x[0])
            err_raw.append(raw - x[0])
    return {"nis": np.array(nis), "track": np.array(err_track), "raw": np.array(err_raw)}


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(e))))


@pytest.mark.parametrize(
    ("cfg", "one_d"),
    [
        (TrackerConfig(), False),
        (TrackerConfig(), True),
        (TrackerConfig.constant_velocity_only(), False),
    ],
    ids=["default-3d", "default-offset-only", "cv-only-3d"],
)
def test_mean_nis_inside_chi2_95_band(cfg: TrackerConfig, one_d: bool) -> None:
    sim = _simulate_cv(cfg, n_steps=1020, seed=7, one_d=one_d)
    n, dim_z = len(sim["nis"]), 1 if one_d else 3
    # N * mean(NIS) ~ chi2(N * dim_z) for a consistent filter; every NIS counts, gated ones too
    lo, hi = chi2.ppf([0.025, 0.975], n * dim_z) / n
    assert np.all(np.isfinite(sim["nis"]))
    assert lo < sim["nis"].mean() < hi, (lo, sim["nis"].mean(), hi)


def test_tracked_offset_rmse_at_least_30_percent_below_raw() -> None:
    sim = _simulate_cv(TrackerConfig(), n_steps=1020, seed=11)
    reduction = 1.0 - _rms(sim["track"]) / _rms(sim["raw"])
    assert reduction >= 0.30, reduction


def _lane_in_car_frame(px: float, py: float, yaw: float) -> np.ndarray:
    """Centreline of a left arc of radius 150 m, centre (0, R), seen from the car: 0..30 m fit."""
    c, s = np.cos(yaw), np.sin(yaw)
    dx, dy = 0.0 - px, RADIUS_M - py
    cx, cy = c * dx + s * dy, -s * dx + c * dy  # circle centre in the car frame
    x = np.linspace(0.0, 30.0, 61)
    y = cy - np.sqrt(RADIUS_M**2 - (x - cx) ** 2)
    return np.polyfit(x, y, 2)[::-1]


def _drive_and_coast(cfg: TrackerConfig, seed: int, n_tracked: int = 100, n_coast: int = 5):
    """Drive the 150 m curve at 15 m/s, weaving (yaw rate 0.1 +- 0.02 rad/s), then coast.

    Returns the coast errors of c0 and the tracked / raw c0 errors while measured.
    """
    rng = np.random.default_rng(seed)
    tracker = LaneTracker(cfg)
    px = py = yaw = t = 0.0
    substeps = 20
    h = DT_S / substeps
    coast_err, tracked_err, raw_err = [], [], []
    for k in range(n_tracked + n_coast):
        yaw_before = yaw
        for _ in range(substeps):
            omega = SPEED_MPS / RADIUS_M + 0.02 * np.cos(2.0 * np.pi * t / 4.0)
            px += SPEED_MPS * h * np.cos(yaw + 0.5 * omega * h)
            py += SPEED_MPS * h * np.sin(yaw + 0.5 * omega * h)
            yaw += omega * h
            t += h
        truth = _lane_in_car_frame(px, py, yaw)
        tracker.predict(DT_S, SPEED_MPS, (yaw - yaw_before) / DT_S)  # mean yaw rate, as a gyro
        if k < n_tracked:
            z = truth + rng.multivariate_normal(np.zeros(3), cfg.coefficient_r)
            tracker.update_coefficients(z)
            if k >= 20:
                tracked_err.append(tracker.lateral_m() - truth[0])
                raw_err.append(z[0] - truth[0])
        else:
            assert tracker.update_coefficients(None).status is UpdateStatus.MISSED
            assert tracker.valid
            coast_err.append(tracker.lateral_m() - truth[0])
    return np.abs(coast_err), np.array(tracked_err), np.array(raw_err)


def test_coasts_five_missed_steps_under_10_cm_on_150_m_curve_with_ego_motion() -> None:
    coast_err, tracked, raw = _drive_and_coast(TrackerConfig(), seed=3)
    assert len(coast_err) == 5
    assert coast_err.max() < 0.10, coast_err
    assert 1.0 - _rms(tracked) / _rms(raw) >= 0.30  # and it filters while driving the curve


def test_ego_motion_coasting_beats_constant_velocity_over_seeds() -> None:
    seeds = range(40)
    ego = np.array([_drive_and_coast(TrackerConfig(), s)[0].max() for s in seeds])
    cv = np.array(
        [_drive_and_coast(TrackerConfig.constant_velocity_only(), s)[0].max() for s in seeds]
    )
    assert np.mean(ego < 0.10) >= 0.85, np.sort(ego)[-8:]
    assert np.median(ego) < 0.75 * np.median(cv), (np.median(ego), np.median(cv))


def test_ego_motion_transform_keeps_the_followed_curve_still() -> None:
    c = _lane_in_car_frame(0.0, 0.0, 0.0)
    a, b = ego_motion_transform(c, SPEED_MPS, SPEED_MPS / RADIUS_M, DT_S)
    after = _lane_in_car_frame(*_arc_pose(SPEED_MPS * DT_S, SPEED_MPS / RADIUS_M * DT_S))
    assert np.allclose(a @ c + b, after, atol=[3e-3, 5e-4, 2e-5])
    a0, b0 = ego_motion_transform(c, 0.0, 0.0, DT_S)
    assert np.allclose(a0, np.eye(3), atol=1e-9) and np.allclose(b0, 0.0, atol=1e-9)


def test_ego_motion_transform_moves_the_lane_by_the_sideslip() -> None:
    """A car sliding left at 0.5 m/s over 0.1 s sees a straight lane 5 cm further right."""
    c = np.array([0.2, 0.0, 0.0])
    a, b = ego_motion_transform(c, SPEED_MPS, 0.0, DT_S, lateral_speed_mps=0.5)
    np.testing.assert_allclose(a @ c + b, [0.2 - 0.05, 0.0, 0.0], atol=1e-9)


def _arc_pose(ds: float, dyaw: float) -> tuple[float, float, float]:
    r = ds / dyaw
    return r * np.sin(dyaw), r * (1.0 - np.cos(dyaw)), dyaw


def _steady_tracker(cfg: TrackerConfig | None = None) -> tuple[LaneTracker, np.ndarray]:
    rng = np.random.default_rng(5)
    tracker = LaneTracker(cfg)
    truth = np.array([-1.75, 0.01, 2e-3])
    for _ in range(50):
        tracker.predict(DT_S)
        tracker.update_coefficients(
            truth + rng.multivariate_normal(np.zeros(3), tracker.config.coefficient_r)
        )
    return tracker, truth


def test_one_metre_outlier_is_gated() -> None:
    tracker, truth = _steady_tracker()
    tracker.predict(DT_S)
    prior = tracker.x
    result = tracker.update_coefficients(truth + np.array([1.0, 0.0, 0.0]))
    assert result.status is UpdateStatus.GATED
    assert result.nis > chi2.ppf(0.99, 3)
    # the coefficients as predicted; coasting without rates (the default), the rates back to 0
    assert np.array_equal(tracker.x[:3], prior[:3]) and not tracker.x[3:].any()
    assert tracker.missed_steps == 1
    tracker.predict(DT_S)
    assert tracker.update_offset(-truth[0] + 1.0).status is UpdateStatus.GATED  # 1-D too
    tracker.predict(DT_S)
    assert tracker.update_coefficients(truth).status is UpdateStatus.UPDATED
    assert tracker.missed_steps == 0


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_measurements_are_missed_not_propagated(bad: float) -> None:
    tracker, truth = _steady_tracker()
    tracker.predict(DT_S)
    prior = tracker.x
    assert tracker.update_coefficients([truth[0], bad, truth[2]]).status is UpdateStatus.MISSED
    assert tracker.update_offset(bad).status is UpdateStatus.MISSED
    assert np.array_equal(tracker.x[:3], prior[:3]) and not tracker.x[3:].any()
    tracker.predict(DT_S, speed_mps=bad, yaw_rate_rps=bad)  # unknown ego-motion: CV only
    assert np.all(np.isfinite(tracker.x)) and np.all(np.isfinite(tracker.P))
    assert tracker.valid and abs(tracker.lateral_m() - truth[0]) < 0.1
    assert tracker.missed_steps == 2


def test_fresh_tracker_ignores_bad_input_and_starts_on_good() -> None:
    tracker = LaneTracker()
    assert tracker.update_coefficients([np.nan, 0.0, 0.0]).status is UpdateStatus.MISSED
    assert not tracker.valid and tracker.offset_m() is None
    assert tracker.update_offset(0.3, x_m=0.0).status is UpdateStatus.INITIALIZED
    assert tracker.offset_m() == pytest.approx(0.3, abs=0.01)


def test_coasts_then_reports_invalid_then_restarts() -> None:
    cfg = TrackerConfig(max_coast_steps=4)
    tracker, truth = _steady_tracker(cfg)
    for k in range(1, 6):
        tracker.predict(DT_S)
        tracker.update_coefficients(None)
        assert tracker.valid == (k <= 4)
    assert tracker.offset_m() is None and tracker.offset_variance_m2() is None
    tracker.predict(DT_S)
    far = truth + np.array([3.5, 0.0, 0.0])  # a jump the gate would reject on a live track
    assert tracker.update_coefficients(far).status is UpdateStatus.INITIALIZED
    assert tracker.valid and tracker.lateral_m() == pytest.approx(far[0], abs=0.01)


def test_covariance_stays_symmetric_positive_definite() -> None:
    rng = np.random.default_rng(9)
    tracker = LaneTracker()
    for k in range(300):
        tracker.predict(DT_S, SPEED_MPS, 0.1 * np.sin(0.05 * k))
        z = None if k % 7 == 3 else [-1.7, 0.0, 1e-3] + 0.05 * rng.standard_normal(3)
        tracker.update_coefficients(z)
        p = tracker.P
        assert np.allclose(p, p.T, atol=1e-15)
        assert np.linalg.eigvalsh(p).min() > 0.0


def test_offset_sign_and_variance_follow_the_curve() -> None:
    tracker = LaneTracker()
    tracker.update_coefficients([-1.0, 0.02, 1e-3])  # lane centre 1 m to the right
    assert tracker.offset_m() == pytest.approx(1.0, abs=1e-3)  # car left of centre: positive
    assert tracker.offset_m(10.0) == pytest.approx(1.0 - 0.2 - 0.1, abs=1e-2)
    assert tracker.offset_variance_m2(20.0) > tracker.offset_variance_m2(0.0) > 0.0


def _coast_after_a_curved_fit(coast_with_rates: bool) -> tuple[np.ndarray, np.ndarray]:
    """Track a straight lane, fuse one fit that bends it (c2 -0.002), then coast 6 steps.

    Returns the state just after that fit and after the coast.
    """
    cfg = TrackerConfig(c2_accel_psd_pm2ps3=3e-4, coast_with_rates=coast_with_rates)
    rng = np.random.default_rng(4)
    tracker = LaneTracker(cfg)
    straight = np.array([-1.75, 0.0, 0.0])
    for _ in range(30):
        tracker.predict(DT_S, SPEED_MPS, 0.0)
        tracker.update_coefficients(straight + rng.multivariate_normal(np.zeros(3),
                                                                       cfg.coefficient_r))
    tracker.predict(DT_S, SPEED_MPS, 0.0)
    assert tracker.update_coefficients([-1.75, 0.02, -0.002]).status is UpdateStatus.UPDATED
    after_fit = tracker.x
    for _ in range(6):
        tracker.predict(DT_S, SPEED_MPS, 0.0)
        assert tracker.update_coefficients(None).status is UpdateStatus.MISSED
    return after_fit, tracker.x


def test_coasting_without_rates_does_not_extrapolate_one_fits_curvature() -> None:
    after_fit, coasted = _coast_after_a_curved_fit(coast_with_rates=False)
    c2_rate = after_fit[5]
    assert c2_rate < -0.005  # the bent fit left a curvature rate behind
    # One prediction step uses the rate (the coast is only known after it); then it is 0.
    assert np.all(coasted[3:] == 0.0)
    assert abs(coasted[2] - (after_fit[2] + c2_rate * DT_S)) < 2e-4
    _, coasted_with_rates = _coast_after_a_curved_fit(coast_with_rates=True)
    # With the rates extrapolated the same fit becomes a 2.5x tighter curve in 0.6 s.
    assert coasted_with_rates[2] < 2.5 * coasted[2] < 0.0
