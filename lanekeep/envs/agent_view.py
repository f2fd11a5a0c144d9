"""What a learning agent sees of one control step, and what it is paid: shared by the dm_env
face (lanekeep/envs/dm_env_face.py) and the Gymnasium face (lanekeep/envs/gym_env.py), so
both name the same
numbers the same way.

The view holds only what the car's own loop holds: the two camera frames, the estimators'
lanes and the vehicle's sensor signals (`StepResult.signals`, noisy as configured). The reward
and the `info` entries are the simulator's truth; they score the agent and never reach it as
an observation.

Sign conventions (vehicle frame: x forward, y left, as in detectors/base.py): an
`offset_m` is + when the car is left of the lane centre; `heading_rad` is the angle of the lane
centre line at the look-ahead relative to the car's heading, + = the lane runs towards the
car's left; `curvature_1pm` is + for a lane turning left.
"""

from __future__ import annotations

import atexit
import math
import weakref

import numpy as np

from lanekeep.geometry.lane_poly import LanePoly
from lanekeep.loop.episode import Episode, Percept, StepResult
from lanekeep.scoring.step_score import FUSED

LANE_KEYS = ("valid", "offset_m", "heading_rad", "curvature_1pm")
SIGNAL_KEYS = ("speed_mps", "yaw_rate_rps", "accel_long_mps2", "accel_lat_mps2",
               "steer_angle_rad")
# Symmetric bounds of every named number (the spaces' limits; values are clipped to them).
# Generous: a track that ran off beyond 20 m or a 1 m turn radius means nothing to steer on.
LIMITS = {"offset_m": 20.0, "heading_rad": math.pi / 2, "curvature_1pm": 1.0,
          "speed_mps": 100.0, "yaw_rate_rps": 10.0, "accel_long_mps2": 100.0,
          "accel_lat_mps2": 100.0, "steer_angle_rad": 1.0}


def bounded(key: str, value: float) -> float:
    """`value` clipped to LIMITS[key]."""
    limit = LIMITS[key]
    return min(max(value, -limit), limit)


def lane_names(models: list[str]) -> list[str]:
    """The entries of `lanes`: each front model's own Kalman track, then the MMAE output."""
    return [*models, FUSED]


def _lane(centre: np.ndarray | None, offset_m: float | None, x_m: float) -> dict[str, float]:
    """One lane at look-ahead x: zeros with valid = 0 when there is none (never NaN)."""
    if centre is None or offset_m is None:
        return dict.fromkeys(LANE_KEYS, 0.0)
    lane = LanePoly.of(centre)
    return {"valid": 1.0, "offset_m": bounded("offset_m", float(offset_m)),
            "heading_rad": lane.heading_rad(x_m),
            "curvature_1pm": bounded("curvature_1pm", float(lane.curvature_1pm(x_m)))}


def view(percept: Percept, models: list[str]) -> dict:
    """The named numbers of one percept (python floats within LIMITS; each face casts them).

    `lanes[<model>]` is the model's own track and `lanes["fused"]` the MMAE output, both at the
    output's look-ahead; `detected[<model>]` says whether the model's raw detection on this
    frame was valid; `reference` is the rear reference's offset. All of it comes from the
    frames and sensor signals of `Episode.observe`: no truth.
    """
    estimate = percept.estimate
    x = estimate.offset_x_m
    lanes = {}
    for name in models:
        track = estimate.tracked[name]
        offset = None if track is None else float(LanePoly.of(track).offset_m(x))
        lanes[name] = _lane(track, offset, x)
    lanes[FUSED] = _lane(estimate.centre, estimate.offset_m, x)
    ref = estimate.selection.reference_m
    signals = percept.signals
    return {
        "lanes": lanes,
        "detected": {name: float(percept.estimates[name].valid) for name in models},
        "reference": {"valid": float(ref is not None),
                      "offset_m": 0.0 if ref is None else bounded("offset_m", float(ref))},
        "probabilities": [float(p) for p in estimate.selection.probabilities],
        "selected": int(estimate.selected),
        "vehicle": {key: bounded(key, float(getattr(signals, key))) for key in SIGNAL_KEYS},
    }


def progress_m(episode: Episode, result: StepResult) -> float:
    """Metres the car advanced along the road in this step (truth; wraps on a closed track)."""
    road = episode.world.road
    s, _ = road.local_coordinates(np.array([result.sensed_pose[:2], result.pose[:2]]))
    ds = float(s[1] - s[0])
    if road.closed:
        ds = (ds + road.length_m / 2.0) % road.length_m - road.length_m / 2.0
    return ds


def reward(episode: Episode, result: StepResult) -> tuple[float, float]:
    """(reward, progress_m) of one step: progress minus a lateral-error penalty, from truth.

    progress = metres advanced / (target speed x period), capped at 1 so speeding pays nothing;
    penalty = |true offset from the ego lane centre| / half a lane width, capped at 1. Driving
    the lane centre at the target speed pays 1 per step; standing still pays at most 0.
    """
    scenario = episode.scenario
    ds = progress_m(episode, result)
    per_step = max(scenario.target_speed_mps, 1.0) * episode.dt_s
    half_lane = episode.world.road.lane_width_m / 2.0
    penalty = min(abs(result.truth_offset_m) / half_lane, 1.0)
    return min(ds / per_step, 1.0) - penalty, ds


def departed(result: StepResult) -> bool:
    """A wheel crossed an ego-lane boundary in this step (truth)."""
    return any(e.startswith("lane departure") for e in result.events)


class EpisodeSlot:
    """Holds an environment's current Episode and closes it when the environment is collected
    or the interpreter exits, before EGL shuts down: MuJoCo's renderers freed by their own
    `__del__` after `eglTerminate` (an atexit hook mujoco.egl adds with its first context)
    print EGLError tracebacks. Our atexit hook is added after an Episode (so after that
    context) exists, and atexit runs hooks last-in first-out."""

    def __init__(self, owner: object) -> None:
        self.episode: Episode | None = None
        self._at_exit = False
        finalizer = weakref.finalize(owner, self._release)
        finalizer.atexit = False  # at exit, the hook below runs instead, in the right order

    def replace(self, episode: Episode) -> Episode:
        self.close()
        self.episode = episode
        if not self._at_exit:
            atexit.register(self.close)
            self._at_exit = True
        return episode

    def close(self) -> None:
        if self.episode is not None:
            self.episode.close()
            self.episode = None

    def _release(self) -> None:
        self.close()
        if self._at_exit:
            atexit.unregister(self.close)
            self._at_exit = False
