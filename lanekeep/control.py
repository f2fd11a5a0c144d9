"""Controllers: the paper's steering PID (eq. 9) with a gain schedule, and a speed PI.

Both run at the control period and saturate to [-1, 1] with conditional-integration
anti-windup (the integrator only accumulates while the output is not saturated in the same
direction), as in openpilot's common/pid.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class SpeedGains:
    """Throttle per m/s of speed error and per m of integrated error."""

    kp: float = 0.6
    ki: float = 0.15
    kff_per_mps: float = 0.004  # feed-forward against rolling resistance and tyre damping


class SpeedController:
    """PI speed controller: throttle in [-1, 1] (negative = brake) toward a target speed."""

    def __init__(self, target_mps: float, dt_s: float, gains: SpeedGains | None = None) -> None:
        if dt_s <= 0:
            raise ValueError(f"dt_s must be > 0, got {dt_s}")
        self.target_mps = target_mps
        self.dt_s = dt_s
        self.gains = gains or SpeedGains()
        self.integral = 0.0

    def reset(self) -> None:
        self.integral = 0.0

    def __call__(self, speed_mps: float) -> float:
        if not math.isfinite(speed_mps):
            return 0.0
        error = self.target_mps - speed_mps
        g = self.gains
        unclipped = g.kp * error + g.ki * self.integral + g.kff_per_mps * self.target_mps
        out = min(max(unclipped, -1.0), 1.0)
        saturated = (out >= 1.0 and error > 0) or (out <= -1.0 and error < 0)
        if not saturated:
            self.integral += error * self.dt_s
        return out


@dataclass(frozen=True)
class SteeringTuning:
    """Closed-loop targets from which the PID gains follow (see `derive_gains`).

    The paper's Table 2 gains act on its own offset units; ours act on metres, so they are
    derived from a time constant and a damping ratio instead of copied.
    """

    tau_straight_s: float = 0.9  # closed-loop time constant on straights
    tau_curvy_s: float = 0.4  # faster on curves, where the lane runs away from the car
    zeta: float = 0.8  # damping ratio
    integral_time_curvy_s: float = 6.0  # paper: K_i > 0 only on curvy roads
    curvy_threshold_1pm: float = 1.0 / 400.0  # |curvature| above which the curvy set is used
    integral_limit_m_s: float = 2.0  # anti-windup clamp on the summed error (m*s)
    curvature_feedforward: bool = True


@dataclass(frozen=True)
class Gains:
    """Discrete PID gains of paper eq. 9, in steer units per metre of offset."""

    kp: float
    ki: float  # per metre per step (eq. 9 sums e_i without dt)
    kd: float  # per metre of change per step


def derive_gains(tau_s: float, zeta: float, speed_mps: float, lookahead_m: float, dt_s: float,
                 wheelbase_m: float, max_steer_rad: float, integral_time_s: float | None
                 ) -> Gains:
    """PID gains for a kinematic bicycle tracking an offset measured `lookahead_m` ahead.

    Linearised: y' = v psi, psi' = (v / L) delta, measured e = y + x_L psi. With
    delta = -k (y + X psi) the loop is s^2 + (v k X / L) s + v^2 k / L = 0, so for a natural
    frequency 1/tau: k = L / (v tau)^2 and X = 2 zeta v tau. The look-ahead supplies x_L of X;
    the derivative supplies the rest: (e_k - e_{k-1}) ~ v psi dt, so Kd = Kp (X - x_L) / (v dt).
    """
    v = max(speed_mps, 1.0)
    k_rad_per_m = wheelbase_m / (v * tau_s) ** 2
    kp = k_rad_per_m / max_steer_rad
    extra_lookahead = max(2.0 * zeta * v * tau_s - lookahead_m, 0.0)
    kd = kp * extra_lookahead / (v * dt_s)
    ki = 0.0 if not integral_time_s else kp * dt_s / integral_time_s
    return Gains(kp=kp, ki=ki, kd=kd)


class SteeringPID:
    """Paper eq. 9, s_k = Kp e_k + Ki sum(e_i) + Kd (e_k - e_{k-1}), e = 0 - offset.

    Gains are scheduled between a straight and a curvy set by the estimated road curvature,
    re-derived for the current speed; the integral is clamped and frozen while the output
    saturates (anti-windup). Output: steer in [-1, 1], + = left.

    Our addition to eq. 9: a curvature feed-forward, the steady-state Ackermann angle
    atan(L kappa) of the estimated lane curvature, so that the feedback only corrects errors
    instead of having to build a standing offset (or a slow integral) to hold a curve. Set
    `SteeringTuning.curvature_feedforward = False` for the paper's pure PID.
    """

    def __init__(self, dt_s: float, lookahead_m: float, wheelbase_m: float,
                 max_steer_rad: float, tuning: SteeringTuning | None = None) -> None:
        self.dt_s = dt_s
        self.lookahead_m = lookahead_m
        self.wheelbase_m = wheelbase_m
        self.max_steer_rad = max_steer_rad
        self.tuning = tuning or SteeringTuning()
        self.reset()

    def reset(self) -> None:
        self.error_sum = 0.0
        self.previous_error: float | None = None
        self.curvy = False

    def gains(self, speed_mps: float, curvature_1pm: float) -> Gains:
        t = self.tuning
        self.curvy = abs(curvature_1pm) > t.curvy_threshold_1pm
        tau = t.tau_curvy_s if self.curvy else t.tau_straight_s
        ti = t.integral_time_curvy_s if self.curvy else None
        return derive_gains(tau, t.zeta, speed_mps, self.lookahead_m, self.dt_s,
                            self.wheelbase_m, self.max_steer_rad, ti)

    def __call__(self, offset_m: float | None, speed_mps: float, curvature_1pm: float = 0.0
                 ) -> float:
        if offset_m is None or not math.isfinite(offset_m):
            # No estimate: hold the wheel straight-ish, keep state (coasting is the tracker's job).
            return 0.0
        g = self.gains(speed_mps, curvature_1pm)
        error = -offset_m  # eq. 9: target offset 0
        delta = 0.0 if self.previous_error is None else error - self.previous_error
        self.previous_error = error
        unclipped = g.kp * error + g.ki * self.error_sum + g.kd * delta  # eq. 9
        if self.tuning.curvature_feedforward:
            unclipped += math.atan(self.wheelbase_m * curvature_1pm) / self.max_steer_rad
        out = min(max(unclipped, -1.0), 1.0)
        saturated = (out >= 1.0 and error > 0) or (out <= -1.0 and error < 0)
        if not saturated and g.ki > 0:
            limit = self.tuning.integral_limit_m_s / self.dt_s
            self.error_sum = min(max(self.error_sum + error, -limit), limit)
        return out
