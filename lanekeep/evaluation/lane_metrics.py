"""Lane metrics of `lanekeep eval`: AP, IoU / F1, ADE / FDE, offset error and ms per frame.

Every detector is scored by this code on the same frames. Ground truth (the dataset's labels,
made from the road geometry: lanekeep/evaluation/dataset.py) is used here only, never shown to a
detector.
All image quantities are at 1280x720, the frame our cameras give and the labels are in.

AP (proposal average precision at IoU 0.5). Ground truth: every labelled boundary (all slots,
continuous through dash gaps, as TuSimple labels lanes) cut at the row bands of LaneNet's output
grid laid over the frame (`CellGrid` with LaneNetConfig's rows x cols): one box per boundary per
band it spans, one cell wide and one band tall, centred on the label's x at the band's centre
row. A detector's proposals are boxes with a confidence. They are ranked by confidence over all
frames; a proposal takes the unmatched ground-truth box of its frame that it overlaps most if
that IoU is >= 0.5 (a true positive), else it is a false positive; AP is the area under the
precision-recall curve made monotone (VOC's all-point interpolation). LaneNet's proposals are
all its cells with objectness above 0.05 (`detectors.lanenet.CANDIDATE_SCORE`), as a detector's
AP is taken over all its confidences; its boundaries are fitted to those above 0.5. Equal boxes
in one band overlap by IoU >= 0.5 when |dx| <= cell width / 3 (about 10.7 px). Classical
detectors make no proposals, so theirs are made from their fitted boundaries (the ego pair and
the other lanes' lines they report, `LaneEstimate.others`): each boundary
projected into the image over the range `lanekeep detect` draws it (camera x + 1 m to 1.3x the
far edge of its ground window), one cell-sized box per band it crosses, every box scored by the
estimate's confidence. Ties in confidence keep frame order.

AP-ego: the same, against the boxes of the labelled ego-left / ego-right boundaries only (every
other proposal is a false positive there). A model that reports only the ego lane (the paper's
two classical models did until 2026-11-30; a plug-in may) cannot recall the other boundaries'
boxes, so its AP is bounded by `ego_box_share` (the ego boundaries' share of all boxes: about
0.72 on the clear set, 2026-11-29); AP-ego is its like-for-like figure. A model that reports
every lane (LaneNet; the classical models with `LaneEstimate.others`) is scored on all of them
by AP; its AP-ego counts its other lanes against it.

IoU / F1 (CULane's lane IoU). Each boundary, predicted or labelled, is drawn as a 30 px wide
polyline through its x at the label rows (every 5 px) on a 1280x720 mask. Predicted and labelled
boundaries are paired by the Hungarian assignment that maximises the summed mask IoU (slots are
ignored, so a detector is not penalised for naming a boundary differently). `iou` is the mean over
labelled boundaries of their partner's IoU, 0 for a boundary left without one: a missed lane
counts. `iou_ego` is the same over the labelled ego-left / ego-right boundaries only. A pair with
IoU >= 0.5 is a true positive; F1 = 2 TP / (2 TP + FP + FN) over all boundaries.

ADE / FDE (cm) of the ego boundaries: the lateral error |y_pred(x) - y_true(x)| of the estimate's
left / right polynomials y(x) (vehicle frame) against the labelled ego-left / ego-right
boundaries' ground y at ADE_POINTS_M (4..20 m; behind the car for a rear camera), where labelled.
ADE is the mean over points, sides and frames with a valid estimate; FDE the same at 20 m. The
errors are over valid estimates only, so `valid` (the share of frames with one) is reported too.

Offset error (cm): |estimate.offset_m - true offset| at the estimate's look-ahead x_m; the true
offset is -(y_left + y_right) / 2 of the labelled ego boundaries, interpolated to x_m.

ms: wall time of the detector's call on one 1280x720 frame. The test sets are rendered and stored
at 640x360 (what the classical detectors shrink a frame to anyway, and 4x the network's working
size), so each is upscaled to 1280x720 first, outside the timer, and every detector sees that
upscaled frame (softer than a native 1280x720 render).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.lanenet_model import LaneNetConfig
from lanekeep.detectors.lanenet_targets import CellGrid, boundary_crossings
from lanekeep.evaluation.dataset import LABEL_HEIGHT, LABEL_ROWS, LABEL_WIDTH
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.lane_poly import LanePoly
from lanekeep.scoring.metrics import ADE_POINTS_M

BOX_IOU = 0.5  # a proposal is a true positive at this box IoU
LANE_IOU = 0.5  # a lane pair is a true positive at this mask IoU
LANE_WIDTH_PX = 30  # CULane's lane width at 1280 px (it uses 30 at 1640; we keep the figure)
EGO_SLOTS = (0, 1)  # ego-left, ego-right (detectors/lanenet_targets.SLOTS)


def eval_grid() -> CellGrid:
    """LaneNet's output grid over the 1280x720 frame: the bands AP cuts boundaries at."""
    rows, cols = LaneNetConfig().grid
    return CellGrid(LABEL_WIDTH, LABEL_HEIGHT, rows, cols)


def cell_boxes(xs: np.ndarray, ys: np.ndarray, grid: CellGrid) -> np.ndarray:
    """Cell-sized boxes (N, 4) x0 y0 x1 y1 centred on the points (xs, ys)."""
    hw, hh = grid.cell_w / 2.0, grid.cell_h / 2.0
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    return np.stack([xs - hw, ys - hh, xs + hw, ys + hh], -1).reshape(-1, 4)


def gt_boxes(xs: np.ndarray, slots: np.ndarray, grid: CellGrid) -> np.ndarray:
    """Ground-truth boxes of one frame's labels: x (B, len(LABEL_ROWS)) and slots (B,)."""
    boxes = [np.zeros((0, 4))]
    for x, slot in zip(xs, slots, strict=True):
        ok = np.isfinite(x)
        if slot < 0 or ok.sum() < 2:
            continue
        rows, bx = boundary_crossings(np.stack([x[ok], LABEL_ROWS[ok]], 1), grid)
        boxes.append(cell_boxes(bx, grid.row_centres()[rows], grid))
    return np.concatenate(boxes)


def box_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU matrix (N, M) of boxes x0 y0 x1 y1."""
    a, b = np.asarray(a, float)[:, None], np.asarray(b, float)[None]
    w = np.clip(np.minimum(a[..., 2], b[..., 2]) - np.maximum(a[..., 0], b[..., 0]), 0, None)
    h = np.clip(np.minimum(a[..., 3], b[..., 3]) - np.maximum(a[..., 1], b[..., 1]), 0, None)
    inter = w * h
    area = lambda r: (r[..., 2] - r[..., 0]) * (r[..., 3] - r[..., 1])  # noqa: E731
    return inter / np.maximum(area(a) + area(b) - inter, 1e-9)


def match_boxes(boxes: np.ndarray, scores: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """True-positive flags of one frame's proposals (in their order), greedy by score."""
    tp = np.zeros(len(boxes), bool)
    if len(boxes) == 0 or len(gt) == 0:
        return tp
    iou = box_iou(boxes, gt)
    taken = np.zeros(len(gt), bool)
    for i in np.argsort(-np.asarray(scores), kind="stable"):
        cand = np.where(taken, -1.0, iou[i])
        j = int(np.argmax(cand))
        if cand[j] >= BOX_IOU:
            tp[i], taken[j] = True, True
    return tp


def average_precision(scores: np.ndarray, tp: np.ndarray, n_gt: int) -> float:
    """VOC all-point interpolated AP; NaN with no ground truth, 0 with no proposals."""
    if n_gt == 0:
        return float("nan")
    if len(scores) == 0:
        return 0.0
    order = np.argsort(-np.asarray(scores), kind="stable")
    hit = np.asarray(tp, float)[order]
    ctp, cfp = np.cumsum(hit), np.cumsum(1.0 - hit)
    recall = np.concatenate([[0.0], ctp / n_gt, [1.0]])
    precision = np.concatenate([[0.0], ctp / (ctp + cfp), [0.0]])
    precision = np.maximum.accumulate(precision[::-1])[::-1]  # the envelope
    i = np.flatnonzero(recall[1:] != recall[:-1])
    return float(np.sum((recall[i + 1] - recall[i]) * precision[i + 1]))


def lane_mask(x_at_rows: np.ndarray, rows: np.ndarray = LABEL_ROWS) -> np.ndarray:
    """A boundary drawn LANE_WIDTH_PX wide through its finite points, as a bool 720x1280 mask."""
    mask = np.zeros((LABEL_HEIGHT, LABEL_WIDTH), np.uint8)
    ok = np.isfinite(x_at_rows)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
    for start, stop in zip(edges[::2], edges[1::2], strict=True):  # each run of finite x
        pts = np.stack([x_at_rows[start:stop], rows[start:stop]], -1)
        if len(pts) >= 2:
            cv2.polylines(mask, [np.round(pts * 4).astype(np.int32)], False, 1,
                          thickness=LANE_WIDTH_PX, lineType=cv2.LINE_8, shift=2)
    return mask.astype(bool)


def lane_iou_matrix(pred: list[np.ndarray], gt: list[np.ndarray]) -> np.ndarray:
    """Mask IoU (G, P) of labelled against predicted boundaries (x at LABEL_ROWS each)."""
    pm, gm = [lane_mask(x) for x in pred], [lane_mask(x) for x in gt]
    out = np.zeros((len(gm), len(pm)))
    p_area = [np.count_nonzero(p) for p in pm]
    for i, g in enumerate(gm):
        g_area = np.count_nonzero(g)
        for j, p in enumerate(pm):
            inter = np.count_nonzero(g & p)
            union = g_area + p_area[j] - inter
            out[i, j] = inter / union if union else 0.0
    return out


def match_lanes(iou: np.ndarray) -> np.ndarray:
    """Each labelled boundary's IoU with its Hungarian partner (0 without one)."""
    per_gt = np.zeros(iou.shape[0])
    if iou.size:
        r, c = linear_sum_assignment(-iou)
        per_gt[r] = iou[r, c]
    return per_gt


def x_at_rows(coeffs: np.ndarray, camera: CameraModel, rows: np.ndarray,
              x_range: tuple[float, float]) -> np.ndarray:
    """Image x of the ground curve y(x) = coeffs at each row, over x_range (NaN elsewhere)."""
    g = np.linspace(min(x_range), max(x_range), 400)
    uv, ok = camera.project_ground(np.stack([g, LanePoly.of(coeffs).y(g)], -1))
    uv = uv[ok]
    uv = uv[np.argsort(uv[:, 1])]
    if len(uv) < 2:
        return np.full(len(rows), np.nan)
    x = np.interp(rows, uv[:, 1], uv[:, 0], left=np.nan, right=np.nan)
    return np.where((x > -0.5) & (x < camera.width - 0.5), x, np.nan)


@dataclass(frozen=True)
class FramePrediction:
    """What one detector gave for one frame, in the terms the metrics need."""

    boxes: np.ndarray  # (N, 4) proposals, 1280x720 pixels
    scores: np.ndarray  # (N,)
    lanes: list[np.ndarray]  # every boundary it reports, x at LABEL_ROWS (NaN off it)
    estimate: LaneEstimate  # the ego lane (vehicle frame)


def estimate_prediction(estimate: LaneEstimate, camera: CameraModel,
                        x_range: tuple[float, float], grid: CellGrid) -> FramePrediction:
    """A classical detector's frame as proposals and lanes: its boundaries (see above)."""
    lanes, boxes = [], [np.zeros((0, 4))]
    sides = (estimate.left, estimate.right, *estimate.others) if estimate.valid else ()
    for coeffs in sides:
        if coeffs is None:
            continue
        lanes.append(x_at_rows(coeffs, camera, LABEL_ROWS, x_range))
        band_x = x_at_rows(coeffs, camera, grid.row_centres(), x_range)
        ok = np.isfinite(band_x)
        boxes.append(cell_boxes(band_x[ok], grid.row_centres()[ok], grid))
    box = np.concatenate(boxes)
    return FramePrediction(box, np.full(len(box), float(estimate.confidence)), lanes, estimate)


def _ego_rows(slots: np.ndarray, rear: bool) -> tuple[int | None, int | None]:
    """Label indices of the vehicle's left and right ego boundaries (a rear camera's
    ego-left slot is the vehicle's right)."""
    found = [np.flatnonzero(slots == s) for s in EGO_SLOTS]
    left, right = (int(f[0]) if len(f) else None for f in found)
    return (right, left) if rear else (left, right)


def ego_errors(estimate: LaneEstimate, ground_y: np.ndarray, slots: np.ndarray,
               rear: bool = False) -> np.ndarray:
    """|y_pred - y_true| (m) at ADE_POINTS_M, (2, P) for left / right; NaN where unscored."""
    err = np.full((2, len(ADE_POINTS_M)), np.nan)
    if not estimate.valid:
        return err
    x = np.asarray(ADE_POINTS_M) * (-1.0 if rear else 1.0)
    for k, (row, coeffs) in enumerate(zip(_ego_rows(slots, rear),
                                          (estimate.left, estimate.right), strict=True)):
        if row is not None and coeffs is not None:
            err[k] = np.abs(LanePoly.of(coeffs).y(x) - ground_y[row])
    return err


def offset_error(estimate: LaneEstimate, ground_y: np.ndarray, slots: np.ndarray,
                 rear: bool = False) -> float:
    """|offset error| (m) at the estimate's look-ahead; NaN if either ego label is missing."""
    left, right = _ego_rows(slots, rear)
    if not estimate.valid or left is None or right is None:
        return float("nan")
    dist = np.asarray(ADE_POINTS_M)
    at = abs(estimate.x_m)
    y_l = np.interp(at, dist, ground_y[left], left=np.nan, right=np.nan)
    y_r = np.interp(at, dist, ground_y[right], left=np.nan, right=np.nan)
    return float(abs(estimate.offset_m + (y_l + y_r) / 2.0))


@dataclass
class Tally:
    """One detector's running scores over one test set (see the module docstring)."""

    grid: CellGrid = field(default_factory=eval_grid)
    scores: list = field(default_factory=list)
    hits: list = field(default_factory=list)
    n_boxes: int = 0
    hits_ego: list = field(default_factory=list)
    n_ego_boxes: int = 0
    lane_iou: list = field(default_factory=list)
    ego_iou: list = field(default_factory=list)
    lane_tp: int = 0
    n_pred_lanes: int = 0
    ade: list = field(default_factory=list)
    fde: list = field(default_factory=list)
    offset: list = field(default_factory=list)
    valid: list = field(default_factory=list)
    ms: list = field(default_factory=list)

    def add(self, pred: FramePrediction, xs: np.ndarray, slots: np.ndarray,
            ground_y: np.ndarray, ms: float, rear: bool = False) -> None:
        """Score one frame: labels xs (B, R), slots (B,), ground_y (B, P)."""
        gt = gt_boxes(xs, slots, self.grid)
        self.scores.append(np.asarray(pred.scores, float))
        self.hits.append(match_boxes(pred.boxes, pred.scores, gt))
        self.n_boxes += len(gt)
        ego = np.isin(slots, EGO_SLOTS)
        gt_ego = gt_boxes(xs[ego], slots[ego], self.grid)
        self.hits_ego.append(match_boxes(pred.boxes, pred.scores, gt_ego))
        self.n_ego_boxes += len(gt_ego)
        labelled = [i for i, s in enumerate(slots) if s >= 0 and np.isfinite(xs[i]).sum() >= 2]
        per_gt = match_lanes(lane_iou_matrix(pred.lanes, [xs[i] for i in labelled]))
        self.lane_iou.extend(per_gt.tolist())
        self.ego_iou.extend(v for v, i in zip(per_gt, labelled, strict=True)
                            if slots[i] in EGO_SLOTS)
        self.lane_tp += int(np.sum(per_gt >= LANE_IOU))
        self.n_pred_lanes += len(pred.lanes)
        err = ego_errors(pred.estimate, ground_y, slots, rear)
        self.ade.extend(err[np.isfinite(err)].tolist())
        self.fde.extend(err[:, -1][np.isfinite(err[:, -1])].tolist())
        self.offset.append(offset_error(pred.estimate, ground_y, slots, rear))
        self.valid.append(bool(pred.estimate.valid))
        self.ms.append(float(ms))

    def summary(self) -> dict:
        """The set's figures (NaN where nothing was scored; JSON writes null)."""
        def mean(v: list, scale: float = 1.0) -> float:
            a = np.asarray(v, float)
            a = a[np.isfinite(a)]
            return float(a.mean() * scale) if len(a) else float("nan")

        n_gt_lanes = len(self.lane_iou)
        fp, fn = self.n_pred_lanes - self.lane_tp, n_gt_lanes - self.lane_tp
        f1_den = 2 * self.lane_tp + fp + fn
        scores = np.concatenate(self.scores) if self.scores else np.zeros(0)
        hits = np.concatenate(self.hits) if self.hits else np.zeros(0, bool)
        hits_ego = np.concatenate(self.hits_ego) if self.hits_ego else np.zeros(0, bool)
        return {
            "frames": len(self.valid),
            "ap": average_precision(scores, hits, self.n_boxes),
            "ap_ego": average_precision(scores, hits_ego, self.n_ego_boxes),
            "ego_box_share": self.n_ego_boxes / self.n_boxes if self.n_boxes else float("nan"),
            "iou": mean(self.lane_iou),
            "iou_ego": mean(self.ego_iou),
            "f1": 2 * self.lane_tp / f1_den if f1_den else float("nan"),
            "ade_cm": mean(self.ade, 100.0),
            "fde_cm": mean(self.fde, 100.0),
            "offset_err_cm": mean(self.offset, 100.0),
            "valid": mean(self.valid),
            "ms": mean(self.ms),
            "gt_boxes": self.n_boxes,
            "gt_lanes": n_gt_lanes,
        }
