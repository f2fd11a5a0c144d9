"""Realism report: the same image statistics for rendered frames and real photos, side by side.

    MUJOCO_GL=egl .venv/bin/python tools/realism_report.py --real ../shared/real \
        [--scenarios clear_straight night ...] [--at S] [--out report.md] [--json report.json]

Simulator side: each scenario's front camera at its start pose (or `--at S` metres along the
road), WITH the scenario's image effects, i.e. the frame the car's camera delivers (the same
frame `lanekeep.sensing.snapshot.render_snapshot(..., effects=True)` writes as front.png), plus
the segmentation render's marking mask for the paint contrast. Real side: every
*.jpg/*.jpeg/*.png in each image folder under `--real` (or `--real` itself); the photos are only
read, never copied. Known folders have a horizon row given here; TuSimple label files
(labels/N.txt) give the paint pixels.

Every statistic is a small pure function of an RGB uint8 image and a horizon row, defined in
its docstring (lanekeep/tuning/realism.py; the report is lanekeep/tuning/realism_report.py).
The table is for SEEING the gap between renders and photos, not a target to fit: a renderer
tuned to match these few numbers on 18 photos would be overfitted to them.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from lanekeep.tuning.realism_report import ReportRequest, run
from lanekeep.tuning.scenarios import TuningInputError


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--real", type=Path, required=True,
                        help="folder of real frames, or of image folders (e.g. ../shared/real)")
    parser.add_argument("--scenarios", nargs="+", metavar="NAME",
                        help="scenario names or .toml paths (default: all shipped)")
    parser.add_argument("--at", type=float, metavar="S",
                        help="render at this arc length (m) instead of each start pose")
    parser.add_argument("--horizon", type=float, metavar="ROW",
                        help="horizon row for every real folder (default: known sets' constants)")
    parser.add_argument("--out", type=Path, help="write the Markdown report here too")
    parser.add_argument("--json", type=Path, help="write all values (per frame too) as JSON")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    started = time.perf_counter()
    request = ReportRequest(args.real, tuple(args.scenarios) if args.scenarios else None,
                            args.at, args.horizon)
    try:
        text, doc = run(request)
    except TuningInputError as err:
        print(f"realism_report: {err}", file=sys.stderr)
        return 2
    print(text, end="")
    if args.out:
        args.out.write_text(text, encoding="utf-8")
    if args.json:
        args.json.write_text(json.dumps(doc, indent=1), encoding="utf-8")
    print(f"realism_report: {time.perf_counter() - started:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
