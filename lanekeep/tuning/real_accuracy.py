"""Score the detectors on labelled real frames (TuSimple rule), for tuning and validation.

    python -m lanekeep.tuning.real_accuracy ../shared/real/tusimple_dev [--detector sliding_window]
    python -m lanekeep.tuning.real_accuracy ../shared/real/tusimple_dev --detector lanenet

A detector that sees every boundary (LaneNet) is scored on all of them, as `lanekeep detect
--format tusimple` reports them; the classical ones on their ego pair.

The folder holds N.jpg and labels/N.txt (one labelled lane a line: "x y x y ..."). Prints per
frame and mean accuracy over all labelled lanes, and the ego accuracy: the same rule on the two
labelled lanes that bound the ego lane (nearest left and right of the image centre at their
lowest labelled row). The photos are never copied anywhere. tools/tune_real.py runs the same
command line from a clone.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from lanekeep.detectors.config import load_config
from lanekeep.detectors.registry import known_detectors, make_detector
from lanekeep.detectors.tusimple import estimate_lanes, every_lane, h_samples_for, score_frame
from lanekeep.realcam.calibration import read_image
from lanekeep.realcam.camera_file import camera_for_image


def read_labels(path: Path, h_samples: list[int]) -> list[list[int]]:
    lanes = []
    for line in path.read_text().splitlines():
        values = [float(v) for v in line.split()]
        if len(values) < 4:
            continue
        pts = dict(zip(np.round(values[1::2]).astype(int), values[0::2], strict=True))
        lanes.append([int(round(pts[v])) if v in pts else -2 for v in h_samples])
    return lanes


def x_at_bottom(lane: list[int], h_samples: list[int], bottom: float) -> float | None:
    """Where a labelled lane meets the frame's bottom row: a line through its lowest five
    labelled points, extended. Lanes end at different rows (a far lane's label can stop at
    row 380 near the frame's edge), so comparing their lowest labelled x would rank a far
    lane as nearer the centre than the ego boundary beside it."""
    pts = [(v, x) for v, x in zip(h_samples, lane, strict=True) if x >= 0]
    if not pts:
        return None
    pts = sorted(pts)[-5:]
    if len(pts) == 1:
        return float(pts[0][1])
    vs, xs = np.asarray(pts, dtype=float).T
    slope, intercept = np.polyfit(vs, xs, 1)
    return float(slope * bottom + intercept)


def ego_lanes(lanes: list[list[int]], h_samples: list[int], centre: float, bottom: float
              ) -> list[list[int]]:
    """The two labelled lanes that bound the ego lane: nearest the image centre, one each side,
    where they meet the frame's bottom row."""
    left, right = None, None
    for lane in lanes:
        x = x_at_bottom(lane, h_samples, bottom)
        if x is None:
            continue
        if x < centre and (left is None or x > left[0]):
            left = (x, lane)
        if x >= centre and (right is None or x < right[0]):
            right = (x, lane)
    return [side[1] for side in (left, right) if side is not None]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("--detector", action="append", choices=known_detectors())
    parser.add_argument("--weights", default=None, help="LaneNet weights (default: shipped)")
    parser.add_argument("--detectors-config", metavar="FILE", default=None,
                        help="a detectors TOML file to run with (default: the shipped one)")
    args = parser.parse_args(argv)
    folder = Path(args.folder)
    config = load_config(args.detectors_config)
    dash = config.dashcam
    for name in args.detector or known_detectors():
        overall, ego = [], []
        for img_path in sorted(folder.glob("*.jpg"), key=lambda p: p.stem):
            label = folder / "labels" / (img_path.stem + ".txt")
            if not label.exists():
                continue
            image = read_image(img_path)
            h_samples = h_samples_for(image.shape[0])
            camera, _, horizon = camera_for_image(
                image, None, dash.hfov_deg, dash.height_m, dash.horizon_fraction,
                dash.min_horizon_fraction, dash.max_horizon_fraction)
            detector = make_detector(name, camera, config, weights=args.weights)
            estimate = detector.detect(image)
            named = every_lane(detector, camera, False, h_samples,
                               (image.shape[1], image.shape[0]), horizon)
            if named is not None:
                pred = [lane.xs for lane in named]
            else:
                x_range = (float(camera.position_m[0]) + 1.0, detector.window.x_far_m * 1.3)
                pred = estimate_lanes(estimate, camera, h_samples, x_range)
            gt = read_labels(label, h_samples)
            acc, _ = score_frame(pred, gt, h_samples)
            ego_gt = ego_lanes(gt, h_samples, image.shape[1] / 2.0, image.shape[0] - 1.0)
            _, per = score_frame(pred, ego_gt, h_samples)
            ego_acc = sum(per) / max(len(ego_gt), 1)
            overall.append(acc)
            ego.append(ego_acc)
            print(f"{name:15s} {img_path.name:8s} horizon {horizon:5.0f} "
                  f"valid {estimate.valid!s:5s} lanes {len(pred)} "
                  f"acc {acc:5.1%} ego {ego_acc:5.1%} {estimate.reason}")
        print(f"{name}: mean accuracy {np.mean(overall):.1%}, ego {np.mean(ego):.1%} "
              f"over {len(overall)} frames")
    return 0


if __name__ == "__main__":
    sys.exit(main())
