"""`LaneKeepEnv`: a closed-loop scenario as a `dm_env.Environment` for learning agents.

Observations: both camera images and the estimators' view (each front model's offset, the MMAE
output and the rear reference, with validity flags, and the MMAE probabilities). Action: steer
and throttle in [-1, 1]. Reward: 1 - |true lateral offset| / half a lane, so keeping the lane
centre pays 1 per step. The episode terminates on a lane departure and is truncated (discount
1) at the scenario's duration.
"""

from __future__ import annotations

import dataclasses

import dm_env
import numpy as np
from dm_env import specs

from lanekeep.episode import Episode
from lanekeep.scenario import Scenario, load_scenario


class LaneKeepEnv(dm_env.Environment):
    """One scenario, reset to its start (same seed each episode unless `seed` advances)."""

    def __init__(self, scenario: Scenario | str, render_size: tuple[int, int] | None = None,
                 duration_s: float | None = None) -> None:
        scenario = load_scenario(scenario) if isinstance(scenario, str) else scenario
        if duration_s is not None:
            scenario = dataclasses.replace(scenario, duration_s=duration_s)
        self.scenario = scenario
        self.render_size = render_size or (scenario.camera.width, scenario.camera.height)
        self._episode: Episode | None = None
        self._reset_next = True
        n_models = len(scenario.estimation.front_detectors)
        self._n_offsets = n_models + 2  # models, MMAE output, reference
        self._n_models = n_models

    # -- specs -----------------------------------------------------------------------------
    def observation_spec(self):
        w, h = self.render_size
        return {
            "front": specs.Array((h, w, 3), np.uint8, "front"),
            "rear": specs.Array((h, w, 3), np.uint8, "rear"),
            "offsets_m": specs.Array((self._n_offsets,), np.float64, "offsets_m"),
            "valid": specs.BoundedArray((self._n_offsets,), np.float64, 0.0, 1.0, "valid"),
            "probabilities": specs.BoundedArray((self._n_models,), np.float64, 0.0, 1.0,
                                                "probabilities"),
            "speed_mps": specs.Array((), np.float64, "speed_mps"),
        }

    def action_spec(self):
        return specs.BoundedArray((2,), np.float64, -1.0, 1.0, "steer_throttle")

    # -- dynamics --------------------------------------------------------------------------
    def reset(self) -> dm_env.TimeStep:
        if self._episode is not None:
            self._episode.close()
        self._episode = Episode(self.scenario, render_size=self.render_size)
        self._reset_next = False
        # The first observation comes from one control step with the car's own controllers
        # idle (zero steer, hold throttle), so that images and estimates exist.
        result = self._episode.step(action=(0.0, 0.0))
        return dm_env.restart(self._observation(result))

    def step(self, action) -> dm_env.TimeStep:
        if self._reset_next or self._episode is None:
            return self.reset()
        action = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        result = self._episode.step(action=(float(action[0]), float(action[1])))
        observation = self._observation(result)
        half_lane = self._episode.world.road.lane_width_m / 2.0
        reward = float(1.0 - min(abs(result.truth_offset_m) / half_lane, 1.0))
        departed = any("lane departure" in e for e in result.events)
        if departed:
            self._reset_next = True
            return dm_env.termination(reward, observation)
        if self._episode.index >= self._episode.total_steps:
            self._reset_next = True
            return dm_env.truncation(reward, observation)
        return dm_env.transition(reward, observation)

    def _observation(self, result) -> dict:
        names = list(self._episode.front)
        offsets, valid = [], []
        for name in names:
            e = result.estimates[name]
            offsets.append(e.offset_m if e.valid else 0.0)
            valid.append(1.0 if e.valid else 0.0)
        for value in (result.output_offset_m, result.reference_m):
            offsets.append(0.0 if value is None else float(value))
            valid.append(0.0 if value is None else 1.0)
        return {
            "front": result.frames["front"].copy(),
            "rear": result.frames["rear"].copy(),
            "offsets_m": np.asarray(offsets, dtype=np.float64),
            "valid": np.asarray(valid, dtype=np.float64),
            "probabilities": np.asarray(result.probabilities, dtype=np.float64),
            "speed_mps": np.float64(result.speed_mps),
        }

    def close(self) -> None:
        if self._episode is not None:
            self._episode.close()
            self._episode = None
