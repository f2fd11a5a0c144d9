"""Leave-content-out fine-tunes side by side (issue #56 part 3): which content of the dataset
the real frames and the eval sets need.

    python tools/leave_out_report.py DIR [--control random] [--margin 0.02]

DIR holds, per run NAME (a factor of tools/dataset_content.py, or the control), the output of
`python -m lanekeep.tuning.real_accuracy FOLDER --detector lanenet --weights W` as NAME.real.txt
and of `lanekeep eval --detectors lanenet --weights W --json NAME.eval.json`. Each run is
paired with the control: over the real frames (the frame's accuracy, all lanes and ego) and
over the eval sets' conditions (AP), each difference with its 95% interval and the verdict
against the margin (real frames: `--margin`, default 0.02, a lane of one frame is worth 1-2%
of ten; AP: its declared margin, lanekeep/scoring/statistics.py). Bad input is one line, exit 2.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import numpy as np

from lanekeep.evaluation.eval_compare import EvalMismatch, compare_evals
from lanekeep.scoring.statistics import paired

FRAME_LINE = re.compile(r"^lanenet\s+(\S+)\s.*\bacc\s+([\d.]+)%\s+ego\s+([\d.]+)%")


def read_real(path: Path) -> dict[str, tuple[float, float]]:
    """frame -> (accuracy, ego accuracy), 0..1, from real_accuracy's printout."""
    rows = {}
    for line in path.read_text().splitlines():
        m = FRAME_LINE.match(line)
        if m:
            rows[m.group(1)] = (float(m.group(2)) / 100.0, float(m.group(3)) / 100.0)
    if not rows:
        raise ValueError(f"{path}: no lanenet frame lines (real_accuracy's output?)")
    return rows


def _cell(p, scale: float = 1.0) -> str:
    lo, hi = p.ci95
    return f"{p.diff * scale:+.3f} [{lo * scale:+.3f}, {hi * scale:+.3f}] {p.verdict}"


def report(folder: Path, control: str, margin: float) -> str:
    names = sorted(p.name[:-len(".real.txt")] for p in folder.glob("*.real.txt"))
    if control not in names:
        raise ValueError(f"{folder}: no {control}.real.txt (the control)")
    base_real = read_real(folder / f"{control}.real.txt")
    base_eval = json.loads((folder / f"{control}.eval.json").read_text())
    lines = ["| run | real all | real ego | eval AP (mean) | vs control: real all | real ego "
             "| eval AP |", "|---|---|---|---|---|---|---|"]
    for name in [control, *[n for n in names if n != control]]:
        real = read_real(folder / f"{name}.real.txt")
        frames = sorted(set(real) & set(base_real))
        doc = json.loads((folder / f"{name}.eval.json").read_text())
        common, scores, _, diffs = compare_evals(doc, base_eval)
        ap = float(np.mean([scores[c]["ap"] for c in common]))
        mean_all = np.mean([real[f][0] for f in frames])
        mean_ego = np.mean([real[f][1] for f in frames])
        if name == control:
            lines.append(f"| {name} (control) | {mean_all:.3f} | {mean_ego:.3f} | {ap:.3f} "
                         "| | | |")
            continue
        d_all = paired([real[f][0] for f in frames], [base_real[f][0] for f in frames],
                       lower_is_better=False, margin=margin)
        d_ego = paired([real[f][1] for f in frames], [base_real[f][1] for f in frames],
                       lower_is_better=False, margin=margin)
        lines.append(f"| without {name} | {mean_all:.3f} | {mean_ego:.3f} | {ap:.3f} "
                     f"| {_cell(d_all)} | {_cell(d_ego)} | {_cell(diffs['ap'])} |")
    lines.append(f"\nreal frames paired over {len(base_real)} frames (margin {margin}); eval "
                 f"AP paired over {len(common)} conditions (its declared margin)")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder")
    parser.add_argument("--control", default="random")
    parser.add_argument("--margin", type=float, default=0.02)
    args = parser.parse_args(argv)
    try:
        print(report(Path(args.folder), args.control, args.margin))
    except (OSError, ValueError, KeyError, EvalMismatch) as exc:
        print(f"leave_out_report: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
