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
