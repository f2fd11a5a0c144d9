"""A closed-loop scenario as a `dm_control.rl.control.Environment`: the world's `Physics`
(lanekeep/world/physics.py) and the lane-keeping `Task`, so that dm_control's tooling
(wrappers, the viewer's policy runner, `suite`-style loaders) works on lanekeep.

    env = lanekeep.envs.dm_control_env.load("clear_curve", render_size=(320, 180))
    timestep = env.reset()
    while not timestep.last():
        timestep = env.step([0.0, 0.2])   # (steer, throttle) in [-1, 1]

Observation, action and reward are the dm_env face's (lanekeep/envs/dm_env_face.py): the two
camera frames and the numbers the car's own loop holds (lanekeep/envs/agent_view.py); the
reward and the termination are the simulator's truth and never reach the observation.

The Task drives one `Episode` (lanekeep/loop/episode.py): `initialize_episode` restarts it on
the same physics; `before_step` applies the command to the car; dm_control steps the physics
(`legacy_step=False`: MuJoCo's own mj_step, as `World.step`); `after_step` moves the other
vehicles and scores the period; `get_observation` senses the next period. So a step here is
the same period as `Episode.step` with the same action. Every reset replays the scenario's
seed: for another drive, load with another `seed`.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from dm_control.rl import control
from dm_env import specs

from lanekeep.core.steps import Command
from lanekeep.envs import agent_view, dm_env_face
from lanekeep.loop.episode import Episode, Percept, StepResult
from lanekeep.scenario.schema import Scenario, load_scenario
from lanekeep.world.physics import LaneKeepPhysics


class LaneKeepTask(control.Task):
    """Keep the ego lane at the target speed, paid by progress less lateral error (truth)."""

    def __init__(self, episode: Episode) -> None:
        self.episode = episode
        self.models = list(episode.driver.front)
        self.render_size = (episode.simulator.rig.settings.width,
                            episode.simulator.rig.settings.height)
        self._command: Command | None = None
        self.last_result: StepResult | None = None  # the last period's scored record (truth)

    def initialize_episode(self, physics: LaneKeepPhysics) -> None:
        self.episode.restart()
        self._command = self.last_result = None

    def before_step(self, action, physics: LaneKeepPhysics) -> None:
        steer, throttle = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        self._command = Command(float(steer), float(throttle))
        self.episode.world.car.apply(self._command.steer, self._command.throttle)

    def after_step(self, physics: LaneKeepPhysics) -> None:
        episode = self.episode
        episode.world.move_scene()
        percept = episode.observe()  # the percept the action was taken on
        episode.forget_percept()
        self.last_result = episode.conclude(percept, self._command)

    def get_observation(self, physics: LaneKeepPhysics) -> dict:
        percept: Percept = self.episode.observe()  # the next period's frames
        return dm_env_face.observation(percept, self.models)

    def get_reward(self, physics: LaneKeepPhysics) -> float:
        if self.last_result is None:
            return 0.0
        return float(agent_view.reward(self.episode, self.last_result)[0])

    def get_termination(self, physics: LaneKeepPhysics) -> float | None:
        """0 (a terminal state) once a wheel crossed a lane boundary or the car left the road;
        the scenario's duration is the Environment's time limit."""
        result = self.last_result
        if result is not None and (agent_view.departed(result) or result.off_road
                                   or result.collision):
            return 0.0
        return None

    def action_spec(self, physics: LaneKeepPhysics) -> specs.BoundedArray:
        return specs.BoundedArray((2,), np.float64, -1.0, 1.0, "steer_throttle")

    def observation_spec(self, physics: LaneKeepPhysics) -> dict:
        return dm_env_face.observation_spec(self.models, self.render_size)


def load(scenario: Scenario | str, render_size: tuple[int, int] | None = None,
         seed: int | None = None, duration_s: float | None = None) -> control.Environment:
    """The scenario (a shipped name or a Scenario) as a dm_control Environment; `seed`
    replaces the scenario's (its drive: start and traffic timing within [start.jitter], image
    and sensor noise), `duration_s` its duration (the Environment's time limit)."""
    scenario = load_scenario(scenario) if isinstance(scenario, str) else scenario
    changes = {k: v for k, v in (("seed", seed), ("duration_s", duration_s)) if v is not None}
    scenario = dataclasses.replace(scenario, **changes)
    episode = Episode(scenario, render_size=render_size)
    physics = LaneKeepPhysics.of(episode.world)
    return control.Environment(physics, LaneKeepTask(episode), time_limit=scenario.duration_s,
                               n_sub_steps=physics.sub_steps(scenario.control_period_s),
                               legacy_step=False)
