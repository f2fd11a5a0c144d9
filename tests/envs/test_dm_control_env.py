"""The dm_control face (lanekeep/envs/dm_control_env.py): dm_env's conformance checks on a real
`dm_control.rl.control.Environment`, the Physics' named accessors against the car's own, a
reset that replays the drive, and a step that is `Episode.step`'s period bit for bit."""


import numpy as np
from absl.testing import absltest
from dm_control.rl import control
from dm_env import test_utils
from helpers import small_scenario

from lanekeep.envs.dm_control_env import load
from lanekeep.loop.episode import Episode
from lanekeep.scenario.schema import load_scenario

SIZE = (96, 54)
ACTIONS = [(0.1, 0.3), (-0.2, 0.5), (0.0, -0.4), (0.3, 0.0), (0.0, 0.2)]


class DmControlConformanceTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    """dm_env's own conformance checks, on a short, low-resolution episode."""

    def make_object_under_test(self):
        return load("clear_straight", render_size=SIZE, duration_s=1.0)

    def make_action_sequence(self):
        for _ in range(25):  # past the end of the 10-step episode twice
            yield self.make_action()


def test_it_is_a_dm_control_environment_with_named_car_state():
    env = load("clear_curve", render_size=SIZE, duration_s=1.0)
    env.reset()
    physics, car = env.physics, env.task.episode.world.car
    assert isinstance(env, control.Environment)
    assert physics.data.ptr is env.task.episode.world.data  # one state, not a copy
    assert physics.car_speed_mps() == car.speed_mps() > 0.0
    x, y, yaw = car.pose()
    assert tuple(physics.car_position()[:2]) == (x, y) and physics.car_yaw_rad() == yaw
    assert env.control_timestep() == load_scenario("clear_curve").control_period_s


def _trajectory(env, actions):
    first = env.reset()
    poses = []
    for action in actions:
        step = env.step(action)
        poses.append(env.task.episode.world.car.pose())
    return first, step, poses


def test_a_reset_replays_the_drive():
    env = load("clear_curve", render_size=SIZE, duration_s=2.0)
    first_a, last_a, poses_a = _trajectory(env, ACTIONS)
    first_b, last_b, poses_b = _trajectory(env, ACTIONS)
    assert np.array_equal(first_a.observation["front"], first_b.observation["front"])
    assert poses_a == poses_b and last_a.reward == last_b.reward


def test_a_step_is_the_episodes_period_with_the_same_action():
    """The dm_control step (before_step, physics, after_step) and `Episode.step(action)` move
    the car to the same poses and pay the same truth-based scores."""
    scenario = small_scenario("clear_curve", 2.0)
    env = load(scenario, render_size=SIZE)
    env.reset()
    env_poses, env_offsets = [], []
    for action in ACTIONS:
        env.step(action)
        result = env.task.last_result
        env_poses.append(result.pose)
        env_offsets.append(result.output_offset_m)
    with Episode(scenario, render_size=SIZE) as episode:
        results = [episode.step(action) for action in ACTIONS]
    assert env_poses == [r.pose for r in results]
    assert env_offsets == [r.output_offset_m for r in results]
