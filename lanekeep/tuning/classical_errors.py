"""Where a classical detector goes wrong on an eval set: per-frame ego errors and overlays.

    python -m lanekeep.tuning.classical_errors --detector hough --condition clear \
        [--split tuning] [--quick] [--worst 8] [--out out/classical_errors] [--detectors-config F]

Runs one detector over one condition's set as `lanekeep eval` does (a fresh detector state per
sequence, frames upscaled to 1280x720), and prints what the mean hides: the share of frames
with no estimate and why (each reason counted), the offset error's median, 90th percentile and
worst frames, how many frames err by more than 10 cm, and what the detector's confidence says
about that (`calibration`: per confidence band of the valid frames, the share within 10 cm; a
confidence that means something rises with it). The worst frames (invalid ones
first when asked with --invalid) go to --out as PNGs: the labelled ego boundaries in green,
the detector's left / right in red / blue, its reason or offset error written on the frame.

The default split is `tuning`: this is a tool for choosing settings, and settings are never
chosen on the scored sets.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import sys
from pathlib import Path

import cv2
import numpy as np

from lanekeep.detectors.config import DetectorsConfig
from lanekeep.evaluation.dataset import LABEL_HEIGHT, LABEL_ROWS, LABEL_WIDTH, camera_from_vector
from lanekeep.evaluation.detector_eval import BadInput, DetectorRunner, load_detectors_config
from lanekeep.evaluation.eval_sets import CONDITIONS, EvalRecipe, load_set
from lanekeep.evaluation.lane_metrics import EGO_SLOTS, offset_error

TRUTH, LEFT, RIGHT = (0, 220, 0), (0, 0, 255), (255, 80, 0)  # BGR
OTHER_TRUTH, OTHER = (0, 110, 0), (0, 220, 255)  # the other lanes' lines: labelled, reported


def frame_errors(detector: str, condition: str, recipe: EvalRecipe, cache: str | None,
                 config: DetectorsConfig | None = None) -> tuple[list[dict], dict]:
    """One record per frame (sequence, frame, valid, reason, offset error m, prediction) and
    the set's arrays; `config` the detectors' settings (None: the shipped ones)."""
    data, _ = load_set(condition, recipe, cache)
    runner = DetectorRunner(detector, None, config)
    records = []
    for q in range(len(data["frames"])):
        camera = camera_from_vector(data["camera"][q])
        seq = [cv2.resize(f, (LABEL_WIDTH, LABEL_HEIGHT), interpolation=cv2.INTER_LINEAR)
               for f in data["frames"][q]]
        runner.start(camera, seq[0])
        for t, frame in enumerate(seq):
            pred, _ = runner.predict(frame)
            est = pred.estimate
            err = offset_error(est, data["ground_y"][q, t], data["slots"][q, t])
            records.append({"q": q, "t": t, "valid": est.valid, "reason": est.reason,
                            "error_m": err, "confidence": float(est.confidence),
                            "pred": pred, "frame": frame})
    return records, data


def draw(record: dict, data: dict) -> np.ndarray:
    """The frame (BGR) with the labelled boundaries (ego bright green, others dark green) and
    the detector's (its left red, right blue, the other lanes' lines it reports yellow)."""
    out = record["frame"][..., ::-1].copy()
    xs, slots = data["xs"][record["q"], record["t"]], data["slots"][record["q"], record["t"]]
    for k, slot in enumerate(slots):
        if slot >= 0:
            _polyline(out, xs[k], TRUTH if slot in EGO_SLOTS else OTHER_TRUTH)
    est = record["pred"].estimate
    # A classical estimate's lanes are its left and right (those found), then its others.
    colours = [c for c, side in ((LEFT, est.left), (RIGHT, est.right)) if side is not None]
    for k, lane in enumerate(record["pred"].lanes):
        _polyline(out, lane, colours[k] if k < len(colours) else OTHER)
    text = (f"offset error {100 * record['error_m']:.1f} cm at x={est.x_m:.1f} m, "
            f"confidence {est.confidence:.2f}" if est.valid else f"invalid: {est.reason}")
    cv2.putText(out, text, (20, 40), cv2.FONT_HERSHEY_SIMPLEX, 0.9, (255, 255, 255), 2)
    return out


def _polyline(image: np.ndarray, xs: np.ndarray, colour: tuple[int, int, int]) -> None:
    ok = np.isfinite(xs) & (xs >= 0)
    pts = np.stack([xs[ok], LABEL_ROWS[ok]], 1).round().astype(np.int32)
    if len(pts) > 1:
        cv2.polylines(image, [pts], False, colour, 3)


CALIBRATION_BANDS = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0001)  # confidence bands, the last holds 1
CALIBRATION_OK_M = 0.10  # "right" for the calibration table: the ego offset within 10 cm


def calibration(records: list[dict]) -> list[dict]:
    """Per confidence band of the valid, scored frames: how many, and the share whose offset
    error is within CALIBRATION_OK_M. A confidence the MMAE or a tracker could take at its word
    would give shares that rise with the band (ideally near the band's confidence)."""
    scored = [r for r in records if r["valid"] and np.isfinite(r["error_m"])]
    conf = np.array([r["confidence"] for r in scored], float)
    ok = np.array([r["error_m"] <= CALIBRATION_OK_M for r in scored], bool)
    rows = []
    for lo, hi in zip(CALIBRATION_BANDS[:-1], CALIBRATION_BANDS[1:], strict=True):
        band = (conf >= lo) & (conf < hi)
        rows.append({"from": lo, "to": min(hi, 1.0), "frames": int(band.sum()),
                     "share_ok": float(ok[band].mean()) if band.any() else float("nan")})
    return rows


def summary(records: list[dict]) -> str:
    n = len(records)
    invalid = collections.Counter(r["reason"] for r in records if not r["valid"])
    errs = np.array([r["error_m"] for r in records if r["valid"]], float)
    errs = errs[np.isfinite(errs)]
    lines = [f"frames {n}, valid {n - sum(invalid.values())} "
             f"({(n - sum(invalid.values())) / max(n, 1):.0%})"]
    for reason, count in invalid.most_common():
        lines.append(f"  invalid {count:3d}: {reason}")
    if len(errs):
        lines.append(f"offset error cm: mean {100 * errs.mean():.1f}, median "
                     f"{100 * np.median(errs):.1f}, p90 {100 * np.quantile(errs, 0.9):.1f}, "
                     f"max {100 * errs.max():.1f}; > 10 cm on {np.mean(errs > 0.1):.0%}, "
                     f"> 5 cm on {np.mean(errs > 0.05):.0%}")
        bands = [f"{b['from']:.1f}-{b['to']:.1f}: {b['frames']} frames, "
                 + (f"{b['share_ok']:.0%} within {100 * CALIBRATION_OK_M:.0f} cm"
                    if b["frames"] else "-") for b in calibration(records)]
        lines.append("confidence band -> share right: " + "; ".join(bands))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--detector", default="hough")
    parser.add_argument("--condition", default="clear", choices=CONDITIONS)
    parser.add_argument("--split", default="tuning", choices=("tuning", "test"))
    parser.add_argument("--worst", type=int, default=8, help="overlays of the N worst frames")
    parser.add_argument("--invalid", action="store_true",
                        help="overlays of invalid frames first, then the worst valid ones")
    parser.add_argument("--quick", action="store_true",
                        help="the one-world set of `lanekeep eval --quick`")
    parser.add_argument("--out", default="out/classical_errors")
    parser.add_argument("--cache", default="out/eval_cache")
    parser.add_argument("--detectors-config", metavar="FILE", default=None,
                        help="a detectors TOML file to run with instead of the shipped "
                             "settings (as `lanekeep eval --detectors-config`)")
    args = parser.parse_args(argv)
    try:
        config = load_detectors_config(args.detectors_config)
    except BadInput as err:
        print(f"classical_errors: {err}", file=sys.stderr)
        return 2
    recipe = (dataclasses.replace(EvalRecipe.quick(), split=args.split) if args.quick
              else EvalRecipe(split=args.split))
    records, data = frame_errors(args.detector, args.condition, recipe, args.cache or None,
                                 config)
    print(f"{args.detector} on {args.split} {args.condition}:")
    print(summary(records))
    if args.worst > 0:
        def badness(r: dict) -> float:
            if not r["valid"]:
                return np.inf if args.invalid else -1.0
            return r["error_m"] if np.isfinite(r["error_m"]) else -1.0
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        for r in sorted(records, key=badness, reverse=True)[:args.worst]:
            path = out / f"{args.detector}_{args.condition}_{r['q']:03d}_{r['t']}.png"
            cv2.imwrite(str(path), draw(r, data))
            print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
