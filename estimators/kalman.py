"""Kalman tracker of one lane polynomial (paper 000 §2.3, with ego-motion prediction).

The tracked curve is y(x) = c0 + c1 x + c2 x^2 in the vehicle ground frame (x forward, y left,
metres). The state is ``[c0, c1, c2, dc0/dt, dc1/dt, dc2/dt]``: paper 000 §2.3 models the lane
parameters as a hidden Markov state with a linear constant-velocity transition
``x(t+1) = f(x(t)) + w``, ``w ~ N(0, Q)``, observed as ``z = h(x) + v``, ``v ~ N(0, R)``.

What we add to the paper's tracker:

* ego-motion prediction: given speed and yaw rate over the step, the polynomial is moved into the
  new vehicle frame before the update (the paper's trackers ignore this; it is what keeps a coasted
  lane on the road in a turn);
* a Mahalanobis gate (chi-square, 99 % by default) that rejects outliers;
* coasting: a missed, non-finite or gated measurement only predicts; after ``max_coast_steps``
  misses in a row the track reports invalid, and the next good measurement re-initialises it.

Episode use, once per control period::

    tracker.predict(dt_s, speed_mps, yaw_rate_rps)
    tracker.update_coefficients(centreline_coefficients_or_None)   # or update_offset(...)
    offset_m, variance_m2 = tracker.offset_m(x_m), tracker.offset_variance_m2(x_m)

Call exactly one update per step (with None when the detector gave nothing): missed updates are
what the coasting counter counts. Offsets are None while the track is invalid.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
from filterpy.kalman import KalmanFilter
from numpy.typing import ArrayLike
from scipy.stats import chi2

from lanekeep.geometry.vehicle_motion import PeriodMotion

N_COEF = 3  # c0, c1, c2
DIM_X = 2 * N_COEF  # coefficients and their rates


@dataclass(frozen=True)
class TrackerConfig:
    """Noise, gate and coasting settings of a `LaneTracker`.

    Process noise is continuous white noise on the second time derivative of each coefficient
    (constant-velocity model). The defaults are the closed loop's (what an `Episode` runs;
    estimators/closed_loop_tracker.toml adds only the measured R): they assume ego-motion
    prediction is on, so Q only has to cover what speed and yaw rate do not explain (sideslip,
    sensor bias, curvature changes); with ego-motion off use `constant_velocity_only()`, whose
    Q also covers the car's own weaving. Measurement standard deviations are a detector's
    coefficient noise (a fit over ~30 m: 5 cm at the car, 0.3 m at 30 m from the heading term).
    """

    c0_accel_psd_m2ps3: float = 0.003
    # Q of c1 and c2: ego-motion explains most of the lane's motion in the car frame; what it
    # cannot is the road's own curvature change (a clothoid into a 40 m radius turns c2 by
    # 0.0125 /m within 1.3 s at 15 m/s, a rate of ~0.01 /m/s) and the sideslip change that
    # comes with it (c1 ~0.03 /s): sized so the filter follows those within 2-3 steps instead
    # of gating them.
    c1_accel_psd_ps3: float = 1e-3
    c2_accel_psd_pm2ps3: float = 3e-4
    c0_measurement_std_m: float = 0.05
    c1_measurement_std: float = 0.01
    c2_measurement_std_pm: float = 2.5e-4
    offset_measurement_std_m: float = 0.10  # 1-D mode: one offset, no fit to average over
    initial_coefficient_std: tuple[float, float, float] = (2.0, 0.2, 0.01)
    # With the ego-motion predicted, a lane's coefficients hardly drift on their own: a new
    # track's rates start near 0 (0.1 m/s, 0.02 /s), not free. A free c0 rate (1 m/s) takes the
    # first innovation after a (re)start, one fit's noise over one step, for a drift and coasts
    # the track off the road.
    initial_rate_std: tuple[float, float, float] = (0.1, 0.02, 1e-3)
    gate_probability: float = 0.99
    max_coast_steps: int = 10  # 1 s at the 0.1 s control period
    # Whether a coasting track (gated or missed) keeps extrapolating its rates. With the
    # ego-motion predicted, the rates are what one or two recent fits did not explain; carried
    # through a coast they turn one noisy fit's curvature into a hairpin the car then follows.
    # False: a coasting track moves with the ego-motion only (its rate means return to their
    # prior, 0, and their spread is kept in P). Without ego-motion the rates are the car's own
    # weaving and must be extrapolated (`constant_velocity_only()`). In snow one accepted bad
    # fit gave the c2 rate 0.024 /s (2.5x the sharpest clothoid we ship), and the car, steered
    # by a track that coasted with it, followed a 40 m hairpin off a 300 m curve.
    coast_with_rates: bool = False
    ego_motion: bool = True
    ego_fit_range_m: float = 30.0  # look-ahead range refitted in the ego-motion transform
    ego_fit_points: int = 16
    # Full 3x3 R of a coefficient measurement; overrides the three stds above. A fitted
    # quadratic's coefficients are strongly correlated (c0-c1 about -0.9, c1-c2 about -0.99:
    # the fit pivots about its data, 5-30 m ahead), and a diagonal R gates ordinary fits.
    coefficient_covariance: tuple[tuple[float, float, float], ...] | None = None

    def __post_init__(self) -> None:
        positive = {
            "c0_accel_psd_m2ps3": self.c0_accel_psd_m2ps3,
            "c1_accel_psd_ps3": self.c1_accel_psd_ps3,
            "c2_accel_psd_pm2ps3": self.c2_accel_psd_pm2ps3,
            "c0_measurement_std_m": self.c0_measurement_std_m,
            "c1_measurement_std": self.c1_measurement_std,
            "c2_measurement_std_pm": self.c2_measurement_std_pm,
            "offset_measurement_std_m": self.offset_measurement_std_m,
            "ego_fit_range_m": self.ego_fit_range_m,
        }
        for name, value in positive.items():
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be positive and finite, got {value}")
        for name in ("initial_coefficient_std", "initial_rate_std"):
            value = getattr(self, name)
            if len(value) != N_COEF or not all(np.isfinite(v) and v > 0 for v in value):
                raise ValueError(f"{name} must be three positive numbers, got {value}")
        if not 0.0 < self.gate_probability < 1.0:
            raise ValueError(f"gate_probability must be in (0, 1), got {self.gate_probability}")
        if self.max_coast_steps < 0:
            raise ValueError(f"max_coast_steps must be >= 0, got {self.max_coast_steps}")
        if self.coefficient_covariance is not None:
            r = np.asarray(self.coefficient_covariance, dtype=float)
            if (r.shape != (N_COEF, N_COEF) or not np.all(np.isfinite(r))
                    or not np.allclose(r, r.T) or np.any(np.linalg.eigvalsh(r) <= 0)):
                raise ValueError("coefficient_covariance must be a symmetric positive-definite "
                                 f"3x3 matrix, got {self.coefficient_covariance}")
        if self.ego_fit_points < N_COEF:
            raise ValueError(f"ego_fit_points must be >= {N_COEF}, got {self.ego_fit_points}")

    @classmethod
    def constant_velocity_only(cls, **overrides: object) -> TrackerConfig:
        """The paper's tracker: no ego-motion, so Q must follow the car's own motion.

        Lateral changes of ~0.45 m/s^2 over ~0.5 s (0.1 m^2/s^3) and yaw-rate changes of
        ~0.05 rad/s^2 (1e-3 /s^3).
        """
        fields = {
            "ego_motion": False,
            "c0_accel_psd_m2ps3": 0.1,
            "c1_accel_psd_ps3": 1e-3,
            "c2_accel_psd_pm2ps3": 1e-6,
            "initial_rate_std": (1.0, 0.1, 1e-3),  # the car's weaving moves the lane freely
            "coast_with_rates": True,
        }
        fields.update(overrides)
        return cls(**fields)  # type: ignore[arg-type]

    @property
    def coefficient_r(self) -> np.ndarray:
        """R of a full coefficient measurement [c0, c1, c2]."""
        if self.coefficient_covariance is not None:
            return np.asarray(self.coefficient_covariance, dtype=float)
        std = (self.c0_measurement_std_m, self.c1_measurement_std, self.c2_measurement_std_pm)
        return np.diag(np.square(std))

    @property
    def initial_p(self) -> np.ndarray:
        """P of a fresh track, before its first measurement."""
        return np.diag(np.square(self.initial_coefficient_std + self.initial_rate_std))


class UpdateStatus(enum.Enum):
    """What an update did with its measurement."""

    INITIALIZED = "initialized"  # started (or restarted) the track, ungated
    UPDATED = "updated"  # passed the gate and was fused
    GATED = "gated"  # rejected by the chi-square gate; the track coasts
    MISSED = "missed"  # None, NaN or inf; the track coasts
    RESTARTED = "restarted"  # gated, but corroborated elsewhere: the track restarts from it


@dataclass(frozen=True)
class UpdateResult:
    """Outcome of one update; `nis` is the normalised innovation squared (NaN when missed)."""

    status: UpdateStatus
    nis: float


def cv_transition(dt_s: float) -> np.ndarray:
    """F of the constant-velocity model: c <- c + dc/dt * dt (paper 000 §2.3, f linear)."""
    f = np.eye(DIM_X)
    f[:N_COEF, N_COEF:] = dt_s * np.eye(N_COEF)
    return f


def cv_process_noise(dt_s: float, psd: ArrayLike) -> np.ndarray:
    """Q of white acceleration noise, per coefficient q [[dt^3/3, dt^2/2], [dt^2/2, dt]]."""
    q = np.zeros((DIM_X, DIM_X))
    for i, qi in enumerate(np.asarray(psd, dtype=float)):
        j = i + N_COEF
        q[i, i] = qi * dt_s**3 / 3.0
        q[i, j] = q[j, i] = qi * dt_s**2 / 2.0
        q[j, j] = qi * dt_s
    return q


def ego_motion_transform(
    coefficients: ArrayLike,
    speed_mps: float,
    yaw_rate_rps: float,
    dt_s: float,
    fit_range_m: float = 30.0,
    fit_points: int = 16,
    lateral_speed_mps: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Affine map c_new = A c + b of a polynomial into the vehicle frame after one step.

    The car drives an arc (speed, yaw rate held over dt). Points of the curve over the look-ahead
    range are moved rigidly into the new frame and refitted by least squares, which is linear in
    the curve's y values. The new-frame x of each point depends weakly on y (through sin(yaw)); it
    is taken at `coefficients` (the current mean), so the mean is mapped exactly and A is the
    Jacobian used for P with that O(yaw * slope) dependence neglected.

    `lateral_speed_mps` is the body-frame sideways velocity (sideslip): in a tight turn the car
    drifts outwards along its own y by ~v*beta*dt, 5-10 cm a step at 0.5 g, which would
    otherwise read as the lane moving.

    Returns:
        A (3, 3) and b (3,).
    """
    c = np.asarray(coefficients, dtype=float)
    motion = PeriodMotion.of(speed_mps, yaw_rate_rps, dt_s, lateral_speed_mps)
    tx, ty, yaw = motion.tx_m, motion.ty_m, motion.yaw_rad
    x_old = tx + np.linspace(0.0, fit_range_m, fit_points)
    v_old = np.vander(x_old, N_COEF, increasing=True)
    y_old = v_old @ c
    cos_y, sin_y = np.cos(yaw), np.sin(yaw)
    # p_new = Rot(-yaw) (p_old - t)
    x_new = cos_y * (x_old - tx) + sin_y * (y_old - ty)
    pinv_new = np.linalg.pinv(np.vander(x_new, N_COEF, increasing=True))
    a = pinv_new @ (cos_y * v_old)  # y_new = cos(yaw) y_old + ...
    b = pinv_new @ (-sin_y * (x_old - tx) - cos_y * ty)  # ... - sin(yaw) dx - cos(yaw) ty
    return a, b


class LaneTracker:
    """Kalman filter over a lane polynomial and its rates, with gate, coasting and ego-motion."""

    def __init__(self, config: TrackerConfig | None = None) -> None:
        self.config = config if config is not None else TrackerConfig()
        self._gate_thresholds: dict[int, float] = {}
        self._kf = KalmanFilter(dim_x=DIM_X, dim_z=N_COEF)
        self._kf.H = np.hstack([np.eye(N_COEF), np.zeros((N_COEF, N_COEF))])
        self._kf.R = self.config.coefficient_r
        self.reset()

    def reset(self) -> None:
        """Forget the track; the next good measurement starts a new one."""
        self._kf.x = np.zeros((DIM_X, 1))
        self._kf.P = self.config.initial_p
        self._initialized = False
        self._missed_steps = 0

    # ---- state -------------------------------------------------------------------------------
    @property
    def initialized(self) -> bool:
        return self._initialized

    @property
    def missed_steps(self) -> int:
        """Consecutive updates that fused nothing (missed, non-finite or gated)."""
        return self._missed_steps

    @property
    def valid(self) -> bool:
        """True while the track exists and has coasted no more than `max_coast_steps`."""
        return self._initialized and self._missed_steps <= self.config.max_coast_steps

    @property
    def x(self) -> np.ndarray:
        """State [c0, c1, c2, dc0/dt, dc1/dt, dc2/dt], a copy."""
        return self._kf.x[:, 0].copy()

    @property
    def P(self) -> np.ndarray:  # noqa: N802 (textbook symbol)
        return self._kf.P.copy()

    @property
    def coefficients(self) -> np.ndarray | None:
        """[c0, c1, c2] of y(x) = c0 + c1 x + c2 x^2, or None while invalid."""
        return self._kf.x[:N_COEF, 0].copy() if self.valid else None

    @property
    def coefficient_covariance(self) -> np.ndarray | None:
        """The 3x3 covariance of [c0, c1, c2] (P's coefficient block), or None while invalid."""
        return self._kf.P[:N_COEF, :N_COEF].copy() if self.valid else None

    def lateral_m(self, x_m: float = 0.0) -> float | None:
        """y of the tracked curve at look-ahead x_m (positive left), or None while invalid."""
        return float(self._h_lateral(x_m) @ self._kf.x[:, 0]) if self.valid else None

    def offset_m(self, x_m: float = 0.0) -> float | None:
        """Car offset from the tracked centreline at x_m, positive = car left of it (= -y)."""
        y = self.lateral_m(x_m)
        return None if y is None else -y

    def offset_variance_m2(self, x_m: float = 0.0) -> float | None:
        """C P C' of the offset at x_m (model term of paper 001 eq. 8), or None while invalid."""
        if not self.valid:
            return None
        h = self._h_lateral(x_m)
        return float(h @ self._kf.P @ h)  # C P C'

    # ---- predict -----------------------------------------------------------------------------
    def predict(self, dt_s: float, speed_mps: float = 0.0, yaw_rate_rps: float = 0.0,
                lateral_speed_mps: float = 0.0) -> None:
        """Propagate the track over dt_s; move the curve by the ego-motion when enabled.

        Non-finite speed or yaw rate means the ego-motion is unknown this step: the prediction is
        then the constant-velocity model alone, never NaN.
        """
        if not (np.isfinite(dt_s) and dt_s > 0):
            raise ValueError(f"dt_s must be positive and finite, got {dt_s}")
        if not self._initialized:
            return
        cfg = self.config
        f_cv = cv_transition(dt_s)
        q = cv_process_noise(
            dt_s, (cfg.c0_accel_psd_m2ps3, cfg.c1_accel_psd_ps3, cfg.c2_accel_psd_pm2ps3)
        )
        f, u = f_cv, np.zeros((DIM_X, 1))
        moving = np.isfinite(speed_mps) and np.isfinite(yaw_rate_rps)
        lateral_speed_mps = lateral_speed_mps if np.isfinite(lateral_speed_mps) else 0.0
        if cfg.ego_motion and moving and (speed_mps != 0.0 or yaw_rate_rps != 0.0):
            c_cv = (f_cv @ self._kf.x)[:N_COEF, 0]
            a, b = ego_motion_transform(
                c_cv, speed_mps, yaw_rate_rps, dt_s, cfg.ego_fit_range_m, cfg.ego_fit_points,
                lateral_speed_mps,
            )
            # c <- A (c + dc/dt dt) + b. The rates stay: they model what the ego-motion does not
            # explain (sideslip, yaw-rate bias, curvature change), which is set in the car frame;
            # transporting them by A as well would count the ego-motion twice.
            f = np.eye(DIM_X)
            f[:N_COEF, :N_COEF] = a
            f = f @ f_cv
            u[:N_COEF, 0] = b
        # x = F x + u ; P = F P F' + Q  (paper 000 §2.3: x(t+1) = f(x(t)) + w, w ~ N(0, Q))
        self._kf.predict(u=u, B=np.eye(DIM_X), F=f, Q=q)

    # ---- update ------------------------------------------------------------------------------
    def update_coefficients(self, coefficients: ArrayLike | None, r_scale: float = 1.0
                            ) -> UpdateResult:
        """Fuse a measured polynomial [c0, c1, c2] (H = [I 0]); None or non-finite = missed.
        `r_scale` multiplies R for this measurement alone (a detection whose own confidence
        says it is noisier or surer than its detector's average: estimators/confidence.py)."""
        if not (np.isfinite(r_scale) and r_scale > 0.0):
            raise ValueError(f"r_scale must be a positive number, got {r_scale}")
        if coefficients is None:
            return self._miss()
        z = np.asarray(coefficients, dtype=float).reshape(-1)
        if z.shape != (N_COEF,):
            raise ValueError(f"expected {N_COEF} coefficients, got shape {z.shape}")
        h = np.hstack([np.eye(N_COEF), np.zeros((N_COEF, N_COEF))])
        return self._update(z, h, r_scale * self.config.coefficient_r)

    def update_offset(self, offset_m: float | None, x_m: float = 0.0) -> UpdateResult:
        """Fuse a measured offset at look-ahead x_m (1-D mode); None or non-finite = missed.

        The offset is the car left of the curve, so z = -y(x_m) and H = -[1, x, x^2, 0, 0, 0].
        """
        if offset_m is None:
            return self._miss()
        h = -self._h_lateral(x_m)[None, :]
        r = np.array([[self.config.offset_measurement_std_m**2]])
        return self._update(np.array([float(offset_m)]), h, r)

    def _update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray) -> UpdateResult:
        if not np.all(np.isfinite(z)):
            return self._miss()  # bad input is a missed step, never fused
        if not self.valid:  # new or lost track: restart from the wide prior, ungated
            self.reset()
            self._kf.update(z[:, None], R=r, H=h)
            self._initialized = True
            self._symmetrize()
            return UpdateResult(UpdateStatus.INITIALIZED, float("nan"))
        x, p = self._kf.x, self._kf.P
        y = z[:, None] - h @ x  # y = z - H x
        s = h @ p @ h.T + r  # S = H P H' + R
        nis = float(y[:, 0] @ np.linalg.solve(s, y[:, 0]))  # NIS = y' S^-1 y
        if nis > self._gate_threshold(len(z)):
            self._coast()
            return UpdateResult(UpdateStatus.GATED, nis)
        # K = P H' S^-1; x = x + K y; P = (I - K H) P (I - K H)' + K R K'  (Joseph form, done
        # by filterpy's KalmanFilter.update)
        self._kf.update(z[:, None], R=r, H=h)
        self._symmetrize()
        self._missed_steps = 0
        return UpdateResult(UpdateStatus.UPDATED, nis)

    def restart(self, coefficients: ArrayLike, r_scale: float = 1.0) -> UpdateResult:
        """Drop the track and start a new one from this measurement, ungated.

        For a measurement the gate rejected but an independent source corroborates (two
        detectors that agree with each other outvote a track that has fallen behind the road,
        e.g. in a clothoid into a tight turn): without it the gate keeps rejecting until the
        track has coasted `max_coast_steps`.
        """
        self.reset()
        result = self.update_coefficients(coefficients, r_scale)
        if result.status is not UpdateStatus.INITIALIZED:
            return result
        return UpdateResult(UpdateStatus.RESTARTED, float("nan"))

    def _miss(self) -> UpdateResult:
        if self._initialized:
            self._coast()
        return UpdateResult(UpdateStatus.MISSED, float("nan"))

    def _coast(self) -> None:
        """Count a step with nothing fused; unless `coast_with_rates`, stop extrapolating the
        rates: their mean goes to the prior's 0 and P's rate block widens by the dropped mean
        (r r'), so a measurement that resumes the track may still carry any rate."""
        self._missed_steps += 1
        if self.config.coast_with_rates:
            return
        rates = self._kf.x[N_COEF:, 0].copy()
        self._kf.x[N_COEF:, 0] = 0.0
        self._kf.P[N_COEF:, N_COEF:] += np.outer(rates, rates)

    def _gate_threshold(self, dim_z: int) -> float:
        """Chi-square quantile of the gate for a dim_z-dimensional innovation."""
        if dim_z not in self._gate_thresholds:
            self._gate_thresholds[dim_z] = float(chi2.ppf(self.config.gate_probability, dim_z))
        return self._gate_thresholds[dim_z]

    def _symmetrize(self) -> None:
        self._kf.P = 0.5 * (self._kf.P + self._kf.P.T)

    @staticmethod
    def _h_lateral(x_m: float) -> np.ndarray:
        """Row [1, x, x^2, 0, 0, 0] that reads y(x_m) off the state."""
        return np.array([1.0, x_m, x_m * x_m, 0.0, 0.0, 0.0])
