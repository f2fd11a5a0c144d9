"""The car's motion over one control period, as its own sensors give it, applied to ground points.

Both the lane tracks (estimators/kalman.py `ego_motion_transform`) and a detector that keeps
what it saw in earlier frames (detectors/point_memory.py) move things seen in the last vehicle
frame into this one. Wheel speed, yaw rate and the sideslip the odometry estimates are held over
the period; the car drives an arc, and a point fixed on the road moves the other way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PeriodMotion:
    """One period's motion in the last vehicle frame: the new frame's origin lies at (`tx_m`,
    `ty_m`) in it, its x axis turned by `yaw_rad` (+ = left)."""

    tx_m: float
    ty_m: float
    yaw_rad: float

    @classmethod
    def of(cls, speed_mps: float, yaw_rate_rps: float, dt_s: float,
           lateral_speed_mps: float = 0.0) -> PeriodMotion:
        """The chord of the arc driven at `speed_mps` and `yaw_rate_rps` over `dt_s`, turned by
        the slip angle of `lateral_speed_mps` (body-frame sideways speed, + = left)."""
        yaw = yaw_rate_rps * dt_s
        ds = float(np.hypot(speed_mps, lateral_speed_mps)) * dt_s * (1.0 if speed_mps >= 0
                                                                     else -1.0)
        if abs(yaw) < 1e-9:
            tx, ty = ds, 0.0
        else:  # chord of an arc of radius ds / yaw
            tx, ty = ds / yaw * np.sin(yaw), ds / yaw * (1.0 - np.cos(yaw))
        if lateral_speed_mps != 0.0:  # the arc is travelled at the slip angle beta to the body x
            beta = np.arctan2(lateral_speed_mps, abs(speed_mps)) * (1.0 if speed_mps >= 0
                                                                    else -1.0)
            tx, ty = tx * np.cos(beta) - ty * np.sin(beta), tx * np.sin(beta) + ty * np.cos(beta)
        return cls(float(tx), float(ty), float(yaw))

    def carry(self, xy_m: np.ndarray) -> np.ndarray:
        """Ground points (N, 2) of the last vehicle frame in the new one: p_new = Rot(-yaw)
        (p_old - t)."""
        xy = np.asarray(xy_m, dtype=float).reshape(-1, 2)
        dx, dy = xy[:, 0] - self.tx_m, xy[:, 1] - self.ty_m
        cos_y, sin_y = np.cos(self.yaw_rad), np.sin(self.yaw_rad)
        return np.stack([cos_y * dx + sin_y * dy, -sin_y * dx + cos_y * dy], axis=-1)
