"""Train the row-anchor rear observer (detectors/rowanchor_model.py, #58) on rear frames, on a
CPU, from scratch; or score given weights on a split (`--evaluate test`).

    python tools/make_dataset.py --out /work/data/observer58 --seed 58 --cameras rear \\
        --train 300 --val 24 --test 24 --sequences-per-world 16 --frames 1 --workers 1
    python tools/train_rowanchor.py --data /work/data/observer58 \\
        --out detectors/weights/rowanchor.pt --checkpoint /work/data/rowanchor.ckpt.pt \\
        --epochs 20 --seed 58 --threads 1
    python tools/train_rowanchor.py --data /work/data/observer58 --evaluate test \\
        --out detectors/weights/rowanchor.pt

Independence: its data are rendered with recipe seed 58 (LaneNet's with seed 0), so no world,
place or image is shared; its initial weights, shuffling and augmentation draw from `--seed`
(58 by default). Only rear frames are used (`is_rear`), whatever the dataset holds.

`--seen-only` labels a point "absent" where no paint of its own boundary lies beside it (the
dataset's paint ids: dash gaps, vehicles over a line), so the network reports only what it
sees; without it the network is taught to place a line across its gaps, which it does from
the texture around (#58). In the loop's rear frames a dashed line then often has too few
painted anchor rows for the lane fit (docs/observer.md, "The bias is the gap reads").

Seeded: the same data and arguments give the same weights on the same machine. Each epoch goes
once over the training frames, each mirrored left-right with probability 0.5 (lanes swap
sides) and given a random exposure, contrast, tint, blur and noise. After every epoch the
validation split is scored and the best epoch's weights are kept (float16, < 1 MB):

  point accuracy: of the labelled anchor points (lane, anchor row), the share the network
  calls present with x within 20 px of the label at 1280x720 (TuSimple's tolerance), over
  the ego pair (`ego`) and over all four lanes (`all`); presence precision and recall.

`--evaluate SPLIT` also runs the detector (the shared ground fit) on every frame of the split
with that sequence's own camera and reports the ego lane's offset error at the rear window's
look-ahead (4 m behind the car) against the labels' ground truth, in centimetres (and which
frames are off by more than FAR_CM, and the RMSE of the others);
and the network's lean into the ego lane on painted rows and across dash gaps
(`lean_into_lane`, all cameras and the wide ones like the loop's); `--baseline lanenet` the
same offset errors for today's reference on the same frames (LaneNet never saw
these worlds either: its data are seed 0's).

A JSON-lines log goes beside the weights (`.log.jsonl`): a first line with the command, seed,
recipe and data, one line per epoch, a last line with the chosen epoch. After every epoch the
whole training state goes to `--checkpoint`; `--resume` goes on from there (the same
arguments give the same weights either way).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import asdict
from pathlib import Path
from typing import NoReturn

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import numpy as np
import torch
from torch.nn import functional as F  # noqa: N812 - the usual torch alias

from lanekeep.detectors.rowanchor import (
    RowAnchorDetector,
    WeightsError,
    load_weights,
    save_weights,
)
from lanekeep.detectors.rowanchor_model import (
    RowAnchorConfig,
    RowAnchorNet,
    anchor_rows,
    bin_to_x,
    decode,
    mirror_targets,
    rowanchor_loss,
    targets,
)
from lanekeep.evaluation.dataset import (
    LABEL_HEIGHT,
    LABEL_ROWS,
    LABEL_WIDTH,
    camera_from_vector,
    load_split,
    read_recipe,
)
from lanekeep.scoring.metrics import ADE_POINTS_M

TOLERANCE_PX = 20.0  # at 1280x720, as TuSimple counts a point
FAR_CM = 30.0  # an offset error beyond this is a wrong lane or a failed fit, not noise
WIDE_HFOV_DEG = 145.0  # "wide" rear cameras: the loop's is 150 deg
LEAN_OUTLIER_PX = 40.0  # a point this far off is a wrong line, not a lean
PAINT_NEAR_PX = 3  # stored pixels (320 wide) either side of a label that count as "on paint"


def fail(why: str) -> NoReturn:
    """One line on stderr and exit 2, as every lanekeep command answers bad input."""
    print(f"train_rowanchor: error: {why}", file=sys.stderr)
    raise SystemExit(2)


def rear_frames(root: Path, split: str, paint: bool = False) -> dict[str, np.ndarray]:
    """The rear frames of a split, one per stored frame: frames (N, H, W, 3), xs, slots,
    ground_y, camera (N, ...); with `paint` also the paint ids (N, H, W)."""
    data = load_split(root, split)
    rear = np.flatnonzero(data["is_rear"])
    t = data["frames"].shape[1]
    out = {k: data[k][rear].reshape(len(rear) * t, *data[k].shape[2:])
           for k in ("frames", "xs", "slots", "ground_y") + (("paint",) if paint else ())}
    out["camera"] = np.repeat(data["camera"][rear], t, axis=0)
    out["tag"] = np.repeat(data["tag"][rear], t, axis=0)
    return out


def targets_of(data: dict, config: RowAnchorConfig, seen_only: bool = False
               ) -> tuple[np.ndarray, np.ndarray]:
    """Class (N, lanes, anchors) and position (N, lanes, anchors) of every frame; with
    `seen_only` a point with no paint of its boundary beside it (a dash gap, an occluder) is
    "absent", so that the network reports only what it sees (#58: across a gap it leant into
    the lane from the texture around)."""
    pairs = [targets(xs, LABEL_ROWS, slots, LABEL_WIDTH, LABEL_HEIGHT, config)
             for xs, slots in zip(data["xs"], data["slots"], strict=True)]
    cls, pos = np.stack([p[0] for p in pairs]), np.stack([p[1] for p in pairs])
    if seen_only:
        unseen = np.isfinite(pos) & ~on_paint(data, config.lanes, config.anchors)
        cls[unseen], pos[unseen] = config.bins, np.nan
    return cls, pos


def on_paint(data: dict, lanes: int, anchors: int) -> np.ndarray:
    """(N, lanes, anchors) bool: the boundary's own paint lies within a row and
    PAINT_NEAR_PX stored pixels of its label at that anchor (the dataset's paint ids: 1 +
    the boundary's index)."""
    paint = data["paint"]
    height, width = paint.shape[1:]
    rows = anchor_rows(LABEL_HEIGHT, anchors)
    rs = np.round((rows + 0.5) * height / LABEL_HEIGHT - 0.5).astype(int)
    out = np.zeros((len(paint), lanes, anchors), bool)
    for i in range(len(paint)):
        for b, slot in enumerate(data["slots"][i]):
            if not 0 <= slot < lanes:
                continue
            at = np.interp(rows, LABEL_ROWS, data["xs"][i, b], left=np.nan, right=np.nan)
            for a in np.flatnonzero(np.isfinite(at)):
                c = int((at[a] + 0.5) * width / LABEL_WIDTH - 0.5)
                near = paint[i, max(rs[a] - 1, 0):rs[a] + 2,
                             max(c - PAINT_NEAR_PX, 0):c + PAINT_NEAR_PX + 1]
                out[i, slot, a] = bool((near == b + 1).any())
    return out


def augment(frames: torch.Tensor, gen: torch.Generator) -> torch.Tensor:
    """uint8 (B, 3, H, W) -> uint8 with a random exposure, contrast, tint, blur and noise per
    frame: the loop's rear camera is none of the dataset's cameras exactly."""
    x = frames.float()
    b = x.shape[0]

    def u(lo: float, hi: float, *shape: int) -> torch.Tensor:
        return lo + (hi - lo) * torch.rand(b, *shape, generator=gen)

    mean = x.mean(dim=(1, 2, 3), keepdim=True)
    x = (x - mean) * u(0.6, 1.4, 1, 1, 1) + mean
    x = x * u(0.5, 1.6, 1, 1, 1) * u(0.9, 1.1, 3, 1, 1)
    blur = torch.rand(b, generator=gen) < 0.3
    if blur.any():
        k = torch.tensor([1.0, 2.0, 1.0]) / 4.0
        kernel = (k[:, None] * k[None, :]).expand(3, 1, 3, 3)
        x[blur] = F.conv2d(F.pad(x[blur], (1, 1, 1, 1), mode="replicate"), kernel, groups=3)
    x = x + u(0.0, 8.0, 1, 1, 1) * torch.randn(x.shape, generator=gen)
    return x.clamp(0.0, 255.0).round().to(torch.uint8)


def point_scores(logits: torch.Tensor, cls: np.ndarray, pos: np.ndarray,
                 bins: int) -> dict[str, float]:
    """Point accuracy (ego pair, all lanes) within TOLERANCE_PX, presence precision/recall."""
    got, presence = decode(logits)
    present = cls < bins
    called = presence > 0.5
    err = np.abs(bin_to_x(got, LABEL_WIDTH, bins) - bin_to_x(np.nan_to_num(pos), LABEL_WIDTH,
                                                              bins))
    hit = present & called & (err < TOLERANCE_PX)
    ego = np.zeros_like(present)
    ego[:, :2] = True
    return {"point_acc_ego": float(hit[ego & present].mean()),
            "point_acc_all": float(hit[present].mean()),
            "presence_precision": float((called & present).sum() / max(called.sum(), 1)),
            "presence_recall": float((called & present).sum() / max(present.sum(), 1)),
            "median_err_px_ego": float(np.median(err[ego & present & called]))
            if (ego & present & called).any() else float("nan")}


def dash_gap_lean(logits: torch.Tensor, data: dict, bins: int) -> dict[str, dict]:
    """The network's signed point error on the ego pair, + = into the ego lane (px at
    1280x720), split by whether the labelled point lies on its boundary's paint ("dash") or
    between dashes ("gap"), over all cameras and over wide ones (horizontal field of view
    >= WIDE_HFOV_DEG, the loop's rear camera is 150 deg). Lower half of the frame only (the
    ground the detector fits), points the network calls present, within LEAN_OUTLIER_PX.

    Why: #58's observer leant about 6 px into the lane across the dash gaps of the loop's
    rear frames (docs/observer.md), which biased its offset by 1-3 cm towards the solid line."""
    got, presence = decode(logits)
    x_got = bin_to_x(got, LABEL_WIDTH, bins)
    rows = anchor_rows(LABEL_HEIGHT, got.shape[2])
    painted = on_paint(data, got.shape[1], got.shape[2])
    hfov = np.degrees(2.0 * np.arctan(0.5 * LABEL_WIDTH / data["camera"][:, 0]))
    errors: dict[tuple[str, str], list[float]] = {}
    for i in range(len(painted)):
        for b, slot in enumerate(data["slots"][i]):
            if slot not in (0, 1):
                continue
            at = np.interp(rows, LABEL_ROWS, data["xs"][i, b], left=np.nan, right=np.nan)
            inward = 1.0 if slot == 0 else -1.0  # ego-left: + x is into the lane
            for a in np.flatnonzero(np.isfinite(at) & (rows >= LABEL_HEIGHT / 2)
                                    & (presence[i, slot] > 0.5)):
                e = float(x_got[i, slot, a] - at[a])
                if abs(e) > LEAN_OUTLIER_PX:
                    continue
                kind = "dash" if painted[i, slot, a] else "gap"
                for cams in ("all", "wide") if hfov[i] >= WIDE_HFOV_DEG else ("all",):
                    errors.setdefault((cams, kind), []).append(inward * e)
    out: dict[str, dict] = {}
    for (cams, kind), v in sorted(errors.items()):
        a = np.asarray(v)
        out[f"{cams}_{kind}"] = {"points": len(a), "mean_px": round(float(a.mean()), 2),
                                 "sem_px": round(float(a.std() / math.sqrt(len(a))), 2)}
    return out


def run_network(model: RowAnchorNet, frames: np.ndarray, batch: int = 64) -> torch.Tensor:
    model.eval()
    outs = []
    with torch.inference_mode():
        for s in range(0, len(frames), batch):
            outs.append(model(torch.from_numpy(frames[s:s + batch]).permute(0, 3, 1, 2)))
    return torch.cat(outs)


def evaluate(model: RowAnchorNet, data: dict, cls: np.ndarray, pos: np.ndarray,
             logits: torch.Tensor | None = None) -> dict[str, float]:
    logits = run_network(model, data["frames"]) if logits is None else logits
    loss, _ = rowanchor_loss(logits, torch.from_numpy(cls), torch.from_numpy(pos))
    return {"loss": float(loss), **point_scores(logits, cls, pos, model.config.bins)}


def true_offset(ground_y: np.ndarray, slots: np.ndarray, at_m: float) -> float | None:
    """The car's true offset from the ego lane's centre at `at_m` behind it (NaN-free labels
    of both ego boundaries needed): + = car left of centre."""
    k = ADE_POINTS_M.index(at_m)
    sides = [np.flatnonzero(slots == s) for s in (0, 1)]
    if any(len(s) != 1 for s in sides):
        return None
    y = [float(ground_y[s[0], k]) for s in sides]
    if not all(math.isfinite(v) for v in y):
        return None
    return -(y[0] + y[1]) / 2.0


def offset_errors(weights: str | None, data: dict, name: str = "rowanchor",
                  config_file: str = "") -> dict:
    """Detector `name` (here: network + shared ground fit) on every frame with its own camera:
    the offset error at the look-ahead, in cm, where the labels have the ego pair. Another
    registered detector (`--baseline lanenet`: the reference today) is made with its own
    default weights, fresh for each frame (a LaneNet keeps no state across these frames)."""
    from lanekeep.detectors.config import load_config
    from lanekeep.detectors.registry import make_detector

    config = load_config(config_file) if config_file else None
    errors, signed, valid, labelled, ms, by_tag, far = [], [], 0, 0, [], {}, []
    for i in range(len(data["frames"])):
        camera = camera_from_vector(data["camera"][i], "rear")
        detector = make_detector(name, camera, config, weights=weights)
        truth = true_offset(data["ground_y"][i], data["slots"][i], abs(detector.x_ref))
        if truth is None:
            continue
        labelled += 1
        t0 = time.perf_counter()
        est = detector.detect(data["frames"][i])
        ms.append(1000.0 * (time.perf_counter() - t0))
        if est.valid:
            valid += 1
            signed.append(100.0 * (est.offset_m - truth))
            e = abs(signed[-1])
            errors.append(e)
            if e > FAR_CM:
                far.append(i)
            by_tag.setdefault(str(data["tag"][i]), []).append(e)
    e = np.array(errors)
    return {"frames_with_ego_pair": labelled, "valid": valid,
            "valid_share": valid / max(labelled, 1),
            "offset_err_cm_median": float(np.median(e)) if len(e) else None,
            "offset_err_cm_rmse": float(np.sqrt(np.mean(e ** 2))) if len(e) else None,
            "offset_err_cm_p90": float(np.percentile(e, 90)) if len(e) else None,
            "share_within_10cm": float((e < 10).sum() / max(labelled, 1)),
            "rmse_cm_under_far": float(np.sqrt(np.mean(e[e <= FAR_CM] ** 2))) if len(e) else None,
            "far_frames": far,
            "bias_cm_under_far": float(np.mean(np.array(signed)[e <= FAR_CM])) if len(e) else None,
            "detect_ms_median": float(np.median(ms)) if ms else None,
            "median_err_cm_by_tag": {k: round(float(np.median(v)), 1)
                                     for k, v in sorted(by_tag.items())}}


def timing(weights: str, data: dict, repeats: int) -> dict:
    """Median ms of one frame at 1280x720 (a stored frame scaled up, as the loop's camera
    gives it): the area resize to 320x176, the network (as `detect` runs it: one thread, on
    the portable convolution path) and the whole `detect` (resize, network, ground fit)."""
    import cv2

    from lanekeep.core.reproducibility import portable_torch

    camera = camera_from_vector(data["camera"][0], "rear")
    detector = RowAnchorDetector(camera, weights=weights)
    cfg = detector.model.config
    frame = cv2.resize(data["frames"][0], (LABEL_WIDTH, LABEL_HEIGHT),
                       interpolation=cv2.INTER_LINEAR)
    times: dict[str, list[float]] = {"resize": [], "network": [], "detect": []}
    for _ in range(repeats):
        t0 = time.perf_counter()
        small = cv2.resize(frame, (cfg.width, cfg.height), interpolation=cv2.INTER_AREA)
        t1 = time.perf_counter()
        with torch.inference_mode(), portable_torch():
            detector.model(torch.from_numpy(small.transpose(2, 0, 1).copy())[None])
        t2 = time.perf_counter()
        detector.detect(frame)
        t3 = time.perf_counter()
        for k, a, b in (("resize", t0, t1), ("network", t1, t2), ("detect", t2, t3)):
            times[k].append(1000.0 * (b - a))
    return {**{f"{k}_ms_median": round(float(np.median(v)), 2) for k, v in times.items()},
            "repeats": repeats, "threads": torch.get_num_threads()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", required=True, help="dataset folder (tools/make_dataset.py)")
    parser.add_argument("--out", default="detectors/weights/rowanchor.pt")
    parser.add_argument("--checkpoint", default="",
                        help="training state file (default: OUT with .ckpt before its suffix)")
    parser.add_argument("--epochs", type=int, default=20)
    parser.add_argument("--batch", type=int, default=32, help="frames per step")
    parser.add_argument("--lr", type=float, default=4e-3)
    parser.add_argument("--seed", type=int, default=58)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--limit", type=int, default=0, help="use only N training frames")
    parser.add_argument("--resume", action="store_true", help="go on from --checkpoint")
    parser.add_argument("--seen-only", action="store_true",
                        help="label a point absent where its boundary has no paint beside it "
                             "(dash gaps, occluders): the network reports only what it sees")
    parser.add_argument("--evaluate", default="", metavar="SPLIT",
                        help="score --out on SPLIT (val or test) and print JSON; no training")
    parser.add_argument("--baseline", default="", metavar="NAME",
                        help="with --evaluate: also the offset errors of detector NAME on the "
                             "same frames (e.g. lanenet, the reference today)")
    parser.add_argument("--detectors-config", default="", metavar="FILE",
                        help="with --evaluate: a detectors TOML (e.g. [rowanchor] mirror = false)")
    parser.add_argument("--time", type=int, default=0, metavar="N",
                        help="with --evaluate: also time N frames at 1280x720")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    root = Path(args.data)
    command = " ".join(["python tools/train_rowanchor.py", *(argv or sys.argv[1:])])
    if args.evaluate:
        try:
            model = load_weights(args.out)
        except WeightsError as exc:
            fail(str(exc))
        data = rear_frames(root, args.evaluate, paint=True)
        cls, pos = targets_of(data, model.config, args.seen_only)
        logits = run_network(model, data["frames"])
        result = {"split": args.evaluate, "frames": len(data["frames"]), "command": command,
                  "weights_bytes": Path(args.out).stat().st_size,
                  **evaluate(model, data, cls, pos, logits),
                  "lean_into_lane": dash_gap_lean(logits, data, model.config.bins),
                  **offset_errors(args.out, data, config_file=args.detectors_config)}
        if args.baseline:
            base = offset_errors(None, data, args.baseline, args.detectors_config)
            result[f"baseline_{args.baseline}"] = base
            result["far_frames_both"] = sorted(set(result["far_frames"]) & set(base["far_frames"]))
        if args.time:
            result["timing_1280x720"] = timing(args.out, data, args.time)
        print(json.dumps(result, indent=1))
        return 0
    return train(args, root, command)


def train(args: argparse.Namespace, root: Path, command: str) -> int:
    from tqdm import tqdm

    torch.manual_seed(args.seed)
    start = time.perf_counter()
    recipe, worlds = read_recipe(root)
    config = RowAnchorConfig()
    data = rear_frames(root, "train", paint=args.seen_only)
    val = rear_frames(root, "val", paint=args.seen_only)
    if args.limit:
        data = {k: v[:args.limit] for k, v in data.items()}
    cls, pos = targets_of(data, config, args.seen_only)
    mcls, mpos = zip(*[mirror_targets(c, p, config.bins) for c, p in zip(cls, pos, strict=True)],
                     strict=True)
    mcls, mpos = np.stack(mcls), np.stack(mpos)
    vcls, vpos = targets_of(val, config, args.seen_only)
    data.pop("paint", None)  # only the targets needed it
    n = len(data["frames"])
    print(f"data: {n} rear training frames, {len(val['frames'])} validation; targets in "
          f"{time.perf_counter() - start:.0f} s", file=sys.stderr)

    model = RowAnchorNet(config, seed=args.seed)
    opt = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    steps_per_epoch = math.ceil(n / args.batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=args.lr, pct_start=0.1,
                                                total_steps=args.epochs * steps_per_epoch)
    gen = torch.Generator().manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    log_path = out.with_suffix(".log.jsonl")
    ckpt = Path(args.checkpoint) if args.checkpoint else out.with_name(
        out.stem + ".ckpt" + out.suffix)
    fixed = {k: getattr(args, k) for k in ("data", "out", "epochs", "batch", "lr", "seed",
                                           "limit", "seen_only")}
    best: dict | None = None
    first_epoch = 0
    if args.resume and ckpt.is_file():
        state = torch.load(str(ckpt), map_location="cpu", weights_only=True)
        # checkpoints written before these arguments were kept
        saved = {"seen_only": False, "out": args.out, **state.get("args", {})}
        if saved != fixed:
            changed = sorted(k for k in fixed if saved.get(k) != fixed[k])
            fail(f"--resume with other arguments than the checkpoint's ({', '.join(changed)}): "
                 f"{ckpt}")
        model.load_state_dict(state["model"])
        opt.load_state_dict(state["opt"])
        sched.load_state_dict(state["sched"])
        gen.set_state(state["gen"])
        rng.bit_generator.state = state["rng"]
        best, first_epoch = state["best"], state["epoch"]
        with log_path.open("a") as f:
            f.write(json.dumps({"event": "resume", "after_epoch": first_epoch,
                                "command": command}) + "\n")
        print(f"resumed after epoch {first_epoch} ({ckpt})", file=sys.stderr)
    else:
        head = {"event": "start", "command": command, "seed": args.seed, "data": str(root),
                "recipe": asdict(recipe), "worlds": worlds, "train_frames": n,
                "val_frames": len(val["frames"]), "config": config.to_dict(),
                "parameters": sum(p.numel() for p in model.parameters()),
                "seen_only": args.seen_only,
                "threads": args.threads, "torch": torch.__version__}
        log_path.write_text(json.dumps(head) + "\n")
    for epoch in range(first_epoch, args.epochs):
        model.train()
        order = rng.permutation(n)
        flips = rng.random(n) < 0.5
        sums: dict[str, float] = {}
        t_epoch = time.perf_counter()
        bar = tqdm(range(steps_per_epoch), desc=f"epoch {epoch + 1}/{args.epochs}",
                   unit="step", leave=False, mininterval=30)
        for step in bar:
            idx = order[step * args.batch:(step + 1) * args.batch]
            flip = torch.from_numpy(flips[idx])
            frames = torch.from_numpy(data["frames"][idx]).permute(0, 3, 1, 2)
            frames = torch.where(flip.view(-1, 1, 1, 1), frames.flip(-1), frames)
            c = torch.where(flip.view(-1, 1, 1), torch.from_numpy(mcls[idx]),
                            torch.from_numpy(cls[idx]))
            p = torch.where(flip.view(-1, 1, 1), torch.from_numpy(mpos[idx]),
                            torch.from_numpy(pos[idx]))
            loss, parts = rowanchor_loss(model(augment(frames, gen)), c, p)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 5.0)
            opt.step()
            sched.step()
            for k, v in parts.items():
                sums[k] = sums.get(k, 0.0) + v
        scores = evaluate(model, val, vcls, vpos)
        row = {"epoch": epoch + 1, **{f"train_{k}": v / steps_per_epoch for k, v in sums.items()},
               **{f"val_{k}": v for k, v in scores.items()}, "lr": sched.get_last_lr()[0],
               "epoch_s": round(time.perf_counter() - t_epoch, 1),
               "elapsed_s": round(time.perf_counter() - start, 1)}
        with log_path.open("a") as f:
            f.write(json.dumps(row) + "\n")
        print(f"epoch {epoch + 1}: loss {row['train_ce']:.3f}+{row['train_l1_bins']:.3f} val "
              f"ego {scores['point_acc_ego']:.3f} all {scores['point_acc_all']:.3f} "
              f"({row['epoch_s']:.0f} s)", file=sys.stderr, flush=True)
        score = scores["point_acc_ego"] + 0.5 * scores["point_acc_all"]
        if best is None or score > best["score"]:
            best = {"score": score, **row}
            meta = {"recipe": {"data": str(root), "worlds": worlds, **asdict(recipe)},
                    "command": command, "seed": args.seed, "seen_only": args.seen_only,
                    "chosen": row}
            save_weights(model, out, meta)
        tmp = ckpt.with_suffix(".tmp")
        torch.save({"model": model.state_dict(), "opt": opt.state_dict(),
                    "sched": sched.state_dict(), "gen": gen.get_state(),
                    "rng": rng.bit_generator.state, "best": best, "epoch": epoch + 1,
                    "args": fixed}, str(tmp))
        tmp.replace(ckpt)
    total = time.perf_counter() - start
    if not out.is_file():  # a finished run resumed with nothing left to train and no weights
        fail(f"no weights at {out}: the checkpoint's run had finished and wrote its best epoch "
             "to another --out")
    summary = {"event": "end", "weights": str(out), "wall_s": round(total),
               "best_epoch": best["epoch"], "val_point_acc_ego": best["val_point_acc_ego"],
               "val_point_acc_all": best["val_point_acc_all"],
               "weights_bytes": out.stat().st_size}
    with log_path.open("a") as f:
        f.write(json.dumps(summary) + "\n")
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
