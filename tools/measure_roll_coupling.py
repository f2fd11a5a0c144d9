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

The code is lanekeep/tuning/roll_coupling.py.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from lanekeep.tuning.roll_coupling import (
    default_scenarios,
    front_lever,
    lever,
    roll_gradient_deg,
    samples,
)
from lanekeep.tuning.scenarios import TuningInputError, select_scenarios

TUNING_DIR = Path(__file__).resolve().parent / "tuning"  # the scenarios the bench does not score


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*", help="names or files (default: tuning curves)")
    parser.add_argument("--allow-scored", action="store_true")
    args = parser.parse_args(argv)
    try:
        paths = select_scenarios(args.scenarios or default_scenarios(TUNING_DIR), TUNING_DIR,
                                 args.allow_scored)
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


if __name__ == "__main__":
    main()
