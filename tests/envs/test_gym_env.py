"""The Gymnasium face (lanekeep/envs/gym_env.py): registered on `import lanekeep`, passes
Gymnasium's env checker, seeded resets repeat, the spaces name the estimates and hold no truth,
and the episode ends by truncation at the scenario's duration or by a lane departure."""

import subprocess
import sys
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")
from gymnasium.utils.env_checker import check_env  # noqa: E402

import lanekeep  # noqa: E402,F401  (registers the id)
from lanekeep.envs.gym_env import LaneKeepGymEnv  # noqa: E402

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
