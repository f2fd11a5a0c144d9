"""Measure the body roll compensation's constants (estimators/roll.py) on the tuning scenarios.

    MUJOCO_GL=egl .venv/bin/python tools/measure_roll_coupling.py [SCENARIO ...]

Runs each scenario (default: the curves of tools/tuning/, which `lanekeep bench` does not
score; a shipped scenario is refused unless --allow-scored) with the compensation off and fits,
by least squares,

* the roll gradient: the body's true roll against the lateral accelerometer's signal, low-passed
  and clipped as the loop does (estimators/roll.py `RollFilter`);
* per detector, the offset error (detection minus the true offset at its look-ahead) against
  the true roll: its lever, in metres of offset per radian.

It prints them and the `[estimation]` values: the front lever is the median of the front
models' levers, the rear one the reference's. The truth (roll, offsets) is read here only,
to calibrate; the loop then uses the accelerometer alone.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
from pathlib import Path

import numpy as np

TOOLS = Path(__file__).resolve().parent
DEFAULT = ("tune_right_curve_r100", "tune_left_curve_r200_rain", "tune_gentle_s_curve_r700_r500",
           "tune_sharp_right_r45")


def _noise_tool():
    spec = importlib.util.spec_from_file_location("measure_detector_noise",
                                                  TOOLS / "measure_detector_noise.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def samples(path: str) -> dict[str, list[tuple[float, float, float]]]:
    """Per source: (offset error m, filtered lateral acceleration m/s^2, true roll rad) per
    step."""
    from lanekeep.estimators.roll import RollCompensation, RollFilter
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.scoring.truth import lane_offsets

    scenario = load_scenario(path)
    est = dataclasses.replace(scenario.estimation, roll_gradient_deg_per_mps2=0.0)
    scenario = dataclasses.replace(scenario, estimation=est)
    out: dict[str, list[tuple[float, float, float]]] = {}
    accel = RollFilter(RollCompensation(), scenario.control_period_s)
    with Episode(scenario) as episode:
        road, lane = episode.world.road, scenario.road.ego_lane
        for _ in range(episode.total_steps):
            step = episode.step()
            rot = episode.world.car.rotation()
            roll = float(np.arctan2(rot[2, 1], rot[2, 2]))
            accel.update(step.signals.accel_lat_mps2)
            for name, e in step.estimates.items():
                if e.valid:
                    truth = float(lane_offsets(road, *step.sensed_pose, lane, [e.x_m])[0])
                    out.setdefault(name, []).append(
                        (e.offset_m - truth, accel.accel_lat_mps2, roll))
    return out


def slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of y on x, with an intercept."""
    return float(np.linalg.lstsq(np.c_[x, np.ones_like(x)], y, rcond=None)[0][0])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*", help="names or files (default: tuning curves)")
    parser.add_argument("--allow-scored", action="store_true")
    args = parser.parse_args(argv)
    given = args.scenarios or [str(TOOLS / "tuning" / f"{n}.toml") for n in DEFAULT]
    guard = ["--allow-scored"] if args.allow_scored else []
    paths = _noise_tool().parse_args([*given, *guard]).scenarios
    pooled: dict[str, list] = {}
    for path in paths:
        for name, rows in samples(path).items():
            pooled.setdefault(name, []).extend(rows)
        print(f"  {Path(path).stem}: done", flush=True)
    levers = {}
    for name, rows in pooled.items():
        err, accel, roll = np.array(rows).T
        core = np.abs(err) < 0.5  # a wild fit is not roll
        levers[name] = slope(roll[core], err[core])
        rest = err[core] - levers[name] * roll[core]
        print(f"{name:>16}: lever {levers[name]:.2f} m/rad ({100 * np.radians(levers[name]):.2f} "
              f"cm/deg), offset RMS {100 * np.sqrt(np.mean(err[core] ** 2)):.2f} cm -> "
              f"{100 * np.sqrt(np.mean(rest ** 2)):.2f} without roll's part; {core.sum()} steps")
    err, accel, roll = np.array(pooled["reference"]).T
    gradient = np.degrees(slope(accel, roll))
    front = float(np.median([v for k, v in levers.items() if k != "reference"]))
    print(f"roll gradient {gradient:.3f} deg per m/s^2\n\n[estimation]")
    print(f"roll_gradient_deg_per_mps2 = {gradient:.2f}\nroll_lever_front_m = {front:.1f}\n"
          f"roll_lever_rear_m = {levers['reference']:.1f}")


if __name__ == "__main__":
    main()
