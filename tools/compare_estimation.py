"""Compare values of one `[estimation]` key in the closed loop, on the tuning scenarios.

    MUJOCO_GL=egl .venv/bin/python tools/compare_estimation.py output=select,fused

Runs every tuning scenario (tools/tuning/*.toml, which `lanekeep bench` does not score) once
per value, full length at the shipped camera size, and prints per episode the MMAE output's
offset RMSE, the best front model's own track (like for like), the car's maximum lateral error
and the rear reference's RMSE; then per value the mean of (output - best track) and the sum of
the car maxima. A choice of the estimator's defaults is made here, and the bench then reports
it on scenarios it was not chosen on. Shipped scenarios are refused (as by
tools/measure_detector_noise.py) unless --allow-scored is given.

The code is lanekeep/tuning/estimation.py.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from lanekeep.tuning.estimation import Setting, run_all, summarise
from lanekeep.tuning.scenarios import TuningInputError, select_scenarios

TUNING_DIR = Path(__file__).resolve().parent / "tuning"  # the scenarios the bench does not score


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("setting",
                        help="KEY=VALUE,VALUE... of [estimation] (strings, numbers, true/false)")
    parser.add_argument("scenarios", nargs="*",
                        help="scenario names or files (default: every file in tools/tuning/)")
    parser.add_argument("--allow-scored", action="store_true",
                        help="allow shipped scenarios, which `lanekeep bench` scores")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    try:
        args.setting = Setting.parse(args.setting)
        args.scenarios = select_scenarios(args.scenarios, TUNING_DIR, args.allow_scored)
    except TuningInputError as err:
        parser.exit(2, f"error: {err}\n")
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    setting: Setting = args.setting
    results = []
    for r in run_all(args.scenarios, setting, args.workers):
        results.append(r)
        print(f"{r.scenario:<36} {r.value:<10} output {r.output_cm:6.3f}  best track "
              f"{r.best_track_cm:6.3f} ({r.best_model})  car max {r.car_max_cm:5.1f}  "
              f"reference {r.reference_cm:5.2f}", flush=True)
    print(f"\nper value of {setting.key} over {len(args.scenarios)} scenarios (cm):")
    for s in summarise(results, setting.values):
        print(f"  {s.value:<10} output - best track: mean {s.output_minus_track:+.3f}; "
              f"car max: sum {s.car_max_sum:.1f}, worst {s.car_max_worst:.1f}")


if __name__ == "__main__":
    main()
