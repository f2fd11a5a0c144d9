"""The Gymnasium face (lanekeep/envs/gym_env.py): registered on `import lanekeep`, passes
Gymnasium's env checker, seeded resets repeat, the spaces name the estimates and hold no truth,
and the episode ends by truncation at the scenario's duration or by a lane departure."""

import subprocess
import sys
import warnings

# Imported, not importorskip'd: gymnasium is in the `test` extra, and a missing one must fail
# README's test command loudly rather than skip these tests.
import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.wrappers import (
    AddRenderObservation,
    FrameStackObservation,
    GrayscaleObservation,
    ResizeObservation,
)

import lanekeep  # noqa: F401  (registers the id)
from lanekeep.envs.gym_env import LaneKeepGymEnv

SIZE = (96, 54)


def _make(duration_s=1.0, **kwargs):
    return gymnasium.make("lanekeep/LaneKeep-v0", render_size=SIZE, duration_s=duration_s,
                          **kwargs)


def test_import_lanekeep_registers_the_id_without_importing_gymnasium():
    code = ("import sys, lanekeep; assert 'gymnasium' not in sys.modules; "
            "import gymnasium; print('lanekeep/LaneKeep-v0' in gymnasium.registry)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "True"


def test_check_env_passes_without_warnings():
    env = _make(scenario="clear_straight", render_mode="rgb_array", disable_env_checker=True)
    assert isinstance(env.unwrapped, LaneKeepGymEnv)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # any checker warning fails the test
            check_env(env.unwrapped, skip_render_check=False)
    finally:
        env.close()


def _equal(a, b):
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    return np.array_equal(np.asarray(a), np.asarray(b))


def test_reset_with_the_same_seed_gives_the_same_first_observation():
    env = _make(scenario="clear_straight")
    try:
        first, info = env.reset(seed=11)
        env.step(env.action_space.sample())
        again, _ = env.reset(seed=11)
        other, _ = env.reset(seed=12)
    finally:
        env.close()
    assert info["seed"] == 11
    assert _equal(first, again)
    assert not _equal(first, other)


def test_spaces_name_the_estimates_and_no_truth():
    env = _make(scenario="clear_straight", render_mode="rgb_array")
    try:
        obs, _ = env.reset()
        space = env.observation_space
        assert obs["front"].shape == (SIZE[1], SIZE[0], 3) and obs["front"].dtype == np.uint8
        assert set(space["lanes"].spaces) == {"hough", "sliding_window", "lanenet", "fused"}
        assert set(space["vehicle"].spaces) == {"speed_mps", "yaw_rate_rps", "accel_long_mps2",
                                                "accel_lat_mps2", "steer_angle_rad"}
        names = str(space).lower()
        assert "truth" not in names and "pose" not in names
        assert env.action_space.shape == (2,)
        assert np.all(env.action_space.low == -1) and np.all(env.action_space.high == 1)
        assert np.array_equal(env.render(), obs["front"])
    finally:
        env.close()


def test_keeping_the_lane_pays_and_the_duration_truncates():
    env = _make(scenario="clear_straight")
    try:
        env.reset(seed=0)
        rewards, steps = [], 0
        while True:
            _, reward, terminated, truncated, info = env.step(np.array([0.0, 0.3], np.float32))
            rewards.append(reward)
            steps += 1
            if terminated or truncated:
                break
    finally:
        env.close()
    assert truncated and not terminated
    assert steps == 10  # 10 periods of 0.1 s; reset() only observes the first
    assert env.spec.max_episode_steps == steps  # from the scenario, for RL libraries
    assert min(rewards) > 0.9  # centred at about the target speed on a straight road
    assert "truth_offset_m" in info


def test_steering_hard_off_the_lane_terminates_with_a_low_reward():
    env = _make(scenario="clear_straight", duration_s=5.0)
    try:
        env.reset(seed=0)
        for _ in range(50):
            _, reward, terminated, truncated, info = env.step(np.array([1.0, 0.3], np.float32))
            if terminated or truncated:
                break
    finally:
        env.close()
    assert terminated and not truncated
    assert any(e.startswith("lane departure") for e in info["events"])
    assert reward < 0.9


@pytest.mark.parametrize("kwargs", [
    {"render_size": (-96, 54)}, {"render_size": (96, 0)}, {"render_size": (96.5, 54)},
    {"render_size": "96x54"}, {"cameras": ("front", "side")}, {"layers": ("rgb", "rgb")},
])
def test_bad_options_raise_one_clear_value_error(kwargs):
    with pytest.raises(ValueError) as err:
        LaneKeepGymEnv("clear_straight", **kwargs)
    message = str(err.value)
    assert next(iter(kwargs)) in message and "\n" not in message


def test_state_only_and_depth_and_segmentation_observations():
    env = _make(scenario="clear_straight", cameras=())
    try:
        obs, _ = env.reset(seed=0)
        assert not {"front", "rear"} & set(obs) and obs in env.observation_space
    finally:
        env.close()
    env = _make(scenario="clear_straight", cameras=("front",),
                layers=("rgb", "depth", "segmentation"))
    try:
        obs, _ = env.reset(seed=0)
        obs, *_ = env.step(np.array([0.0, 0.3], np.float32))
    finally:
        env.close()
    assert {"front", "front_depth", "front_segmentation"} <= set(obs) and "rear" not in obs
    assert obs in env.observation_space
    depth, paint = obs["front_depth"], obs["front_segmentation"].astype(bool)
    assert depth.shape == paint.shape == (SIZE[1], SIZE[0])
    # the road just ahead of the bumper is nearer than the road at the horizon
    assert 0 < np.median(depth[-3:]) < np.median(depth[SIZE[1] // 2 + 2])
    assert 0 < paint.mean() < 0.2  # some lane paint, not the whole picture


def test_gymnasium_wrappers_give_stacked_grey_downscaled_frames():
    env = _make(scenario="clear_straight", render_mode="rgb_array", cameras=())
    env = AddRenderObservation(env, render_only=True)
    env = FrameStackObservation(GrayscaleObservation(ResizeObservation(env, (42, 42))), 4)
    try:
        obs, _ = env.reset(seed=0)
        obs, *_ = env.step(np.array([0.0, 0.3], np.float32))
    finally:
        env.close()
    assert obs.shape == (4, 42, 42) and obs.dtype == np.uint8
    assert obs[-1].std() > 0  # a picture, not a blank
