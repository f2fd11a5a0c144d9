"""Contact sheet: every scenario's front and rear camera at the start and at mid-drive.

    MUJOCO_GL=egl .venv/bin/python tools/contact_sheet.py --out docs/contact_sheet.jpg \
        [NAME_OR_TOML ...] [--tile 320x180] [--quality 80] [--real DIR]

A row per scenario (default: every shipped one): front start, front mid, rear start, rear mid,
each the frame the car's camera delivers WITH the scenario's image effects, as `lanekeep render
NAME --at S` writes it, shrunk to the tile and labelled with the scenario and view. Mid-drive is
start.s_m + duration_s * target_speed_mps / 2 (lanekeep/tuning/contact_sheet.py says why).

`--real DIR` adds a last row of real frames (DIR and its subfolders, e.g. ../shared/real) for
comparison; such a sheet holds real photos, so it must be written outside any git repository
(the sheet in docs/ is made without it). Bad input: one line on stderr, exit 2.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

from lanekeep.tuning.contact_sheet import (
    inside_a_repository,
    load_scenarios,
    make_sheet,
    write_sheet,
)
from lanekeep.tuning.scenarios import TuningInputError

SUFFIXES = (".jpg", ".jpeg", ".png")


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*", metavar="NAME_OR_TOML",
                        help="scenario names or .toml paths (default: every shipped scenario)")
    parser.add_argument("--out", type=Path, required=True, help="the sheet: .jpg, .jpeg or .png")
    parser.add_argument("--tile", default="320x180", metavar="WxH",
                        help="size of each tile in pixels (default 320x180)")
    parser.add_argument("--quality", type=int, default=80, help="JPEG quality 10..100 (80)")
    parser.add_argument("--real", type=Path, metavar="DIR",
                        help="add a row of real frames from DIR (output outside any repository)")
    return parser.parse_args(argv)


def check(args: argparse.Namespace) -> tuple[int, int]:
    """The tile size; raises TuningInputError on any bad argument, before anything renders."""
    match = re.fullmatch(r"(\d+)x(\d+)", args.tile)
    if not match or not (16 <= int(match[1]) <= 1280 and 9 <= int(match[2]) <= 720):
        raise TuningInputError(f"--tile {args.tile}: must be WxH with W in 16..1280 and "
                               f"H in 9..720, e.g. 320x180")
    if args.out.suffix.lower() not in SUFFIXES:
        raise TuningInputError(f"--out {args.out}: must end in .jpg, .jpeg or .png")
    if not args.out.resolve().parent.is_dir():
        raise TuningInputError(f"--out {args.out}: its folder does not exist")
    if not 10 <= args.quality <= 100:
        raise TuningInputError(f"--quality {args.quality}: must be in 10..100")
    if args.real is not None and (repo := inside_a_repository(args.out)) is not None:
        raise TuningInputError(f"--real puts real frames in the sheet: write it outside the "
                               f"repository {repo}, not to {args.out}")
    return int(match[1]), int(match[2])


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    started = time.perf_counter()
    try:
        tile = check(args)
        scenarios = load_scenarios(args.scenarios)
        sheet = make_sheet(scenarios, tile, args.real,
                           progress=lambda name: print(f"rendering {name}", file=sys.stderr))
        write_sheet(sheet, args.out, args.quality)
    except TuningInputError as err:
        print(f"contact_sheet: error: {err}", file=sys.stderr)
        return 2
    print(f"wrote {args.out} ({sheet.shape[1]}x{sheet.shape[0]}, {len(scenarios)} scenarios, "
          f"{time.perf_counter() - started:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
