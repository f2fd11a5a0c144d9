"""Ground points a detector saw in its last few frames, carried into this frame by the car's
own motion (wheel speed and yaw rate: `lanekeep.geometry.vehicle_motion`).

Why: a rear camera sees a dashed line's paint near the car in some frames and a 9 m gap in
others; in the gap frames a one-frame observer has to infer the line and leans (docs/observer.md).
The dash it saw a few frames ago is still on the road, further back, where odometry says: kept
and carried, it gives the fit painted points in every frame.

The memory forgets everything when it is not told the motion between two frames (`move`):
a detector fed still frames (an eval set, `lanekeep detect`) must not carry points it cannot
place.
"""

from __future__ import annotations

import numpy as np

from lanekeep.geometry.vehicle_motion import PeriodMotion


class PointMemory:
    """Per slot, the ground points (x, y; m, vehicle frame) of the last `frames` frames."""

    def __init__(self, frames: int, max_range_m: float) -> None:
        if frames < 0:
            raise ValueError(f"frames must be >= 0, got {frames}")
        self.frames = frames
        self.max_range_m = max_range_m
        self.reset()

    def reset(self) -> None:
        self._entries: list[tuple[int, np.ndarray, np.ndarray]] = []  # (age, xy, slots)
        self._moved = False

    def move(self, motion: PeriodMotion) -> None:
        """One period on: every point carried into the new vehicle frame and a frame older;
        those older than `frames` or further than `max_range_m` are dropped."""
        kept = []
        for age, xy, slots in self._entries:
            if age + 1 > self.frames:
                continue
            moved = motion.carry(xy)
            near = np.hypot(moved[:, 0], moved[:, 1]) <= self.max_range_m
            if near.any():
                kept.append((age + 1, moved[near], slots[near]))
        self._entries = kept
        self._moved = True

    def recall(self) -> tuple[np.ndarray, np.ndarray]:
        """Every kept point (N, 2) and its slot (N,); nothing when no motion was told since the
        last frame (the points could not be placed)."""
        if not self._moved or not self._entries:
            return np.zeros((0, 2)), np.zeros(0, np.int64)
        return (np.concatenate([xy for _, xy, _ in self._entries]),
                np.concatenate([s for _, _, s in self._entries]))

    def remember(self, xy: np.ndarray, slots: np.ndarray) -> None:
        """This frame's points (age 0); the next frame needs a `move` first. Without a `move`
        since the last frame, what was kept is forgotten: it could not be placed."""
        if not self._moved:
            self._entries = []
        if self.frames > 0 and len(xy):
            self._entries.append((0, np.asarray(xy, float).reshape(-1, 2),
                                  np.asarray(slots, np.int64).ravel()))
        self._moved = False
