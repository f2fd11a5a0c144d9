"""`LaneKeepEnv`: a closed-loop scenario as a `dm_env.Environment` for learning agents.

The same view, reward and timing as the Gymnasium face (lanekeep/envs/gym_env.py's docstring; the
numbers are named in lanekeep/envs/agent_view.py), as nested dicts of float64 (`selected` int64):
`front`, `rear` (uint8 images), `lanes[<model> | "fused"]` {valid, offset_m, heading_rad,
curvature_1pm}, `detected[<model>]`, `reference` {valid, offset_m}, `probabilities`, `selected`
and `vehicle` {speed_mps, yaw_rate_rps, accel_long_mps2, accel_lat_mps2, steer_angle_rad}.
Action: (steer, throttle) in [-1, 1]. Reward: progress minus the lateral-error penalty (truth,
scoring only). A lane departure or leaving the road terminates; the scenario's duration
truncates (discount 1). `reset(seed)` takes a seed; lanekeep/envs/dm_control_env.py gives the
same observation, action and reward as a `dm_control.rl.control.Environment` (its Physics and
Task), for dm_control's tooling.
"""

from __future__ import annotations

import dataclasses

import dm_env
import numpy as np
from dm_env import specs

from lanekeep.detectors.registry import front_labels
from lanekeep.envs import agent_view
from lanekeep.loop.episode import Episode, Percept
from lanekeep.scenario.schema import Scenario, load_scenario


def _scalar(key: str) -> specs.BoundedArray:
    limit = agent_view.LIMITS[key]
    return specs.BoundedArray((), np.float64, -limit, limit, key)


def _flag(name: str) -> specs.BoundedArray:
    return specs.BoundedArray((), np.float64, 0.0, 1.0, name)


def observation_spec(models: list[str], render_size: tuple[int, int]) -> dict:
    """The specs of `observation`: images at `render_size` (width, height) and the named
    numbers of lanekeep/envs/agent_view.py."""
    w, h = render_size
    n = len(models)
    lane_keys = agent_view.LANE_KEYS[1:]
    return {
        "front": specs.Array((h, w, 3), np.uint8, "front"),
        "rear": specs.Array((h, w, 3), np.uint8, "rear"),
        "lanes": {name: {"valid": _flag("valid"), **{k: _scalar(k) for k in lane_keys}}
                  for name in agent_view.lane_names(models)},
        "detected": {name: _flag(name) for name in models},
        "reference": {"valid": _flag("valid"), "offset_m": _scalar("offset_m")},
        "probabilities": specs.BoundedArray((n,), np.float64, 0.0, 1.0, "probabilities"),
        "selected": specs.BoundedArray((), np.int64, 0, n - 1, "selected"),
        "vehicle": {k: _scalar(k) for k in agent_view.SIGNAL_KEYS},
    }


def observation(percept: Percept, models: list[str]) -> dict:
    """One percept as nested dicts of float64 (`selected` int64) and the two images."""
    v = agent_view.view(percept, models)
    f64 = np.float64
    return {
        "front": percept.frames["front"].copy(),
        "rear": percept.frames["rear"].copy(),
        "lanes": {name: {k: f64(x) for k, x in lane.items()}
                  for name, lane in v["lanes"].items()},
        "detected": {name: f64(x) for name, x in v["detected"].items()},
        "reference": {k: f64(x) for k, x in v["reference"].items()},
        "probabilities": np.clip(np.asarray(v["probabilities"], dtype=f64), 0.0, 1.0),
        "selected": np.int64(v["selected"]),
        "vehicle": {k: f64(x) for k, x in v["vehicle"].items()},
    }


class LaneKeepEnv(dm_env.Environment):
    """One scenario; `reset(seed)` runs it with that seed (None: the last seed given, at first
    the scenario's own, its nominal drive)."""

    def __init__(self, scenario: Scenario | str, render_size: tuple[int, int] | None = None,
                 duration_s: float | None = None) -> None:
        scenario = load_scenario(scenario) if isinstance(scenario, str) else scenario
        if duration_s is not None:
            scenario = dataclasses.replace(scenario, duration_s=duration_s)
        self.scenario = scenario
        self.render_size = render_size or (scenario.camera.width, scenario.camera.height)
        self.models = front_labels(scenario.estimation.front_detectors)
        self._slot = agent_view.EpisodeSlot(self)
        self._reset_next = True
        self._seed = scenario.seed

    # -- specs -----------------------------------------------------------------------------
    def observation_spec(self):
        return observation_spec(self.models, self.render_size)

    def action_spec(self):
        return specs.BoundedArray((2,), np.float64, -1.0, 1.0, "steer_throttle")

    # -- dynamics --------------------------------------------------------------------------
    def reset(self, seed: int | None = None) -> dm_env.TimeStep:
        """A new episode; `seed` replaces the scenario's seed and is kept for the next resets
        without one. The seed draws the world's details, the image effects and the sensor noise
        and, unless it is the file's own seed (0 for a scenario built in memory), the start's
        offset, heading and speed and the other vehicles' timing within `[start.jitter]`
        (lanekeep/scenario/nuisance.py); the same seed gives the same first observation."""
        if seed is not None:
            self._seed = int(seed)
        self._slot.close()  # before the next rig exists: freeing a renderer disturbs another's
        scenario = dataclasses.replace(self.scenario, seed=self._seed)
        episode = self._slot.replace(Episode(scenario, render_size=self.render_size))
        self._reset_next = False
        # The first observation is the first period's percept, before any action.
        return dm_env.restart(self._observation(episode.observe()))

    def step(self, action) -> dm_env.TimeStep:
        episode = self._slot.episode
        if self._reset_next or episode is None:
            return self.reset()
        action = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        result = episode.act(action=(float(action[0]), float(action[1])))
        # The next period's percept: the agent acts on the frames of the period it acts in.
        observation = self._observation(episode.observe())
        reward, _ = agent_view.reward(episode, result)
        if agent_view.departed(result) or result.off_road or result.collision:
            self._reset_next = True
            return dm_env.termination(reward, observation)
        if episode.index >= episode.total_steps:
            self._reset_next = True
            return dm_env.truncation(reward, observation)
        return dm_env.transition(reward, observation)

    def _observation(self, percept: Percept) -> dict:
        return observation(percept, self.models)

    def close(self) -> None:
        self._slot.close()
