"""Replay recorded camera frames through the classical detectors and score them: a quick,
open-loop way to tune the detectors on the tuning scenarios (never on the shipped ones).

    MUJOCO_GL=egl .venv/bin/python tools/tuning/detector_replay.py record \\
        tools/tuning/tune_traffic_lead_van_three_lanes.toml /tmp/lk/replay/van --seconds 25
    .venv/bin/python tools/tuning/detector_replay.py score /tmp/lk/replay/van
    .venv/bin/python tools/tuning/detector_replay.py score /tmp/lk/replay/van --config my.toml

`record` drives the scenario once and keeps every front and rear frame (raw uint8 .npy, about
2.8 MB a frame) with the true offsets at each detector's look-ahead, taken from the pose the
frame was rendered at (scoring only: the detectors still see the frames alone). The car is
steered on the true lane centre plus a slow sinusoidal wander (WANDER_M, WANDER_PERIOD_S): the
recording is data for tuning the detectors, and a loop that a fooled detector drove out of its
lane would leave nothing to tune on; `--closed-loop` records the loop's own drive instead.
`score` runs a fresh hough and sliding_window on the front frames and sliding_window on the
rear (the closed loop's reference) in order, so the sliding windows' memory of the last fit
plays as in the loop, and prints per detector: RMSE and the 95th percentile of the offset
error, the share of valid frames, the share of gross errors (over GROSS_M) and the detector's
time per frame. `--config FILE` scores a candidate detectors TOML (a partial file: the rest
keeps the tuned defaults) instead of the shipped one. A replay scores detection, not control.

The code is lanekeep/tuning/detector_replay.py.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from lanekeep.detectors.config import load_config
from lanekeep.tuning.detector_replay import record, score


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record")
    rec.add_argument("scenario")
    rec.add_argument("out", type=Path)
    rec.add_argument("--seconds", type=float)
    rec.add_argument("--closed-loop", action="store_true",
                     help="record the loop's own drive, not the truth-steered one")
    sco = sub.add_parser("score")
    sco.add_argument("folders", type=Path, nargs="+")
    sco.add_argument("--config", type=Path,
                     help="detectors TOML to score (default: the shipped detectors.toml)")
    args = parser.parse_args(argv)
    if args.command == "score" and args.config is not None:
        try:  # a bad candidate file: one line, before any frame is scored
            load_config(args.config)
        except (OSError, ValueError) as err:
            parser.exit(2, f"detector_replay: error: {err}\n")
    if args.command == "record":
        record(args.scenario, args.out, args.seconds, args.closed_loop)
        return
    for folder in args.folders:
        print(folder.name)
        for job, s in score(folder, args.config).items():
            print(f"  {job:22s} rmse {s['rmse_cm']:6.1f} cm  p95 {s['p95_cm']:6.1f}  max "
                  f"{s['max_cm']:6.1f}  valid {s['valid_pct']:5.1f}%  gross "
                  f"{s['gross_pct']:5.1f}%  {s['ms']:5.1f} ms")


if __name__ == "__main__":
    main()
