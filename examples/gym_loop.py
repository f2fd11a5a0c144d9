"""A Gymnasium loop: `gymnasium.make("lanekeep/LaneKeep-v0")` driven by a hand-written policy
that reads only the observation (the MMAE output's lane and the wheel-speed signal).

    python examples/gym_loop.py clear_curve
    python examples/gym_loop.py clear_straight --seconds 3 --size 320x180   # quick
"""

import argparse
import sys

# lanekeep before numpy and Gymnasium: it pins numpy's kernels as they load, so that this
# loop computes what the CLI and another machine compute (docs/reproducibility.md); it also
# registers "lanekeep/LaneKeep-v0".
import lanekeep  # noqa: F401

# isort: split
import numpy as np

try:
    import gymnasium
except ModuleNotFoundError:  # one line, not a traceback
    sys.exit("gym_loop.py: error: needs Gymnasium: pip install -e '.[gym]'")


def policy(obs: dict, target_speed_mps: float) -> np.ndarray:
    """Steer against the lane offset and along the lane's heading; hold the speed."""
    lane = obs["lanes"]["fused"]
    steer = 0.0
    if lane["valid"]:  # offset + = car left of the centre; heading + = lane runs left
        steer = -0.3 * float(lane["offset_m"]) + 1.0 * float(lane["heading_rad"])
    throttle = 0.3 * (target_speed_mps - float(obs["vehicle"]["speed_mps"]))
    return np.clip(np.array([steer, throttle], dtype=np.float32), -1.0, 1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default="clear_straight")
    parser.add_argument("--seconds", type=float, default=None)
    parser.add_argument("--size", default="640x360", help="camera size WxH")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    size = tuple(int(v) for v in args.size.split("x"))
    env = gymnasium.make("lanekeep/LaneKeep-v0", scenario=args.scenario, render_size=size,
                         duration_s=args.seconds)
    target = env.unwrapped.scenario.target_speed_mps
    obs, info = env.reset(seed=args.seed)
    total, steps = 0.0, 0
    terminated = truncated = False
    while not (terminated or truncated):
        obs, reward, terminated, truncated, info = env.step(policy(obs, target))
        total += reward
        steps += 1
    env.close()
    end = "a lane departure or leaving the road" if terminated else "the scenario's duration"
    print(f"{args.scenario}: {steps} steps, return {total:.1f} (at most {steps}), ended by "
          f"{end}; last true offset {100 * info['truth_offset_m']:.1f} cm")


if __name__ == "__main__":
    main()
