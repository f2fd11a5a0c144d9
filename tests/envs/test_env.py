"""The dm_env face (lanekeep/envs/dm_env_face.py): dm_env's conformance checks, seeded resets, named
observation entries, and renderers closed at garbage collection without EGL tracebacks."""

import subprocess
import sys
import textwrap

import numpy as np
from absl.testing import absltest
from dm_env import test_utils

from lanekeep.envs.dm_env_face import LaneKeepEnv

SIZE = (96, 54)


class LaneKeepEnvConformanceTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    """dm_env's own conformance checks, on a short, low-resolution episode."""

    def make_object_under_test(self):
        return LaneKeepEnv("clear_straight", render_size=SIZE, duration_s=1.0)

    def make_action_sequence(self):
        for _ in range(25):  # past the end of the 10-step episode twice
            yield self.make_action()


def _flatten(obs, prefix=""):
    if isinstance(obs, dict):
        out = {}
        for key, value in obs.items():
            out.update(_flatten(value, f"{prefix}/{key}"))
        return out
    return {prefix: np.asarray(obs)}


def test_same_seed_gives_the_same_first_observation_and_another_seed_does_not():
    env = LaneKeepEnv("clear_straight", render_size=SIZE, duration_s=1.0)
    try:
        a = _flatten(env.reset(seed=7).observation)
        env.step([0.3, 0.5])
        b = _flatten(env.reset(seed=7).observation)
        c = _flatten(env.reset(seed=8).observation)
    finally:
        env.close()
    assert a.keys() == b.keys()
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert not all(np.array_equal(a[k], c[k]) for k in a)  # the sensors' noise follows it


def test_observation_names_every_estimate():
    env = LaneKeepEnv("clear_straight", render_size=SIZE, duration_s=1.0)
    try:
        obs = env.reset().observation
        for _ in range(3):
            obs = env.step([0.0, 0.3]).observation
    finally:
        env.close()
    assert set(obs["lanes"]) == {"hough", "sliding_window", "lanenet", "fused"}
    assert set(obs["lanes"]["fused"]) == {"valid", "offset_m", "heading_rad", "curvature_1pm"}
    assert set(obs["vehicle"]) >= {"speed_mps", "yaw_rate_rps"}
    assert 10.0 < float(obs["vehicle"]["speed_mps"]) < 20.0  # the scenario starts at 15 m/s
    assert obs["lanes"]["fused"]["valid"] == 1.0  # a clear straight road is found
    assert abs(float(obs["lanes"]["fused"]["offset_m"])) < 0.5  # started on the centre


def test_an_environment_dropped_without_close_exits_quietly():
    script = textwrap.dedent(f"""
        from lanekeep.envs.dm_env_face import LaneKeepEnv
        kept = [LaneKeepEnv("clear_straight", render_size={SIZE}, duration_s=1.0)
                for _ in range(2)]
        for env in kept:
            env.reset()
        kept[0].reset(seed=3)  # a replaced episode, too
        dropped = LaneKeepEnv("clear_straight", render_size={SIZE}, duration_s=1.0)
        dropped.reset()
        del dropped  # collected here; `kept` lives until the interpreter exits
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
