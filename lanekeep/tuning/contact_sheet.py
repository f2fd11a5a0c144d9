"""Contact sheet: every scenario's front and rear camera at the start and at mid-drive.

    MUJOCO_GL=egl python -m lanekeep.tuning.contact_sheet --out docs/contact_sheet.jpg \\
        [NAME_OR_TOML ...] [--tile 320x180] [--quality 80] [--real DIR]

On one image, to SEE how the world looks (and how it changed) at a glance. A row per scenario
(default: every shipped one): front start, front mid, rear start, rear mid. Each tile is the
frame the car's camera delivers, with the scenario's image effects, exactly as `lanekeep render
SCENARIO --at S` writes front.png / rear.png (lanekeep/sensing/snapshot.py's machinery: the same
world, render settings and effects drawn from the scenario seed), rendered at the scenario's
size, shrunk to the tile by area averaging and labelled with the scenario and view. The car
sits on its ego lane's centre, heading along the road; "mid-drive" is start.s_m + duration_s *
target_speed_mps / 2 (where the car would be half way through its episode at its target speed),
clipped to the road. Traffic stands where it starts (a snapshot does not run time), so
mid-drive tiles show the t = 0 traffic.

`--real DIR` adds a last row of real frames (DIR and its subfolders, e.g. ../shared/real,
`real_row`) for comparison; such a sheet holds real photos, so it must be written outside any
git repository (the sheet in docs/ is made without it): real frames are never committed. Bad
input: one line on stderr, exit 2. tools/contact_sheet.py runs the same command line from a
clone.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from lanekeep.tuning.scenarios import TuningInputError

VIEWS = (("front", "start"), ("front", "mid"), ("rear", "start"), ("rear", "mid"))
IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png")
BACKGROUND = (24, 24, 24)  # RGB of the gaps between tiles and of letterbox bars
GAP_PX = 2


@dataclass(frozen=True)
class Tile:
    """One labelled picture of the sheet (RGB uint8, any size: `fit` makes it a tile)."""

    image: np.ndarray
    label: str


def mid_drive_s(scenario) -> float:
    """Arc length (m) half way through the episode at the target speed, clipped to the road."""
    s = scenario.start.s_m + 0.5 * scenario.duration_s * scenario.target_speed_mps
    return float(min(max(s, 0.0), scenario.road.length_m))


def scenario_tiles(scenario) -> list[Tile]:
    """The four VIEWS of a scenario, each as `render_snapshot(scenario, at_s=s)` renders it
    (a fresh effects stream, the episode's, per pose, cameras in the rig's order)."""
    from lanekeep.scenario.streams import stream_entropy
    from lanekeep.sensing.cameras import CameraRig, RenderSettings
    from lanekeep.sensing.snapshot import camera_frame, make_effects, place_on_road
    from lanekeep.world.build import build

    world = build(scenario)
    poses = {"start": scenario.start.s_m, "mid": mid_drive_s(scenario)}
    frames: dict[tuple[str, str], np.ndarray] = {}
    with CameraRig(world.model, RenderSettings.of(scenario)) as rig:
        for pose, s in poses.items():
            place_on_road(world, s)
            rng = np.random.default_rng(stream_entropy(scenario))
            effects = make_effects(scenario, world, rig, rng)
            for cam in rig.CAMERA_NAMES:
                frames[cam, pose] = camera_frame(rig, world, cam, effects[cam], rng,
                                                 scenario.start.speed_mps)
    return [Tile(frames[cam, pose], f"{scenario.name} | {cam} {pose} s={poses[pose]:.0f} m")
            for cam, pose in VIEWS]


def fit(image: np.ndarray, tile: tuple[int, int]) -> np.ndarray:
    """`image` shrunk (area averaging) to fit a (width, height) tile, letterboxed, RGB uint8."""
    width, height = tile
    h, w = image.shape[:2]
    scale = min(width / w, height / h)
    size = (max(1, round(w * scale)), max(1, round(h * scale)))
    small = cv2.resize(image, size, interpolation=cv2.INTER_AREA if scale < 1 else
                       cv2.INTER_LINEAR)
    out = np.empty((height, width, 3), np.uint8)
    out[:] = BACKGROUND
    top, left = (height - size[1]) // 2, (width - size[0]) // 2
    out[top:top + size[1], left:left + size[0]] = small
    return out


def label(tile: np.ndarray, text: str) -> np.ndarray:
    """`tile` with `text` in white on a darkened band along its top (scaled to the tile)."""
    out = tile.copy()
    height = out.shape[0]
    scale = max(0.25, height / 450.0)
    thickness = 1
    (_, text_h), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thickness)
    band = min(height, text_h + base + 4)
    out[:band] = (out[:band] * 0.35).astype(np.uint8)
    cv2.putText(out, text, (3, band - base - 1), cv2.FONT_HERSHEY_SIMPLEX, scale,
                (255, 255, 255), thickness, cv2.LINE_AA)
    return out


def layout(rows: Sequence[Sequence[Tile]], tile: tuple[int, int]) -> np.ndarray:
    """One RGB image: a row of labelled tiles per entry of `rows`, GAP_PX apart; a short row
    leaves its last places empty."""
    if not rows:
        raise ValueError("a contact sheet needs at least one row")
    width, height = tile
    columns = max(len(r) for r in rows)
    sheet = np.empty((len(rows) * (height + GAP_PX) + GAP_PX,
                      columns * (width + GAP_PX) + GAP_PX, 3), np.uint8)
    sheet[:] = BACKGROUND
    for i, row in enumerate(rows):
        for j, item in enumerate(row):
            top, left = GAP_PX + i * (height + GAP_PX), GAP_PX + j * (width + GAP_PX)
            sheet[top:top + height, left:left + width] = label(fit(item.image, tile), item.label)
    return sheet


def real_frames(folder: Path, count: int) -> list[Path]:
    """Up to `count` image files from `folder` and its subfolders, spread evenly over their
    sorted list (so each of several sets gets a share)."""
    if not folder.is_dir():
        raise TuningInputError(f"--real {folder}: not a folder")
    found = sorted(p for p in folder.rglob("*") if p.suffix.lower() in IMAGE_SUFFIXES
                   and p.is_file())
    if not found:
        raise TuningInputError(f"--real {folder}: no .jpg/.jpeg/.png files in it")
    picks = np.unique(np.linspace(0, len(found) - 1, min(count, len(found))).round().astype(int))
    return [found[i] for i in picks]


def real_row(folder: Path, count: int = len(VIEWS)) -> list[Tile]:
    """Tiles of real frames (read only, labelled `real | <set>/<file>`)."""
    tiles = []
    for path in real_frames(folder, count):
        bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if bgr is None:
            raise TuningInputError(f"--real: cannot read {path}")
        tiles.append(Tile(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB),
                          f"real | {path.parent.name}/{path.name}"))
    return tiles


def inside_a_repository(path: Path) -> Path | None:
    """The git work tree holding `path` (a folder with .git), or None."""
    for parent in Path(path).resolve().parents:
        if (parent / ".git").exists():
            return parent
    return None


def write_sheet(sheet: np.ndarray, out: Path, jpeg_quality: int = 80) -> None:
    """Write the RGB sheet as JPEG (at `jpeg_quality`) or PNG, by `out`'s suffix."""
    params = ([cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality), cv2.IMWRITE_JPEG_OPTIMIZE, 1]
              if out.suffix.lower() in (".jpg", ".jpeg") else [])  # optimize: ~6% smaller
    if not cv2.imwrite(str(out), cv2.cvtColor(sheet, cv2.COLOR_RGB2BGR), params):
        raise TuningInputError(f"--out {out}: could not write it")


def load_scenarios(names: Sequence[str]) -> list:
    """The scenarios named (shipped names or .toml paths), or every shipped one, in order.

    Raises TuningInputError (one line) for a name or file that does not load."""
    from lanekeep.scenario.schema import ScenarioError, load_scenario, shipped_scenarios

    scenarios = []
    for name in list(names) or shipped_scenarios():
        try:
            scenarios.append(load_scenario(name))
        except ScenarioError as err:
            raise TuningInputError(str(err)) from None
    return scenarios


def make_sheet(scenarios: Sequence, tile: tuple[int, int] = (320, 180),
               real: Path | None = None, progress=None) -> np.ndarray:
    """The sheet of `scenarios` (a row each) and, with `real`, a last row of real frames;
    `progress(name)` is called before each scenario renders."""
    rows = []
    for scenario in scenarios:
        if progress is not None:
            progress(scenario.name)
        rows.append(scenario_tiles(scenario))
    if real is not None:
        rows.append(real_row(real))
    return layout(rows, tile)


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
    if args.out.suffix.lower() not in IMAGE_SUFFIXES:
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
