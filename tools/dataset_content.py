"""What a LaneNet dataset's worlds contain (lanekeep/evaluation/dataset_content.py), and the
training worlds of a leave-content-out fine-tune.

    python tools/dataset_content.py --data data/lanenet59 [--json content.json]
    python tools/dataset_content.py --data data/lanenet59 --drop traffic --count 80 \\
        --keep worlds.json
    python tools/train_lanenet.py --data data/lanenet59 --worlds worlds.json ...

`--drop FACTOR --count N` writes to `--keep` the training worlds left when the N with the most
of FACTOR are dropped (`paint_contrast`: the N with the faintest paint; `random`: N drawn with
`--seed`, the control of the same size). Bad input is one line, exit 2.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import numpy as np

from lanekeep.evaluation.dataset_content import (
    FACTORS,
    content_rows,
    held_out,
    label_contrast,
    split_content,
)

COLUMNS = ("paint_contrast_dn", "label_contrast_dn", "vehicles_per_lane_km", "shade_share",
           "horizon_row", "camera_height_m")


def summary(rows: list[dict]) -> str:
    lines = [f"{len(rows)} worlds; dashcam {sum(r['dashcam'] for r in rows)}",
             f"{'':22s} {'p10':>7s} {'median':>7s} {'p90':>7s}"]
    for key in COLUMNS:
        v = np.array([r[key] for r in rows], float)
        v = v[np.isfinite(v)]
        p10, p50, p90 = np.percentile(v, [10, 50, 90]) if len(v) else (math.nan,) * 3
        lines.append(f"{key:22s} {p10:7.2f} {p50:7.2f} {p90:7.2f}")
    return "\n".join(lines)


def real_contrast(folder: Path) -> str:
    """The label-read paint contrast of each labelled real frame, at the network's size."""
    from lanekeep.detectors.lanenet_model import LaneNetConfig, prepare_frame
    from lanekeep.realcam.calibration import read_image

    config, values, lines_out = LaneNetConfig(), [], []
    labelled = sorted((folder / "labels").glob("*.txt"))
    if not labelled:
        raise ValueError(f"{folder}: no labels/*.txt")
    for label in labelled:
        image = read_image(folder / f"{label.stem}.jpg")
        small = prepare_frame(image, config).transpose(1, 2, 0)
        lines = [np.asarray([float(v) for v in row.split()]).reshape(-1, 2)
                 for row in label.read_text().splitlines() if len(row.split()) >= 4]
        full = (image.shape[1], image.shape[0])
        value = label_contrast(np.ascontiguousarray(small), lines, full)
        values.append(value)
        lines_out.append(f"  {label.stem}: {value:.1f}")
    finite = [v for v in values if math.isfinite(v)]
    return "\n".join([f"real frames ({folder}), label_contrast_dn: median "
                      f"{np.median(finite):.1f} over {len(finite)} frames", *lines_out])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", required=True, help="dataset folder (tools/make_dataset.py)")
    parser.add_argument("--split", default="train")
    parser.add_argument("--json", help="write every world's content here")
    parser.add_argument("--drop", choices=FACTORS, help="the factor a leave-out run drops")
    parser.add_argument("--count", type=int, default=80, help="worlds to drop")
    parser.add_argument("--seed", type=int, default=0, help="the random control's draw")
    parser.add_argument("--keep", help="write the kept training worlds (JSON list) here")
    parser.add_argument("--real", help="also read the paint contrast at the labels of these "
                        "real frames (N.jpg, labels/N.txt), as for the worlds' labels")
    args = parser.parse_args(argv)
    if bool(args.drop) != bool(args.keep):
        print("dataset_content: error: --drop and --keep go together", file=sys.stderr)
        return 2
    try:
        content = split_content(Path(args.data), args.split)
        dropped = held_out(content, args.drop, args.count, args.seed) if args.drop else []
    except (OSError, ValueError) as exc:
        print(f"dataset_content: error: {exc}", file=sys.stderr)
        return 2
    rows = content_rows(content)
    print(summary(rows))
    if args.real:
        try:
            print(real_contrast(Path(args.real)))
        except (OSError, ValueError) as exc:
            print(f"dataset_content: error: --real: {exc}", file=sys.stderr)
            return 2
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")
    if args.keep:
        kept = [w.index for w in content if w.index not in set(dropped)]
        gone = [r for r in rows if r["index"] in set(dropped)]
        print(f"\ndropping {len(dropped)} worlds by {args.drop}:")
        print(summary(gone))
        Path(args.keep).write_text(json.dumps(kept) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
