"""LaneNet labels, the per-cell training targets made from them, and the loss.

Labels, per frame, in frame pixels (1280x720 for our cameras; the origin is the centre of the top
left pixel): every lane boundary as a polyline continuous through dash gaps (as TuSimple labels
lanes), with its slot, and optionally the per-pixel marking mask.

Slots name a boundary by its place around the camera, counted outwards from it on the ground
near the car (TuSimple / CULane order the same lanes left to right around the ego lane):
    0 ego-left    the nearest boundary left of the camera's optical axis
    1 ego-right   the nearest boundary right of it
    2 next-left   the second boundary on the left (the far side of the left neighbour lane)
    3 next-right  the second on the right
    4 other       any boundary further out
`slots_from_lateral` assigns them from lateral offsets, as the dataset generator should.

Targets, per feature cell (row band r, column c of the 1/8 grid, see `CellGrid`): a boundary
"owns" the cell of its row band that holds the polyline's x at the band's centre row; then
objectness = 1, x_offset = that x's place across the cell (0..1), slot = its slot. Each boundary
gives at most one cell per row band, so a row of proposals is a row of points on the curves.
Where two boundaries meet one cell (near the horizon) the lower slot (nearer the ego lane) wins.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import torch
from torch.nn import functional as F  # noqa: N812 - the usual torch alias

from lanekeep.detectors.lanenet_model import LaneNetOutput

SLOTS = ("ego-left", "ego-right", "next-left", "next-right", "other")
OTHER = SLOTS.index("other")


def slots_from_lateral(lateral_m: np.ndarray) -> np.ndarray:
    """Slot ids for boundaries at lateral offsets y (m, + = left of the camera), near the car."""
    y = np.asarray(lateral_m, dtype=float)
    slots = np.full(y.shape, OTHER, dtype=np.int64)
    for side, first in ((y > 0, 0), (y <= 0, 1)):
        idx = np.flatnonzero(side)
        order = idx[np.argsort(np.abs(y[idx]), kind="stable")]
        for rank, i in enumerate(order[:2]):
            slots[i] = first + 2 * rank
    return slots


@dataclass(frozen=True)
class BoundaryLabel:
    """One boundary: polyline (N, 2) of (x, y) frame pixels, and its slot id (0..4)."""

    points_px: np.ndarray
    slot: int

    def __post_init__(self) -> None:
        p = np.asarray(self.points_px, dtype=float)
        if p.ndim != 2 or p.shape[1] != 2 or len(p) < 2:
            raise ValueError("a boundary polyline needs (N >= 2, 2) points")
        if not 0 <= self.slot < len(SLOTS):
            raise ValueError(f"slot {self.slot} is not one of 0..{len(SLOTS) - 1}")


@dataclass(frozen=True)
class FrameLabel:
    """Everything known about one frame's lanes; `marking_mask` (H, W) bool/uint8 or None."""

    boundaries: tuple[BoundaryLabel, ...]
    marking_mask: np.ndarray | None = None


@dataclass(frozen=True)
class CellGrid:
    """Feature cells in frame pixels: cell (r, c) spans columns [c w, (c+1) w) and rows
    [r h, (r+1) h) of pixel edges; pixel centres sit at integers, edges at -0.5."""

    frame_width: int
    frame_height: int
    rows: int
    cols: int

    @property
    def cell_w(self) -> float:
        return self.frame_width / self.cols

    @property
    def cell_h(self) -> float:
        return self.frame_height / self.rows

    def row_centres(self) -> np.ndarray:
        """Frame y (pixel coordinates) of each row band's centre."""
        return (np.arange(self.rows) + 0.5) * self.cell_h - 0.5

    def x_to_cell(self, x_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Column index and the offset across it (0..1) of frame x."""
        u = (np.asarray(x_px, dtype=float) + 0.5) / self.cell_w
        col = np.floor(u).astype(np.int64)
        return col, u - col

    def cell_to_x(self, col: np.ndarray, offset: np.ndarray) -> np.ndarray:
        return (np.asarray(col) + np.asarray(offset)) * self.cell_w - 0.5


@dataclass(frozen=True)
class Targets:
    """Per-cell targets of one frame, (rows, cols) each; `marking` is None without a mask."""

    objectness: np.ndarray  # float32 0/1
    x_offset: np.ndarray  # float32, 0..1 where objectness
    slot: np.ndarray  # int64, slot id where objectness, -1 elsewhere
    marking: np.ndarray | None = None  # float32 0/1: the cell holds paint


def boundary_crossings(points_px: np.ndarray, grid: CellGrid) -> tuple[np.ndarray, np.ndarray]:
    """(row indices, x at each band's centre row) where the polyline spans that row."""
    p = np.asarray(points_px, dtype=float)
    p = p[np.argsort(p[:, 1], kind="stable")]
    yc = grid.row_centres()
    inside = (yc >= p[0, 1]) & (yc <= p[-1, 1])
    rows = np.flatnonzero(inside)
    xs = np.interp(yc[rows], p[:, 1], p[:, 0])
    keep = (xs > -0.5) & (xs < grid.frame_width - 0.5)
    return rows[keep], xs[keep]


def encode(label: FrameLabel, grid: CellGrid) -> Targets:
    """The training targets of one frame's label on `grid` (see the module docstring)."""
    obj = np.zeros((grid.rows, grid.cols), np.float32)
    xoff = np.zeros_like(obj)
    slot = np.full((grid.rows, grid.cols), -1, np.int64)
    # Highest slot first, so nearer-ego boundaries overwrite shared cells.
    for b in sorted(label.boundaries, key=lambda b: -b.slot):
        rows, xs = boundary_crossings(b.points_px, grid)
        cols, off = grid.x_to_cell(xs)
        obj[rows, cols] = 1.0
        xoff[rows, cols] = off
        slot[rows, cols] = b.slot
    marking = None
    if label.marking_mask is not None:
        m = (np.asarray(label.marking_mask) > 0).astype(np.float32)
        share = cv2.resize(m, (grid.cols, grid.rows), interpolation=cv2.INTER_AREA)
        marking = (share > 0).astype(np.float32)  # exact labels: any paint pixel counts
    return Targets(obj, xoff, slot, marking)


def collate(targets: list[list[Targets]]) -> dict[str, torch.Tensor]:
    """Targets of B sequences of T frames -> tensors (B, T, rows, cols) for the loss."""
    def stack(attr: str) -> torch.Tensor:
        return torch.from_numpy(np.stack([np.stack([getattr(t, attr) for t in seq])
                                          for seq in targets]))

    batch = {k: stack(k) for k in ("objectness", "x_offset", "slot")}
    if all(t.marking is not None for seq in targets for t in seq):
        batch["marking"] = stack("marking")
    return batch


@dataclass(frozen=True)
class LossWeights:
    """Weights of the loss terms and the focal loss's shape (Lin et al. 2017's usual values)."""

    objectness: float = 1.0
    x_offset: float = 2.0  # smooth-L1 on offsets in cell widths: an error of 0.1 = 3 px
    slot: float = 0.5
    marking: float = 0.5
    focal_gamma: float = 2.0
    focal_alpha: float = 0.75  # weight of positives: a frame has ~60 positives in ~880 cells
    smooth_l1_beta: float = 0.05

    def __post_init__(self) -> None:
        if min(self.objectness, self.x_offset, self.slot, self.marking) < 0:
            raise ValueError("loss weights must be >= 0")
        if not 0.0 <= self.focal_alpha <= 1.0 or self.focal_gamma < 0:
            raise ValueError("focal_alpha must be in [0, 1], focal_gamma >= 0")


def focal_loss(logits: torch.Tensor, target: torch.Tensor, alpha: float, gamma: float
               ) -> torch.Tensor:
    """Mean binary focal loss: easy background cells (most of the image) count little."""
    ce = F.binary_cross_entropy_with_logits(logits, target, reduction="none")
    p = torch.sigmoid(logits)
    p_t = p * target + (1 - p) * (1 - target)
    a_t = alpha * target + (1 - alpha) * (1 - target)
    n_pos = target.sum().clamp(min=1.0)
    return (a_t * (1 - p_t) ** gamma * ce).sum() / n_pos


def lanenet_loss(out: LaneNetOutput, batch: dict[str, torch.Tensor],
                 weights: LossWeights = LossWeights()) -> tuple[torch.Tensor, dict[str, float]]:
    """Total loss and its parts: focal objectness over all cells; smooth-L1 x offset and slot
    cross-entropy on positive cells; BCE on paint presence when the batch has masks."""
    obj_t = batch["objectness"].float()
    pos = obj_t > 0.5
    l_obj = focal_loss(out.objectness, obj_t, weights.focal_alpha, weights.focal_gamma)
    if pos.any():
        l_x = F.smooth_l1_loss(out.x_offset[pos], batch["x_offset"][pos].float(),
                               beta=weights.smooth_l1_beta)
        slot_logits = out.slot.movedim(2, -1)[pos]  # (N, n_slots)
        l_slot = F.cross_entropy(slot_logits, batch["slot"][pos])
    else:
        l_x = l_slot = out.x_offset.sum() * 0.0
    total = weights.objectness * l_obj + weights.x_offset * l_x + weights.slot * l_slot
    parts = {"objectness": l_obj.item(), "x_offset": l_x.item(), "slot": l_slot.item()}
    if "marking" in batch:
        l_mark = F.binary_cross_entropy_with_logits(out.marking, batch["marking"].float())
        total = total + weights.marking * l_mark
        parts["marking"] = l_mark.item()
    parts["total"] = total.item()
    return total, parts
