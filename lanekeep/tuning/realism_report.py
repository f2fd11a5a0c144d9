"""Realism report: the same image statistics for rendered frames and real photos, side by side.

    MUJOCO_GL=egl python -m lanekeep.tuning.realism_report --real ../shared/real \\
        [--scenarios clear_straight night ...] [--at S] [--out report.md] [--json report.json]

Simulator side: each scenario's front camera at its start pose (or `--at S` metres along the
road), WITH the scenario's image effects, i.e. the frame the car's camera delivers (the same
frame `lanekeep.sensing.snapshot.render_snapshot(..., effects=True)` writes as front.png), plus
the segmentation render's marking mask for the paint contrast. Real side: every
*.jpg/*.jpeg/*.png in each image folder under `--real` (or `--real` itself); the photos are only
read, never copied. Known folders have a horizon row given here; TuSimple label files
(labels/N.txt) give the paint pixels. Renders only, nothing scored: the shipped scenarios are
the default. The report is a Markdown table and a JSON document; a second table puts issue
#59's statistics (tone, green, open sky, road structure: `lanekeep.tuning.realism_gaps`) side
by side, ours' median and range over the scenarios against each real set's median.

Every statistic is a small pure function of an RGB uint8 image and a horizon row, defined in
its docstring (`lanekeep.tuning.realism`). The table is for SEEING the gap between renders and
photos, not a target to fit: a renderer tuned to match these few numbers on 18 photos would be
overfitted to them. tools/realism_report.py runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from lanekeep.tuning.realism import (
    CANNY_HIGH,
    CANNY_LOW,
    WORK_WIDTH,
    camera_horizon_row,
    frame_stats,
    label_paint_mask,
    mean_stats,
    read_label_lanes,
)
from lanekeep.tuning.realism_gaps import gap_stats
from lanekeep.tuning.scenarios import TuningInputError


@dataclass(frozen=True)
class RealSet:
    """A folder of real frames: its display name and horizon row (None: not known)."""

    name: str
    horizon_row: float | None
    horizon_source: str


# Horizon rows of the two development sets as given in the [realism] issue (TuSimple near row
# 250, Udacity near 430) and checked by eye on the frames: where the lane lines vanish. Constants,
# not estimates: the README gives none, and all frames of a set share one camera mounting.
KNOWN_SETS = {
    "tusimple_dev": RealSet("TuSimple", 250.0, "constant (vanishing point of the lanes)"),
    "udacity": RealSet("Udacity", 430.0, "constant (vanishing point of the lanes)"),
}
IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png")


# -- simulator frames --------------------------------------------------------------------------
def render_front(scenario, at_s: float | None = None
                 ) -> tuple[np.ndarray, np.ndarray, float]:
    """(RGB, marking mask, horizon row) of a scenario's front camera at a road pose.

    The RGB is exactly render_snapshot(scenario, ..., effects=True)'s front.png: the same
    world, pose, render settings and image effects drawn from the episode's stream in the same
    order (both cameras' effects are made, then the front's are applied); the test checks it.
    Only the front camera is rendered, plus its segmentation for the marking mask.
    """
    from lanekeep.scenario.streams import stream_entropy
    from lanekeep.sensing.cameras import CameraRig, RenderSettings
    from lanekeep.sensing.snapshot import camera_frame, make_effects, place_on_road
    from lanekeep.world.build import build

    world = build(scenario)
    s = scenario.start.s_m if at_s is None else at_s
    if not 0.0 <= s <= world.road.length_m:
        raise TuningInputError(f"--at {s} is outside {scenario.name}'s road "
                               f"(0..{world.road.length_m:.0f} m)")
    place_on_road(world, s)
    settings = RenderSettings.of(scenario)
    with CameraRig(world.model, settings) as rig:
        rng = np.random.default_rng(stream_entropy(scenario))
        effects = make_effects(scenario, world, rig, rng)
        rgb = camera_frame(rig, world, "front", effects["front"], rng, scenario.start.speed_mps)
        paint = world.marking_mask(rig.render_segmentation(world.data, "front"))
        horizon = camera_horizon_row(rig.cameras["front"])
    return rgb, paint, horizon


def all_stats(rgb: np.ndarray, horizon_row: float, paint: np.ndarray | None
              ) -> dict[str, float]:
    """Every statistic of one frame: `realism.frame_stats` and #59's `realism_gaps.gap_stats`."""
    return {**frame_stats(rgb, horizon_row, paint), **gap_stats(rgb, horizon_row, paint)}


# -- real frames -------------------------------------------------------------------------------
def image_folders(root: Path) -> list[Path]:
    """Folders holding images: `root` itself if it does, else its subfolders that do, sorted."""
    def has_images(folder: Path) -> bool:
        return any(p.suffix.lower() in IMAGE_SUFFIXES for p in folder.iterdir() if p.is_file())

    if has_images(root):
        return [root]
    return [d for d in sorted(root.iterdir()) if d.is_dir() and has_images(d)]


def real_set(folder: Path, horizon_override: float | None) -> RealSet:
    """The set a folder holds: a known one's name and horizon, else the folder name and the
    `--horizon` row (or the centre row, said so in the table)."""
    if folder.name in KNOWN_SETS and horizon_override is None:
        return KNOWN_SETS[folder.name]
    if horizon_override is not None:
        return RealSet(folder.name, horizon_override, "--horizon")
    return RealSet(folder.name, None, "assumed: image centre row")


def read_rgb(path: Path) -> np.ndarray | None:
    """An image file as RGB uint8, None if it cannot be read."""
    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    return None if bgr is None else cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def real_folder_stats(folder: Path, info: RealSet) -> list[dict[str, float]]:
    """Statistics of every readable image in a folder; labels/<stem>.txt, if there, gives paint."""
    rows = []
    for path in sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES):
        rgb = read_rgb(path)
        if rgb is None:
            print(f"realism_report: skipping unreadable {path}", file=sys.stderr)
            continue
        horizon = info.horizon_row if info.horizon_row is not None else (rgb.shape[0] - 1) / 2
        label = folder / "labels" / f"{path.stem}.txt"
        paint = (label_paint_mask(read_label_lanes(label), rgb.shape[:2])
                 if label.is_file() else None)
        rows.append({"image": path.name, **all_stats(rgb, horizon, paint)})
    return rows


# -- output ------------------------------------------------------------------------------------
COLUMNS = (  # (header, formatter of a stats dict)
    ("horizon row", lambda s: cell(s["horizon_row"], 0)),
    ("edges above", lambda s: cell(s["edges_above"], 3)),
    ("edges below", lambda s: cell(s["edges_below"], 3)),
    ("sky share above", lambda s: cell(s["sky_share"], 2)),
    ("luma mean", lambda s: cell(s["luma_mean"], 0)),
    ("luma p5/p50/p95", lambda s: "/".join(cell(s[k], 0)
                                         for k in ("luma_p5", "luma_p50", "luma_p95"))),
    ("mean R/G/B", lambda s: "/".join(cell(s[k], 0) for k in ("mean_r", "mean_g", "mean_b"))),
    ("saturation", lambda s: cell(s["saturation"], 2)),
    ("colourfulness", lambda s: cell(s["colourfulness"], 1)),
    ("noise sigma", lambda s: cell(s["noise_sigma"], 2)),
    ("paint-road", lambda s: cell(s["paint_minus_road"], 0)),
    ("paint/road", lambda s: cell(s["paint_over_road"], 2)),
    ("paint p90-road", lambda s: cell(s["paint_p90_minus_road"], 0)),
    ("paint edge px", lambda s: cell(s["paint_edge_px"], 1)),
    ("shade/sun", lambda s: cell(s["shade_over_sun"], 2)),
)

LEGEND = """\
Columns: horizon row (sim: from the camera model; real: per-set constant); edges above/below:
share of Canny(50, 150) edge pixels after a sigma-1 Gaussian, above / below the horizon; sky
share above: share of the pixels above the horizon that are smooth and blue-ish or bright;
luma (Rec. 601, DN) below the horizon; mean R/G/B, HSV saturation and Hasler-Suesstrunk
colourfulness of the whole frame; noise sigma: sigma (DN) of Immerkaer's high-pass of the luma
in the flattest 20% of 8x8 blocks below the horizon, noise plus finest texture (JPEG smooths
real frames: a lower bound there); paint-road / paint/road: difference / ratio of the median
luma of marking pixels and of road 15..30 px beside them; paint p90-road: the same with the
paint's 90th percentile (sim: segmentation mask; TuSimple: +-2 px around the label polylines,
which run through dash gaps and over raised dots, so a lower bound, the medians mostly see
road; "-": no labels); paint edge px: mean 10-90% rise width of the luma across paint edges
along image rows through the mask's (labels') centre, edges >= 20 DN only; shade/sun: mean
luma of the darker over the brighter class of an Otsu split of a road trapezoid below the
horizon, "-" when the darker covers < 10% (unshaded asphalt still reads 0.7-0.9: texture,
wheel paths). Real rows are means over their frames; all values at 1280 px wide."""

# #59's statistics, one row each: (key, label, scale to the shown unit, decimals).
GAP_ROWS = (
    ("dark_share", "dark share (luma < 40 DN), % of frame", 100.0, 1),
    ("dark_p1", "darkest 1% (luma p1), DN", 1.0, 0),
    ("green_share", "saturated green, % of frame", 100.0, 2),
    ("green_v", "green: mean V (HSV, 0-255)", 1.0, 0),
    ("green_texture", "green: mean abs Laplacian, DN", 1.0, 1),
    ("open_sky_share", "open sky, share above horizon", 1.0, 2),
    ("road_edges", "road-structure edges, % (paint: mask/labels)", 100.0, 2),
    ("road_edges_guess", "road-structure edges, % (paint guessed)", 100.0, 2),
)

GAP_LEGEND = """\
#59's statistics (lanekeep/tuning/realism_gaps.py; ours: median and range over the scenarios'
frames; real: median over each set's frames; "n/a": not defined for that source, "-": no
value). Dark share and darkest 1%: luma (Rec. 601) of the whole frame. Saturated green: HSV hue
70-170 deg, S >= 0.25, V >= 20, on the frame shrunk to 320 px wide; its mean V and mean
|Laplacian| of the luma there (texture of clumps and tufts). Open sky: smooth, bright (luma >=
100), blue-ish or grey pixels above the horizon (ours: camera model; real: the set's constant
row), closed 5x5, connected to the top edge, holes (clouds) filled. Road-structure edges:
Canny(20, 60) pixels in the road trapezoid above 88% of the height, outside paint and a margin
of 3 px + 0.06 px per row below the horizon; paint from the segmentation (ours), the label
polylines (TuSimple), none (n/a) for an unlabelled set; "paint guessed" uses a two-sided ridge
(>= 20 DN) or yellow as paint for every source alike (approximate: it misses raised dots and
faint dashes, whose edges then count)."""

FOOTER = ("This table is for seeing the gap between the renders and real photos, not a target "
          "to fit: matching these numbers on a handful of photos would overfit the renderer "
          "to them without making it realistic.")


def cell(value: float, digits: int) -> str:
    """A table cell: the value to `digits` decimals, "-" where there is none."""
    return "-" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def markdown_table(rows: list[tuple[str, dict[str, float]]]) -> str:
    """Markdown table: one row per (label, stats), the COLUMNS as columns."""
    head = "| frames | " + " | ".join(h for h, _ in COLUMNS) + " |"
    rule = "|---|" + "---:|" * len(COLUMNS)
    body = ["| " + label + " | " + " | ".join(f(s) for _, f in COLUMNS) + " |"
            for label, s in rows]
    return "\n".join([head, rule, *body])


def spread(rows: list[dict[str, float]], key: str) -> dict[str, float]:
    """Median, min and max of one statistic over frames, NaN ignored; n: the finite values."""
    values = np.array([r[key] for r in rows], dtype=float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return {"median": math.nan, "min": math.nan, "max": math.nan, "n": 0}
    return {"median": float(np.median(values)), "min": float(values.min()),
            "max": float(values.max()), "n": int(values.size)}


def gap_summary(sim: list[dict[str, float]], real: dict[str, list[dict[str, float]]]
                ) -> dict[str, dict[str, dict[str, float]]]:
    """#59's statistics side by side: {key: {"ours": spread, <real set name>: spread}}."""
    return {key: {"ours": spread(sim, key), **{name: spread(rows, key)
                                                for name, rows in real.items()}}
            for key, *_ in GAP_ROWS}


def gap_table(summary: dict[str, dict[str, dict[str, float]]], real_names: list[str]) -> str:
    """Markdown table of `gap_summary`: ours' median and range, each real set's median;
    "n/a" where a source has no value on any frame."""
    def shown(value: float, scale: float, digits: int) -> str:
        return cell(value * scale, digits)

    n_sim = max(summary[key]["ours"]["n"] for key, *_ in GAP_ROWS)
    head = (f"| statistic | ours median (of {n_sim}) | ours range | "
            + " | ".join(f"{name} median" for name in real_names) + " |")
    rule = "|---|---:|---:|" + "---:|" * len(real_names)
    body = []
    for key, label, scale, digits in GAP_ROWS:
        ours = summary[key]["ours"]
        cells = [shown(ours["median"], scale, digits),
                 f"{shown(ours['min'], scale, digits)}-{shown(ours['max'], scale, digits)}"]
        cells += [shown(summary[key][name]["median"], scale, digits)
                  if summary[key][name]["n"] else "n/a" for name in real_names]
        body.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join([head, rule, *body])


def jsonable(value):
    """`value` with every non-finite float as None (JSON has no NaN)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, list):
        return [jsonable(v) for v in value]
    return value


@dataclass(frozen=True)
class ReportRequest:
    """What to compare: the real frames' root, the scenarios (None: every shipped one), the
    arc length to render at (None: each start pose) and a horizon row for every real folder
    (None: the known sets' constants)."""

    real: Path
    scenarios: tuple[str, ...] | None = None
    at_s: float | None = None
    horizon_row: float | None = None


def run(request: ReportRequest) -> tuple[str, dict]:
    """The report's Markdown and its JSON document; TuningInputError on a user error."""
    real = request.real
    if not real.is_dir():
        raise TuningInputError(f"--real {real}: no such folder")
    folders = image_folders(real)
    if not folders:
        raise TuningInputError(f"--real {real}: no {'/'.join(IMAGE_SUFFIXES)} images in it or "
                               "in its subfolders")
    from lanekeep.core.config_io import ConfigError
    from lanekeep.scenario.schema import load_scenario, shipped_scenarios

    rows: list[tuple[str, dict[str, float]]] = []
    doc: dict = {"sim": [], "real": []}
    real_frames: dict[str, list[dict[str, float]]] = {}
    for name in request.scenarios or shipped_scenarios():
        try:
            scenario = load_scenario(name)
        except ConfigError as err:
            raise TuningInputError(str(err)) from None
        rgb, paint, horizon = render_front(scenario, request.at_s)
        stats = all_stats(rgb, horizon, paint)
        rows.append((scenario.name, stats))
        doc["sim"].append({"scenario": scenario.name, "at_s": request.at_s, "stats": stats})
    for folder in folders:
        info = real_set(folder, request.horizon_row)
        per_image = real_folder_stats(folder, info)
        if not per_image:
            continue
        frames = [{k: v for k, v in r.items() if k != "image"} for r in per_image]
        real_frames[info.name] = frames
        stats = mean_stats(frames)
        label = f"{info.name} (mean of {len(per_image)})"
        if info.horizon_row is None:
            label += " [horizon assumed: centre row]"
        rows.append((label, stats))
        doc["real"].append({"set": info.name, "folder": str(folder),
                            "horizon_source": info.horizon_source, "mean": stats,
                            "per_image": per_image})
    if not doc["real"]:
        raise TuningInputError(f"--real {real}: none of its images could be read")
    summary = gap_summary([d["stats"] for d in doc["sim"]], real_frames)
    doc["gaps"] = summary
    text = "\n\n".join([markdown_table(rows), LEGEND, gap_table(summary, list(real_frames)),
                         GAP_LEGEND, FOOTER]) + "\n"
    doc["settings"] = {"work_width": WORK_WIDTH, "canny": [CANNY_LOW, CANNY_HIGH],
                       "at_s": request.at_s, "footer": FOOTER}
    return text, jsonable(doc)


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
