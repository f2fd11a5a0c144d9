"""Front-model lane estimates carried forward by odometry to where the rear reference looks.

The rear camera sees, at step k, road that the front camera saw some steps earlier. Comparing
car-relative offsets across those steps (paper eq. 2 compares z_ref(k) with z_n(k-1)) mixes in
how the car has moved and turned since. Here each front model's lane-centre point at its
look-ahead is stored in world (odometry) coordinates; at step k the stored points are brought
into the current vehicle frame and interpolated at the reference's look-behind x, giving the
offset each model *predicted* for the point the reference measures now. The residual
r_n = z_ref(k) - z_n(aligned) then differs from zero only by estimation error.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from lanekeep.geometry.lane_poly import LanePoly


class OdometryAlignedHistory:
    """Per model, world points of its lane centre (x, y, variance) at successive steps."""

    def __init__(self, n_models: int, max_steps: int = 80) -> None:
        self.n_models = n_models
        self._points: list[deque] = [deque(maxlen=max_steps) for _ in range(n_models)]

    def reset(self) -> None:
        for points in self._points:
            points.clear()

    def push(self, pose: tuple[float, float, float], centres: list[np.ndarray | None],
             variances_m2: list[float | None], look_ahead_m: float) -> None:
        """Store each model's lane-centre point at `look_ahead_m` (None = nothing this step)."""
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        for points, centre, var in zip(self._points, centres, variances_m2, strict=True):
            if centre is None or var is None or not math.isfinite(var):
                continue
            ly = float(LanePoly.of(centre).y(look_ahead_m))
            points.append((x + c * look_ahead_m - s * ly, y + s * look_ahead_m + c * ly, var))

    def offsets_at(self, pose: tuple[float, float, float], x_m: float
                   ) -> tuple[list[float | None], list[float | None]]:
        """Each model's predicted offset (and variance) at vehicle-frame x = `x_m` now."""
        x0, y0, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        offsets: list[float | None] = []
        variances: list[float | None] = []
        for points in self._points:
            if len(points) < 2:
                offsets.append(None)
                variances.append(None)
                continue
            arr = np.asarray(points)
            dx, dy = arr[:, 0] - x0, arr[:, 1] - y0
            local_x = c * dx + s * dy  # world -> current vehicle frame
            local_y = -s * dx + c * dy
            order = np.argsort(local_x)
            lx, ly, lv = local_x[order], local_y[order], arr[order, 2]
            if not lx[0] <= x_m <= lx[-1]:
                offsets.append(None)
                variances.append(None)
                continue
            y_at = float(np.interp(x_m, lx, ly))
            offsets.append(-y_at)  # offset convention: + = car left of the lane centre
            variances.append(float(np.interp(x_m, lx, lv)))
        return offsets, variances
