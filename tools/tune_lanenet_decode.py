"""Choose LaneNet's decoding prior on the simulated validation split, never on the test sets.

    python tools/make_dataset.py --out data/lanenet --train 0 --val 24 --test 0   # ~1.5 min
    python tools/tune_lanenet_decode.py --data data/lanenet [--priors 0,0.01,0.005,0.002,0.001]

For each curvature prior (`DecodeSettings.curvature_prior_per_m`, 1/m; 0 = none) the shipped
weights run over every validation sequence (front and rear frames, each sequence from a reset
state, frames upscaled to 1280x720 as `lanekeep eval` does), and the ego lane is scored by
`lanekeep/lane_eval.py`'s rules: ADE / FDE at 4-20 m, offset error, share of valid frames.
Prints one row per prior and the one with the lowest ADE (ties: the weaker prior). Labels are
read only to score. The validation worlds are disjoint from the training worlds and from
`lanekeep eval`'s sets, so the choice is scored afresh there.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

from lanekeep.dataset import LABEL_HEIGHT, LABEL_WIDTH, camera_from_vector, load_split
from lanekeep.detectors.lanenet import LaneNetDetector, LaneNetSettings
from lanekeep.lane_eval import ego_errors, offset_error


def score(data: dict, settings: LaneNetSettings, weights: str | None) -> dict[str, float]:
    """Ego-lane ADE / FDE / offset error (cm) and valid share over a split."""
    errors, offsets, valid = [], [], []
    detectors: dict[bytes, LaneNetDetector] = {}
    for q in range(len(data["frames"])):
        camera = camera_from_vector(data["camera"][q])
        key = camera.K.tobytes() + camera.position_m.tobytes() + camera.rotation.tobytes()
        if key not in detectors:
            detectors[key] = LaneNetDetector(camera, settings=settings, weights=weights)
        det = detectors[key]
        det.reset()
        rear = bool(data["is_rear"][q])
        for t, frame in enumerate(data["frames"][q]):
            big = cv2.resize(frame, (LABEL_WIDTH, LABEL_HEIGHT), interpolation=cv2.INTER_LINEAR)
            est = det.detect(big)
            labels = data["slots"][q, t], data["ground_y"][q, t]
            errors.append(ego_errors(est, labels[1], labels[0], rear))
            offsets.append(offset_error(est, labels[1], labels[0], rear))
            valid.append(est.valid)
    err = np.asarray(errors) * 100.0
    return {"ade_cm": float(np.nanmean(err)), "fde_cm": float(np.nanmean(err[:, :, -1])),
            "median_fde_cm": float(np.nanmedian(err[:, :, -1])),
            "offset_err_cm": float(np.nanmean(offsets) * 100.0), "valid": float(np.mean(valid))}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", required=True, help="dataset folder with a val split")
    parser.add_argument("--priors", default="0,0.01,0.005,0.003,0.002,0.001,0.0005",
                        help="curvature priors to try (1/m, comma-separated; 0 = none)")
    parser.add_argument("--weights", default=None, help="LaneNet weights (default: shipped)")
    args = parser.parse_args(argv)
    data = load_split(Path(args.data), "val")
    rows = []
    for prior in sorted({float(p) for p in args.priors.split(",")}):
        s = score(data, LaneNetSettings(curvature_prior_per_m=prior), args.weights)
        rows.append((prior, s))
        print(f"prior {prior:<7g} ADE {s['ade_cm']:6.1f}  FDE {s['fde_cm']:6.1f} "
              f"(median {s['median_fde_cm']:5.1f})  offset {s['offset_err_cm']:5.1f} cm  "
              f"valid {s['valid']:.2f}", flush=True)
    best = min(rows, key=lambda r: (round(r[1]["ade_cm"], 1), r[0] > 0, -r[0]))
    print(f"lowest ADE: prior {best[0]:g} 1/m ({best[1]['ade_cm']:.1f} cm) over "
          f"{len(data['frames'])} sequences")
    return 0


if __name__ == "__main__":
    sys.exit(main())
