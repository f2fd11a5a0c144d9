"""Replay one drive's estimator inputs through the estimator with other settings: seconds a
value where tools/compare_estimation.py needs minutes, for the estimator's choices only.

    MUJOCO_GL=egl .venv/bin/python tools/replay_estimation.py record DIR [SCENARIO ...]
    MUJOCO_GL=egl .venv/bin/python tools/replay_estimation.py record DIR fog --seed 2
    .venv/bin/python tools/replay_estimation.py compare DIR reference_std_m=0.05,0.03

`record` drives each scenario once in the closed loop (default: every tuning scenario; shipped
ones only with --allow-scored, as compare_estimation) and keeps, per step, what the estimator
was given (the front detections, the rear reference, the dead-reckoned ego-motion) and the true
offset at the output's look-ahead, scoring only; one pickle per scenario in DIR (about 1 MB).
`--seed` records another seed than the file's; the bench scores each shipped scenario at its
file's seed only, so a shipped scenario at any other seed is unscored data and allowed.
`compare` runs a fresh `LaneEstimator` over each recording once per value of one
`EstimatorSettings` key and prints the output's RMSE against the best own track's, to 0.1 mm,
and per value the mean and the count of episodes where the output is above its best track.

Open loop: the car drove the recorded line whatever the replayed output says, so a change that
would have steered it elsewhere is not scored for that; confirm a choice with
compare_estimation (closed loop) and the bench. The recordings are pickles: load only your own.

The code is lanekeep/tuning/replay.py.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from pathlib import Path

from lanekeep.tuning.replay import compare, load_recordings, record, setting_values, summarise
from lanekeep.tuning.scenarios import TuningInputError, own_seed, select_scenarios

TUNING_DIR = Path(__file__).resolve().parent / "tuning"  # the scenarios the bench does not score


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record", help="drive scenarios and keep the estimator's inputs")
    rec.add_argument("out", type=Path)
    rec.add_argument("scenarios", nargs="*", help="default: every file in tools/tuning/")
    rec.add_argument("--allow-scored", action="store_true",
                     help="allow shipped scenarios, which `lanekeep bench` scores")
    rec.add_argument("--seed", type=int, help="record this seed instead of the file's")
    cmp = sub.add_parser("compare", help="replay recordings with values of one setting")
    cmp.add_argument("recordings", type=Path, help="a directory of `record`'s pickles")
    cmp.add_argument("setting", help="KEY=VALUE,VALUE... of the estimator's settings")
    args = parser.parse_args(argv)
    if args.command == "record":
        if args.seed is not None and args.seed < 0:
            parser.exit(2, f"error: --seed must be >= 0, got {args.seed}\n")
        unscored = args.seed is not None and all(
            own_seed(s) != args.seed for s in args.scenarios)
        try:
            scenarios = select_scenarios(args.scenarios, TUNING_DIR, args.allow_scored or unscored)
        except TuningInputError as err:
            parser.exit(2, f"error: {err}\n")
        if args.out.exists() and not args.out.is_dir():
            parser.exit(2, f"error: {args.out} exists and is not a directory\n")
        args.out.mkdir(parents=True, exist_ok=True)
        os.environ.setdefault("MUJOCO_GL", "egl")
        for scenario in scenarios:
            print(record(scenario, args.out, args.seed), flush=True)
        return
    from lanekeep.estimators.lane_estimator import EstimatorSettings

    key, _, text = args.setting.partition("=")
    if key not in {f.name for f in dataclasses.fields(EstimatorSettings)} or not text:
        parser.exit(2, f"error: {args.setting!r} is not KEY=VALUE,... of EstimatorSettings\n")
    try:
        recordings = load_recordings(args.recordings, key)
        values = setting_values(recordings, key, text)
    except TuningInputError as err:
        parser.exit(2, f"error: {err}\n")
    try:
        rows = compare(recordings, key, values)
    except ValueError as err:  # the estimator's own checks (an unknown mode, a bad number)
        parser.exit(2, f"error: {key}: {err}\n")
    for name, value, output, track, model in rows:
        print(f"{name:<36} {value!s:<10} output {output:7.4f}  best track {track:7.4f} "
              f"({model})  {output - track:+.4f}")
    print(f"\nper value of {key} over {len(recordings)} recordings (cm, open loop):")
    for s in summarise(rows, values):
        print(f"  {s.value!s:<10} output - best track: mean {s.output_minus_track:+.4f}"
              f"; above it in {s.above}")


if __name__ == "__main__":
    main()
