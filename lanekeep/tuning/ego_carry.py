"""How well the car's own motion carries a lane from one frame to the next.

    MUJOCO_GL=egl python -m lanekeep.tuning.ego_carry [SCENARIO ...] [--seeds 3]
        [--front-detectors hough,sliding_window]

A track coasts on the ego-motion alone while its detector has nothing (estimators/kalman.py
`ego_motion_transform`, driven by estimators/odometry.py `DeadReckoning`). This drives each
episode and carries the true lane of every step to the next with the motion the estimator
was handed, against the true lane there, at `--at` m ahead: the error is what a coasting track
drifts by each step before any detection has a say. It is printed for the motion
`DeadReckoning` hands on (the period's mean of the two samples around it), for the sample at
the period's end alone, and for no yaw at all (the scale of the effect).

By default the three traffic tuning scenarios (lanekeep/tuning/scenario_files), which the
bench does not score, from their own seed on. Truth is read for scoring only, as in
`lanekeep run`; tools/ego_carry_check.py runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

DEFAULT_PATTERN = "tune_traffic_*.toml"
MOTIONS = ("handed_on", "end_sample", "no_yaw")


@dataclass(frozen=True)
class CarryStep:
    """One control step: the true centre line in the car's frame where the frames were taken,
    and the wheel-speed and gyro samples taken with them."""

    true_centre: tuple[float, float, float]
    speed_mps: float
    yaw_rate_rps: float


def carry_errors(steps: Sequence[CarryStep], dt_s: float, at_m: float,
                 lever_m: float) -> dict[str, np.ndarray]:
    """Per motion (`MOTIONS`), each step's error at `at_m` of the previous true lane carried
    over the period against this step's true lane, m."""
    from lanekeep.estimators.kalman import ego_motion_transform
    from lanekeep.estimators.odometry import DeadReckoning

    odometry = DeadReckoning(dt_s, lever_m)
    powers = np.array([1.0, at_m, at_m * at_m])
    errors: dict[str, list[float]] = {m: [] for m in MOTIONS}
    previous: np.ndarray | None = None
    for step in steps:
        ego = odometry.update(step.speed_mps, step.yaw_rate_rps)
        now = np.asarray(step.true_centre, dtype=float)
        if previous is not None:
            motions = {"handed_on": (ego.speed_mps, ego.yaw_rate_rps, ego.lateral_speed_mps),
                       "end_sample": (step.speed_mps, step.yaw_rate_rps,
                                      odometry.lateral_speed_mps(step.yaw_rate_rps)),
                       "no_yaw": (ego.speed_mps, 0.0, 0.0)}
            for name, (v, r, lateral) in motions.items():
                a, b = ego_motion_transform(previous, v, r, dt_s, lateral_speed_mps=lateral)
                errors[name].append(float(powers @ (a @ previous + b - now)))
        previous = now
    return {name: np.asarray(values) for name, values in errors.items()}


def drive(scenario_arg: str, seed: int, front: tuple[str, ...] | None) -> tuple[list[CarryStep],
                                                                             float, float]:
    """One episode's steps, its control period and the odometry lever it ran with."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    from lanekeep.loop.episode import Episode
    from lanekeep.loop.overrides import PluginOverrides
    from lanekeep.scenario.schema import load_scenario

    scenario = dataclasses.replace(load_scenario(scenario_arg), seed=seed)
    if front:
        scenario = PluginOverrides(front, None, None, (), None).apply(scenario)
    steps: list[CarryStep] = []

    def on_step(result, _n) -> None:
        centre = np.asarray(result.truth.centre, dtype=float)
        steps.append(CarryStep((float(centre[0]), float(centre[1]), float(centre[2])),
                               float(result.signals.speed_mps),
                               float(result.signals.yaw_rate_rps)))

    with Episode(scenario) as episode:
        lever = episode.driver.odometry.lever_m
        episode.run(None, on_step=on_step)
    return steps, scenario.control_period_s, lever


def rms_cm(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(values)))) * 100.0 if values.size else float("nan")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m lanekeep.tuning.ego_carry",
        description=__doc__.split("\n\n")[0] + " Prints, per episode and over all, the RMS "
        "one-step carry error of the true lane in cm.")
    parser.add_argument("scenarios", nargs="*", metavar="SCENARIO",
                        help=f"names or files (default: the tuning scenarios {DEFAULT_PATTERN})")
    parser.add_argument("--seeds", type=int, default=3,
                        help="seeds per scenario, from its own seed on (default: 3)")
    parser.add_argument("--front-detectors", default="hough,sliding_window",
                        help="the front models driving (default: hough,sliding_window, the "
                        "loop whose tracks coast most); '' for the scenario's own")
    parser.add_argument("--at", type=float, default=4.0,
                        help="look-ahead of the error, m (default: 4, the output's)")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error("--seeds must be >= 1")
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.tuning.scenarios import tuning_dir

    scenarios = args.scenarios or sorted(str(p) for p in tuning_dir().glob(DEFAULT_PATTERN))
    try:
        first_seeds = [load_scenario(s).seed for s in scenarios]
    except (OSError, ValueError) as err:
        print(f"ego_carry: error: {err}", file=sys.stderr)
        return 2
    front = tuple(n for n in args.front_detectors.split(",") if n) or None
    pooled: dict[str, list[np.ndarray]] = {m: [] for m in MOTIONS}
    print("episode".ljust(44) + "".join(m.rjust(12) for m in MOTIONS) + "   (RMS, cm)")
    for scenario_arg, first in zip(scenarios, first_seeds, strict=True):
        for seed in range(first, first + args.seeds):
            steps, dt_s, lever = drive(scenario_arg, seed, front)
            errors = carry_errors(steps, dt_s, args.at, lever)
            label = f"{os.path.basename(scenario_arg).removesuffix('.toml')} seed {seed}"
            print(label.ljust(44) + "".join(f"{rms_cm(errors[m]):12.2f}" for m in MOTIONS))
            for m in MOTIONS:
                pooled[m].append(errors[m])
    print("all".ljust(44) + "".join(f"{rms_cm(np.concatenate(pooled[m])):12.2f}"
                                    for m in MOTIONS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
