"""The paper's steering PID (eq. 9) with a gain schedule, and a speed PI. The interface a
controller meets is lanekeep/control/base.py; the registry by name lanekeep/control/registry.py.

The PID and the PI run at the control period and saturate to [-1, 1] with conditional-integration
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
    """Closed-loop targets from which the PID gains follow (see `derive_gains`), the
    straight/curvy schedule and the integrator's limits.

    The paper's Table 2 gains act on its own offset units; by default ours act on metres and
    are derived from a time constant and a damping ratio instead of copied (`PaperGains`
    gives the Table 2 set, converted).
    """

    tau_straight_s: float = 0.9  # closed-loop time constant on straights
    tau_curvy_s: float = 0.4  # faster on curves, where the lane runs away from the car
    zeta: float = 0.8  # damping ratio
    integral_time_curvy_s: float = 6.0  # paper: K_i > 0 only on curvy roads
    # Schedule with hysteresis: enter the curvy set above the threshold, leave it only below
    # `curvy_exit_ratio` times it, so that a curvature estimate hovering near the threshold
    # (noise, a clothoid's ends) does not toggle the gains every step.
    curvy_threshold_1pm: float = 1.0 / 400.0
    curvy_exit_ratio: float = 0.6
    # Anti-windup clamp on the integrator, in steer units (the integrator holds Ki-weighted
    # error, see SteeringPID). 0.3 of full lock is 10.5 deg at 35 deg lock: enough to hold a
    # curve of radius L / tan(10.5 deg) ~ 15 m (L = 2.8 m) without feed-forward (the paper's
    # mode has none), while P and D keep 70% of the authority.
    integral_limit_steer: float = 0.3
    # While Ki = 0 (straight set) the integrator relaxes to zero with this time constant.
    # Holding it would carry a curve's standing steer (0.11 of lock for 40 m radius) onto the
    # following straight as a bias that the straight set (no Ki) could only fight with a
    # standing offset; dropping it at once (what eq. 9 does with Ki = 0) is the bump we avoid.
    # None holds it.
    integral_decay_s: float | None = 1.0
    curvature_feedforward: bool = True

    def __post_init__(self) -> None:
        if not 0.0 < self.curvy_exit_ratio <= 1.0:
            raise ValueError(f"curvy_exit_ratio must be in (0, 1], got {self.curvy_exit_ratio}")
        if self.integral_limit_steer < 0:
            raise ValueError(f"integral_limit_steer must be >= 0, got {self.integral_limit_steer}")
        if self.integral_decay_s is not None and self.integral_decay_s <= 0:
            raise ValueError(f"integral_decay_s must be > 0 or None, got {self.integral_decay_s}")


@dataclass(frozen=True)
class Gains:
    """Discrete PID gains of paper eq. 9, in steer units per metre of offset."""

    kp: float
    ki: float  # per metre per step (eq. 9 sums e_i without dt)
    kd: float  # per metre of change per step

    def scaled(self, factor: float) -> Gains:
        return Gains(self.kp * factor, self.ki * factor, self.kd * factor)


@dataclass(frozen=True)
class PaperGains:
    """Table 2 of the paper (steer per offset unit, per control step), and the one factor
    that converts its offset unit to metres.

    The paper never names the unit of e_k in eq. 9; its offsets are reported in cm (Tables 3
    and 4), so `units_per_m = 100` (e in cm). The same factor follows from the loop itself,
    a kinematic bicycle at 15 m/s, L = 2.8 m, 35 deg lock, reading the offset 5 m ahead with
    one 0.1 s control step of delay (discrete poles, exact zero-order hold):

    * the straight set is stable for a factor below 362 (damping grows with the factor up to
      ~250, since Kd = Kp fixes the derivative's extra look-ahead at v dt = 1.5 m);
    * the curvy set (Ki = 0.05 Kp per step) is stable only between 19.8 and 226.
    * 100 leaves gain margins of 2.3x (up) and 5x (down) for the curvy set and 3.6x for the
      straight one; its straight poles are s = -0.82 +- 2.21j (zeta 0.35, ~1.2 s decay),
      the curvy ones -1.33 +- 3.68j and an integral mode at -0.49 (2 s).
    * the straight Kp, 0.1 steer/m, is what `derive_gains` gives at 15 m/s for a closed-loop
      time constant of 0.45 s (L / (v tau)^2 / max_steer), between our straight and curvy
      targets.

    The ratios of Table 2 are kept exactly; the gains are speed independent, as in the paper.
    """

    straight: Gains = Gains(kp=0.001, ki=0.0, kd=0.001)
    curvy: Gains = Gains(kp=0.002, ki=0.0001, kd=0.001)
    units_per_m: float = 100.0

    def gains(self, curvy: bool) -> Gains:
        """Gains per metre of offset for the straight or curvy set."""
        return (self.curvy if curvy else self.straight).scaled(self.units_per_m)


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
    with hysteresis (`SteeringTuning.curvy_exit_ratio`). They are either re-derived for the
    current speed (`derive_gains`, default) or the paper's Table 2 (`paper_gains`).

    Bumpless transfer: the integrator holds the integrated contribution, I_k = I_{k-1} +
    Ki_k e_k (steer units, as openpilot's common/pid.py does), rather than sum(e_i) multiplied
    by the current Ki. With a fixed Ki the two are the same eq. 9 term; when the schedule
    changes Ki, only future accumulation changes, so the output never jumps by (Ki_new -
    Ki_old) sum(e_i) at the switch. The integrator is clamped (`integral_limit_steer`), frozen
    while the output saturates in the error's direction (anti-windup), and relaxes to zero
    while Ki = 0 (`integral_decay_s`). Output: steer in [-1, 1], + = left.

    Our addition to eq. 9 (derived gains only): a curvature feed-forward, the steady-state
    Ackermann angle atan(L kappa) of the estimated lane curvature, so that the feedback only
    corrects errors instead of having to build a standing offset (or a slow integral) to hold
    a curve. It is off with `paper_gains` (the paper's pure PID) or with
    `SteeringTuning.curvature_feedforward = False`.
    """

    def __init__(self, dt_s: float, lookahead_m: float, wheelbase_m: float,
                 max_steer_rad: float, tuning: SteeringTuning | None = None,
                 paper_gains: PaperGains | None = None) -> None:
        if dt_s <= 0:
            raise ValueError(f"dt_s must be > 0, got {dt_s}")
        self.dt_s = dt_s
        self.lookahead_m = lookahead_m
        self.wheelbase_m = wheelbase_m
        self.max_steer_rad = max_steer_rad
        self.tuning = tuning or SteeringTuning()
        self.paper_gains = paper_gains
        self.feedforward = self.tuning.curvature_feedforward and paper_gains is None
        self.reset()

    def reset(self) -> None:
        self.integral = 0.0  # integrated Ki * e, steer units
        self.previous_error: float | None = None
        self.curvy = False

    def update_schedule(self, curvature_1pm: float) -> bool:
        """Straight/curvy with hysteresis: enter above the threshold, leave below
        `curvy_exit_ratio` times it."""
        t = self.tuning
        kappa = abs(curvature_1pm) if math.isfinite(curvature_1pm) else 0.0
        if self.curvy:
            self.curvy = kappa >= t.curvy_exit_ratio * t.curvy_threshold_1pm
        else:
            self.curvy = kappa > t.curvy_threshold_1pm
        return self.curvy

    def gains(self, speed_mps: float, curvature_1pm: float) -> Gains:
        """Update the schedule from the curvature and return the gains per metre in force."""
        curvy = self.update_schedule(curvature_1pm)
        if self.paper_gains is not None:
            return self.paper_gains.gains(curvy)
        t = self.tuning
        tau = t.tau_curvy_s if curvy else t.tau_straight_s
        ti = t.integral_time_curvy_s if curvy else None
        return derive_gains(tau, t.zeta, speed_mps, self.lookahead_m, self.dt_s,
                            self.wheelbase_m, self.max_steer_rad, ti)

    def __call__(self, offset_m: float | None, speed_mps: float, curvature_1pm: float = 0.0,
                 schedule_curvature_1pm: float | None = None) -> float:
        """`curvature_1pm` feeds the feed-forward and, unless `schedule_curvature_1pm` is
        given, the gain schedule."""
        if offset_m is None or not math.isfinite(offset_m):
            # No estimate: hold the wheel straight-ish, keep state (coasting is the tracker's job).
            return 0.0
        t = self.tuning
        g = self.gains(speed_mps, curvature_1pm if schedule_curvature_1pm is None
                       else schedule_curvature_1pm)
        error = -offset_m  # eq. 9: target offset 0
        delta = 0.0 if self.previous_error is None else error - self.previous_error
        self.previous_error = error
        fixed = g.kp * error + g.kd * delta  # eq. 9, P and D terms
        if self.feedforward:
            fixed += math.atan(self.wheelbase_m * curvature_1pm) / self.max_steer_rad
        if g.ki > 0:
            # eq. 9's Ki sum(e_i), accumulated as Ki e_k so that a gain change is bumpless
            limit = t.integral_limit_steer
            candidate = min(max(self.integral + g.ki * error, -limit), limit)
            out = min(max(fixed + candidate, -1.0), 1.0)
            saturated = (out >= 1.0 and error > 0) or (out <= -1.0 and error < 0)
            if not saturated:  # conditional integration (anti-windup)
                self.integral = candidate
        out = min(max(fixed + self.integral, -1.0), 1.0)
        if g.ki == 0 and t.integral_decay_s is not None:
            # straight set: let the curve's integral go smoothly, after this step's output
            self.integral *= math.exp(-self.dt_s / t.integral_decay_s)
        return out
