"""Measure the body roll compensation's constants (estimators/roll.py) on the tuning scenarios.

    MUJOCO_GL=egl python -m lanekeep.tuning.roll_coupling [SCENARIO ...]

Runs each scenario (default: the curves of lanekeep/tuning/scenario_files/, which
`lanekeep bench` does not score; a shipped scenario is refused unless --allow-scored) with the
compensation off and fits, by least squares,

* the roll gradient: the body's true roll against the lateral accelerometer's signal, low-passed
  and clipped as the loop does (estimators/roll.py `RollFilter`);
* per detector, the offset error (detection minus the true offset at its look-ahead) against
  the true roll: its lever, in metres of offset per radian.

It prints them and the `[estimation]` values: the front lever is the median of the front
models' levers, the rear one the reference's. The truth (roll, offsets) is read here only,
to calibrate; the loop then uses the accelerometer alone.

tools/measure_roll_coupling.py runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lanekeep.tuning.scenarios import (
    TuningInputError,
    add_scenario_arguments,
    select_scenarios,
    tuning_dir,
)

CURVES = ("tune_right_curve_r100", "tune_left_curve_r200_rain", "tune_gentle_s_curve_r700_r500",
          "tune_sharp_right_r45")
CORE_M = 0.5  # an offset error this large is a wild fit, not roll


def default_scenarios(folder: Path | None = None) -> list[str]:
    """The tuning scenarios with curves enough to roll the body: the files of CURVES in
    `folder` (by default the tuning scenarios' `tuning_dir()`)."""
    folder = tuning_dir() if folder is None else Path(folder)
    return [str(folder / f"{name}.toml") for name in CURVES]


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


@dataclass(frozen=True)
class Lever:
    """One source's lever and what roll explains of its offset error."""

    lever_m_per_rad: float
    rms_m: float  # the offset error's RMS over the core steps
    rest_rms_m: float  # the same less the lever times the roll
    steps: int  # core steps (error under CORE_M)


def lever(rows: list[tuple[float, float, float]]) -> Lever:
    """A source's lever from its `samples` rows."""
    err, _accel, roll = np.array(rows).T
    core = np.abs(err) < CORE_M
    value = slope(roll[core], err[core])
    rest = err[core] - value * roll[core]
    return Lever(value, float(np.sqrt(np.mean(err[core] ** 2))),
                 float(np.sqrt(np.mean(rest ** 2))), int(core.sum()))


def roll_gradient_deg(reference_rows: list[tuple[float, float, float]]) -> float:
    """Degrees of roll per m/s^2 of filtered lateral acceleration, over the reference's rows
    (one a step the reference was valid)."""
    _err, accel, roll = np.array(reference_rows).T
    return float(np.degrees(slope(accel, roll)))


def front_lever(levers: dict[str, Lever]) -> float:
    """The front models' lever: the median of theirs (every source but the reference)."""
    return float(np.median([v.lever_m_per_rad for k, v in levers.items() if k != "reference"]))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scenario_arguments(parser, default="the tuning curves")
    args = parser.parse_args(argv)
    try:
        paths = select_scenarios(args.scenarios or default_scenarios(),
                                 allow_scored=args.allow_scored)
    except TuningInputError as err:
        parser.exit(2, f"error: {err}\n")
    pooled: dict[str, list] = {}
    for path in paths:
        for name, rows in samples(path).items():
            pooled.setdefault(name, []).extend(rows)
        print(f"  {Path(path).stem}: done", flush=True)
    levers = {name: lever(rows) for name, rows in pooled.items()}
    for name, fit in levers.items():
        print(f"{name:>16}: lever {fit.lever_m_per_rad:.2f} m/rad "
              f"({100 * np.radians(fit.lever_m_per_rad):.2f} cm/deg), offset RMS "
              f"{100 * fit.rms_m:.2f} cm -> {100 * fit.rest_rms_m:.2f} without roll's part; "
              f"{fit.steps} steps")
    gradient = roll_gradient_deg(pooled["reference"])
    front = front_lever(levers)
    print(f"roll gradient {gradient:.3f} deg per m/s^2\n\n[estimation]")
    print(f"roll_gradient_deg_per_mps2 = {gradient:.2f}\nroll_lever_front_m = {front:.1f}\n"
          f"roll_lever_rear_m = {levers['reference'].lever_m_per_rad:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
