"""Choose LaneNet's decoding priors on the simulated validation split, never on the test sets.

    python tools/make_dataset.py --out data/lanenet --train 0 --val 24 --test 0   # ~1.5 min
    python -m lanekeep.tuning.decode_priors --data data/lanenet

The shipped weights run once over every validation sequence (front and rear frames, each
sequence from a reset state, frames upscaled to 1280x720 as `lanekeep eval` does), on the
sequences as rendered and on a copy with vehicle-sized occluders over 60% of their paint
(`lanekeep/evaluation/eval_sets.occlude`, seeded apart from `lanekeep eval`'s sets). Each
combination of the decoding's priors (`DecodeSettings`: curvature prior and its shape, weight of
points where no paint is seen, std of the ego pair's width about the lane's, power of the
objectness that weighs the ego pair's points, furthest point fitted) then decodes the same
network outputs, and the ego lane is scored by `lanekeep/evaluation/lane_metrics.py`'s rules:
ADE at 4-20 m and the offset error (cm), and the share of valid frames. The choice is the
lowest mean of ADE + offset error over the two copies. Labels are read only to score. The
validation worlds are disjoint from the training worlds and from `lanekeep eval`'s, so the
choice is scored afresh there. tools/tune_lanenet_decode.py runs the same command line
from a clone.
"""

from __future__ import annotations

import argparse
import itertools
import sys
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from lanekeep.detectors.lanenet import LaneNetDetector
from lanekeep.detectors.lanenet_decode import DecodeSettings, ego_estimate, fit_boundaries
from lanekeep.detectors.lanenet_targets import CellGrid
from lanekeep.evaluation.dataset import LABEL_HEIGHT, LABEL_WIDTH, camera_from_vector, load_split
from lanekeep.evaluation.eval_sets import occlude
from lanekeep.evaluation.lane_metrics import ego_errors, offset_error

OCCLUSION_SEED = 0x0CC1  # occluders of the validation copy (lanekeep eval's use their own)


def outputs(data: dict, occlusion: float, weights: str | None) -> list[tuple]:
    """Per frame: (proposals, grid, camera, detector, labels, rear) from one network pass."""
    rng = np.random.default_rng(OCCLUSION_SEED)
    out, detectors = [], {}
    for q in range(len(data["frames"])):
        camera = camera_from_vector(data["camera"][q])
        key = camera.K.tobytes() + camera.position_m.tobytes() + camera.rotation.tobytes()
        if key not in detectors:
            detectors[key] = LaneNetDetector(camera, weights=weights)
        det = detectors[key]
        det.reset()
        frames = data["frames"][q]
        if occlusion > 0:
            height = frames.shape[1]
            horizon = (camera.horizon_row() + 0.5) * height / camera.height - 0.5
            frames, _ = occlude(frames, data["paint"][q], horizon, camera.height_m, occlusion,
                                rng)
        for t, frame in enumerate(frames):
            big = cv2.resize(frame, (LABEL_WIDTH, LABEL_HEIGHT), interpolation=cv2.INTER_LINEAR)
            decoded = det.infer(big)
            rows, cols = det.model.config.grid
            out.append((decoded.proposals, CellGrid(LABEL_WIDTH, LABEL_HEIGHT, rows, cols),
                        camera, det, (data["slots"][q, t], data["ground_y"][q, t]),
                        bool(data["is_rear"][q])))
    return out


def score(frames: list[tuple], settings: DecodeSettings) -> dict[str, float]:
    """Ego-lane ADE / FDE / offset error (cm) and valid share of decoded frames."""
    errors, offsets, valid = [], [], []
    for props, grid, camera, det, (slots, ground_y), rear in frames:
        lane = det.config.lane
        est = ego_estimate(fit_boundaries(props, grid, settings, camera), camera, det.x_ref,
                           lane.lane_width_m, lane.width_tolerance_m, settings)
        errors.append(ego_errors(est, ground_y, slots, rear))
        offsets.append(offset_error(est, ground_y, slots, rear))
        valid.append(est.valid)
    err = np.asarray(errors) * 100.0
    return {"ade_cm": float(np.nanmean(err)), "fde_cm": float(np.nanmean(err[:, :, -1])),
            "offset_err_cm": float(np.nanmean(offsets) * 100.0), "valid": float(np.mean(valid))}


def _floats(text: str) -> list[float]:
    return sorted({float(v) for v in text.split(",")})


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", required=True, help="dataset folder with a val split")
    parser.add_argument("--curvature", default="0,0.005,0.003,0.002,0.001",
                        help="curvature priors (1/m; 0 = none)")
    parser.add_argument("--unseen", default="1,0.5,0.3,0.1",
                        help="weights of points with no paint seen (1 = paint ignored)")
    parser.add_argument("--width-std", default="0,0.5,0.3,0.15",
                        help="std of the ego pair's width about the lane's (m; 0 = none)")
    parser.add_argument("--score-power", default="0,2",
                        help="powers of a point's objectness in the ego pair's weights (0 = "
                             "objectness ignored)")
    parser.add_argument("--prior-shape", default="gaussian,cauchy",
                        help="shapes of the curvature prior in the ego pair's fit")
    parser.add_argument("--max-range", default="150",
                        help="furthest ground points fitted (m ahead of the camera)")
    parser.add_argument("--occlusion", type=float, default=0.6,
                        help="share of paint hidden in the occluded copy")
    parser.add_argument("--weights", default=None, help="LaneNet weights (default: shipped)")
    args = parser.parse_args(argv)
    try:  # every combination is checked before the network runs, so a typo costs nothing
        grid = [replace(DecodeSettings(), curvature_prior_per_m=curvature,
                        curvature_prior_shape=shape, unseen_weight=unseen,
                        width_std_m=width_std, score_power=power, max_range_m=max_range)
                for curvature, shape, unseen, width_std, power, max_range in itertools.product(
                    _floats(args.curvature), args.prior_shape.split(","), _floats(args.unseen),
                    _floats(args.width_std), _floats(args.score_power),
                    _floats(args.max_range))]
    except ValueError as err:
        parser.error(str(err))
    data = load_split(Path(args.data), "val")
    copies = {"as rendered": outputs(data, 0.0, args.weights),
              f"occluded {args.occlusion:.0%}": outputs(data, args.occlusion, args.weights)}
    rows = []
    for settings in grid:
        curvature, shape = settings.curvature_prior_per_m, settings.curvature_prior_shape
        unseen, width_std = settings.unseen_weight, settings.width_std_m
        power, max_range = settings.score_power, settings.max_range_m
        scores = {name: score(frames, settings) for name, frames in copies.items()}
        objective = float(np.mean([s["ade_cm"] + s["offset_err_cm"] for s in scores.values()]))
        rows.append((objective, curvature, unseen, width_std, power, max_range, shape))
        print(f"curvature {curvature:<6g} {shape:<8} unseen {unseen:<4g} "
              f"width_std {width_std:<5g} score_power {power:<3g} max_range {max_range:<4g} "
              + "  ".join(f"{name}: ADE {s['ade_cm']:5.1f} offset {s['offset_err_cm']:5.1f} "
                          f"valid {s['valid']:.2f}" for name, s in scores.items())
              + f"  objective {objective:.2f}", flush=True)
    best = min(rows)
    print(f"chosen: curvature_prior_per_m {best[1]:g}, unseen_weight {best[2]:g}, "
          f"width_std_m {best[3]:g}, score_power {best[4]:g}, max_range_m {best[5]:g}, "
          f"curvature_prior_shape {best[6]} (objective {best[0]:.2f}) over "
          f"{len(data['frames'])} validation sequences")
    return 0


if __name__ == "__main__":
    sys.exit(main())
