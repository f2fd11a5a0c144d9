"""`LaneKeepGymEnv`: a closed-loop scenario as a Gymnasium environment, "lanekeep/LaneKeep-v0".

    import gymnasium, lanekeep
    env = gymnasium.make("lanekeep/LaneKeep-v0", scenario="clear_straight",
                         render_size=(320, 180), render_mode="rgb_array")

Observation (a Dict; lanekeep/envs/agent_view.py has the sign conventions), for front models M
and each camera c in `cameras` (default both; `cameras=()`: state only, no images):
  c                 uint8 (height, width, 3): the camera frame, after the image effects
  c_depth           float32 (height, width): z-depth in metres (with "depth" in `layers`)
  c_segmentation    uint8 (height, width): 1 on lane-marking paint, else 0 (with
                    "segmentation" in `layers`; the simulator's labels, as CARLA's
                    semantic camera gives them: a privileged sensor, opt-in)
  lanes[m]          for m in M and "fused": valid (0/1), offset_m, heading_rad, curvature_1pm of
                    each model's own Kalman track and of the MMAE output, at the output's
                    look-ahead (`[estimation] offset_lookahead_m`, 4 m by default)
  detected[m]       0/1: the model's raw detection on this frame was valid
  reference         valid (0/1), offset_m: the rear reference detector's offset
  probabilities     float32 (len(M),): the MMAE's model probabilities; selected: its choice
  vehicle           speed_mps, yaw_rate_rps, accel_long_mps2, accel_lat_mps2, steer_angle_rad:
                    the car's sensor signals (noisy, as `[sensors]` says), not the truth
Flags are Discrete(2) ints; every other number is float32 within agent_view.LIMITS (clipped:
offsets +-20 m, headings +-pi/2 rad, curvatures +-1 1/m, ...); an invalid lane reads 0 with
valid = 0, never NaN.
Nothing of the simulator's truth is in the observation (unless "segmentation" is asked for);
`info` carries it for scoring (truth_offset_m, progress_m, events, time_s).

Pixels for a CNN: Gymnasium's own wrappers, on the front frame (`render()`), e.g. 84x84 grey,
4 frames stacked (docs/api.md):
    env = gymnasium.make("lanekeep/LaneKeep-v0", render_mode="rgb_array", cameras=())
    env = AddRenderObservation(env, render_only=True)
    env = FrameStackObservation(GrayscaleObservation(ResizeObservation(env, (84, 84))), 4)

Action: Box [-1, 1]^2 float32 = (steer, throttle): steer +1 = full left (35 deg road-wheel
angle), throttle > 0 drives, < 0 brakes.

Reward (truth, scoring only): progress along the road per step / (target speed x period),
capped at 1, minus |true offset from the ego lane centre| / half a lane width, capped at 1.

Termination: a wheel crosses an ego-lane boundary, the car leaves the road, or the physics goes
unstable. Truncation: the scenario's `duration_s` is reached, after `max_episode_steps` steps
(duration / control period), which `env.spec.max_episode_steps` reports.

Timing: the observation is what the car has at the start of a control period
(`Episode.observe`); `step(a)` applies `a` for that period (`Episode.act`) and returns the
observation of the next one, so an agent acts on the same period's frames as the built-in
controller does. `reset()` returns the first period's observation, before any action.

Seeds: `reset(seed=s)` runs the scenario with seed s, so the same seed gives the same first
observation. The seed draws the world's details, the image effects and the sensor noise and,
unless s is the file's own seed (0 for a scenario built in memory), the drive too: the start's
offset, heading and speed and the other vehicles' timing, within the file's `[start.jitter]`
(lanekeep/scenario/nuisance.py); the file's own seed is its nominal drive, as the file says. A
later `reset()` without a seed draws the next seed from the environment's generator (so, in
all likelihood, a drawn drive); the very first `reset()` without a seed keeps the scenario
file's own seed, as `lanekeep run` does.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from lanekeep.detectors.registry import front_labels
from lanekeep.envs import agent_view
from lanekeep.loop.episode import Episode, Percept, StepResult
from lanekeep.scenario.schema import Scenario, load_scenario
from lanekeep.world.build import SimulationError


def _scalar(key: str) -> spaces.Box:
    limit = agent_view.LIMITS[key]
    return spaces.Box(-limit, limit, shape=(), dtype=np.float32)


def _f32(value: float) -> np.ndarray:
    return np.asarray(value, dtype=np.float32)


CAMERAS = ("front", "rear")
LAYERS = ("rgb", "depth", "segmentation")  # what a camera can add to the observation


def _checked_size(render_size) -> tuple[int, int]:
    """(width, height) as two positive ints, or one ValueError that says so."""
    try:
        w, h = (int(v) for v in render_size)
        ok = (w, h) == tuple(render_size) and w > 0 and h > 0
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"render_size must be two positive integers (width, height), "
                         f"got {render_size!r}")
    return w, h


def _checked_names(kind: str, names: Sequence[str], allowed: tuple[str, ...]) -> tuple:
    names = (names,) if isinstance(names, str) else tuple(names)
    unknown = [n for n in names if n not in allowed]
    if unknown or len(set(names)) != len(names):
        raise ValueError(f"{kind} must be distinct names out of {allowed}, got {names!r}")
    return names


def _image_key(camera: str, layer: str) -> str:
    return camera if layer == "rgb" else f"{camera}_{layer}"


class LaneKeepGymEnv(gym.Env):
    """One scenario per environment; see the module docstring for spaces, reward and timing."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}
    _spec = None  # until gymnasium.make sets it (see `spec`)

    def __init__(self, scenario: Scenario | str = "clear_straight",
                 render_size: tuple[int, int] | None = None,
                 render_mode: str | None = None, duration_s: float | None = None,
                 cameras: Sequence[str] = CAMERAS, layers: Sequence[str] = ("rgb",)) -> None:
        scenario = load_scenario(scenario) if isinstance(scenario, str) else scenario
        if duration_s is not None:
            scenario = dataclasses.replace(scenario, duration_s=duration_s)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']}, "
                             f"got {render_mode!r}")
        self.scenario = scenario
        self.render_mode = render_mode
        self.render_size = _checked_size(
            (scenario.camera.width, scenario.camera.height) if render_size is None
            else render_size)
        self.cameras = _checked_names("cameras", cameras, CAMERAS)
        self.layers = _checked_names("layers", layers, LAYERS)
        # The episode truncates itself at the scenario's duration; the spec says when.
        self.max_episode_steps = int(round(scenario.duration_s / scenario.control_period_s))
        self.metadata = {**self.metadata,
                         "render_fps": max(1, round(1.0 / scenario.control_period_s))}
        self.models = front_labels(scenario.estimation.front_detectors)
        self.observation_space = self._observation_space()
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self._slot = agent_view.EpisodeSlot(self)
        self._seeded = False
        self._last_obs: dict | None = None
        self._last_front: np.ndarray | None = None

    @property
    def spec(self):
        return self._spec

    @spec.setter
    def spec(self, spec) -> None:
        """`gymnasium.make` sets the registered spec: it gets the scenario's episode length
        (registration cannot know it: the scenario is a `make` argument)."""
        if spec is not None and spec.max_episode_steps is None:
            spec = dataclasses.replace(spec, max_episode_steps=self.max_episode_steps)
        self._spec = spec

    def _image_spaces(self) -> dict[str, spaces.Box]:
        w, h = self.render_size
        boxes = {"rgb": spaces.Box(0, 255, shape=(h, w, 3), dtype=np.uint8),
                 "depth": spaces.Box(0.0, np.inf, shape=(h, w), dtype=np.float32),
                 "segmentation": spaces.Box(0, 1, shape=(h, w), dtype=np.uint8)}
        return {_image_key(c, layer): boxes[layer] for c in self.cameras for layer in self.layers}

    def _observation_space(self) -> spaces.Dict:
        flag = spaces.Discrete(2)
        lane = spaces.Dict({"valid": flag, **{k: _scalar(k) for k in agent_view.LANE_KEYS[1:]}})
        n = len(self.models)
        return spaces.Dict({
            **self._image_spaces(),
            "lanes": spaces.Dict({name: lane for name in agent_view.lane_names(self.models)}),
            "detected": spaces.Dict({name: flag for name in self.models}),
            "reference": spaces.Dict({"valid": flag, "offset_m": _scalar("offset_m")}),
            "probabilities": spaces.Box(0.0, 1.0, shape=(n,), dtype=np.float32),
            "selected": spaces.Discrete(n),
            "vehicle": spaces.Dict({k: _scalar(k) for k in agent_view.SIGNAL_KEYS}),
        })

    # -- the API ---------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        if seed is not None:
            episode_seed = int(seed)
        elif not self._seeded:
            episode_seed = self.scenario.seed
        else:
            episode_seed = int(self.np_random.integers(2**31))
        self._seeded = True
        scenario = dataclasses.replace(self.scenario, seed=episode_seed)
        self._slot.close()  # first: a renderer freed after another's creation can spoil it
        episode = self._slot.replace(Episode(scenario, render_size=self.render_size))
        percept = episode.observe()
        info = {"time_s": percept.time_s, "truth_offset_m": None, "progress_m": 0.0,
                "events": list(percept.events), "lookahead_m": percept.estimate.offset_x_m,
                "status": "running", "seed": episode_seed}
        return self._observe(percept), info

    def step(self, action):
        episode = self._slot.episode
        if episode is None:
            raise RuntimeError("call reset() before step()")
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(2), -1.0, 1.0)
        try:
            result = episode.act(action=(float(a[0]), float(a[1])))
            percept = episode.observe()  # the next period's frames: what the agent acts on
        except SimulationError as err:  # the physics blew up: the episode ends here
            return self._last_obs, 0.0, True, False, {"status": "unstable", "events": [str(err)]}
        reward, progress = agent_view.reward(episode, result)
        terminated = agent_view.departed(result) or bool(result.off_road or result.collision)
        truncated = not terminated and episode.index >= episode.total_steps
        return self._observe(percept), float(reward), terminated, truncated, \
            self._info(result, progress)

    def render(self) -> np.ndarray | None:
        """The latest front frame (what the car saw), in "rgb_array" mode."""
        if self.render_mode != "rgb_array" or self._last_front is None:
            return None
        return self._last_front.copy()

    def close(self) -> None:
        self._slot.close()
        super().close()

    # -- helpers ---------------------------------------------------------------------------
    def _observe(self, percept: Percept) -> dict:
        v = agent_view.view(percept, self.models)
        obs = {
            **self._images(percept),
            "lanes": {name: {"valid": int(lane["valid"]),
                             **{k: _f32(lane[k]) for k in agent_view.LANE_KEYS[1:]}}
                      for name, lane in v["lanes"].items()},
            "detected": {name: int(d) for name, d in v["detected"].items()},
            "reference": {"valid": int(v["reference"]["valid"]),
                          "offset_m": _f32(v["reference"]["offset_m"])},
            "probabilities": np.clip(np.asarray(v["probabilities"], dtype=np.float32), 0, 1),
            "selected": int(v["selected"]),
            "vehicle": {k: _f32(x) for k, x in v["vehicle"].items()},
        }
        self._last_obs, self._last_front = obs, percept.frames["front"].copy()
        return obs

    def _images(self, percept: Percept) -> dict[str, np.ndarray]:
        """The cameras' layers asked for: the frames the car saw, and depth and segmentation
        renders of the same state (before the agent acts, so they match the frames)."""
        episode, images = self._slot.episode, {}
        for c in self.cameras:
            for layer in self.layers:
                if layer == "rgb":
                    image = percept.frames[c].copy()
                elif layer == "depth":
                    rig = episode.simulator.rig
                    _, image = rig.render_rgb_depth(episode.world.data, c, step_px=1)
                else:
                    ids = episode.simulator.rig.render_segmentation(episode.world.data, c)
                    image = episode.world.marking_mask(ids).astype(np.uint8)
                images[_image_key(c, layer)] = image
        return images

    @staticmethod
    def _info(result: StepResult, progress: float) -> dict:
        """Truth, for scoring and logging only (never an input to the agent's policy)."""
        return {"time_s": result.time_s, "truth_offset_m": result.truth_offset_m,
                "progress_m": progress, "events": list(result.events),
                "lookahead_m": result.output_x_m,
                "status": result.off_road or result.collision or "running"}

