"""Rear-camera reference repair (paper 001 §3).

The MMAE judges the front models against the rear-camera reference, so a reference failure
(a speed bump, a glare frame) would punish healthy models. Paper 001 §3: a reference that changes
by more than a threshold (20 cm found best) from its previous value has failed, and is replaced by
the average of the measured value and a linear extrapolation of previous values.

Our reading of "previous values": the last two *accepted* (unrepaired, unflagged) values. Feeding
repaired values back instead makes a one-step spike echo: a 0.6 m spike leaves the output 0.3 m
off for three steps, and lets a sustained failure through after two steps, because the repaired
value walks towards the failure. A reference that stays away from its last accepted value for more
than `max_repair_steps` (or comes back after a gap that long) is taken as a genuine change, such as
a lane change, and accepted as is.
"""

from __future__ import annotations

from collections import deque

import numpy as np


class ReferenceRepair:
    """Flags and repairs jumps of a scalar reference signal, one call per control step."""

    def __init__(self, jump_threshold_m: float = 0.20, max_repair_steps: int = 5) -> None:
        if not (np.isfinite(jump_threshold_m) and jump_threshold_m > 0):
            raise ValueError(f"jump_threshold_m must be positive, got {jump_threshold_m}")
        if max_repair_steps < 1:
            raise ValueError(f"max_repair_steps must be >= 1, got {max_repair_steps}")
        self.jump_threshold_m = jump_threshold_m
        self.max_repair_steps = max_repair_steps
        self.reset()

    def reset(self) -> None:
        self._k = -1
        self._accepted: deque[tuple[int, float]] = deque(maxlen=2)  # (step, value)

    def __call__(self, value_m: float | None) -> tuple[float | None, bool]:
        """Return (the reference to use, whether this value was flagged as a failure).

        None or a non-finite value is a missed step: (None, False), history kept.
        """
        self._k += 1
        if value_m is None or not np.isfinite(value_m):
            return None, False
        value_m = float(value_m)
        if self._accepted and self._k - self._accepted[-1][0] > self.max_repair_steps:
            self._accepted.clear()  # too long away: a genuine change, start again
        if not self._accepted or abs(value_m - self._accepted[-1][1]) <= self.jump_threshold_m:
            self._accepted.append((self._k, value_m))
            return value_m, False
        k1, z1 = self._accepted[-1]
        if len(self._accepted) == 2:  # linear extrapolation of the last two accepted values
            k0, z0 = self._accepted[0]
            extrapolated = z1 + (z1 - z0) * (self._k - k1) / (k1 - k0)
        else:
            extrapolated = z1
        return 0.5 * (value_m + extrapolated), True  # §3: average of measured and extrapolated
