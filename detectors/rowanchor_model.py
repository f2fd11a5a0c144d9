"""The row-anchor lane network: #58's independent observer for the rear camera.

The idea is the row-anchor formulation of published fast lane detectors (Qin et al., "Ultra
Fast Structure-aware Deep Lane Detection", 2020): instead of segmenting paint pixel by pixel,
for each of a fixed set of image rows (anchors) and each lane boundary, classify the column
the boundary crosses that row in, among `bins` column bins, or "absent". The code here is our
own and shares nothing learned with LaneNet (detectors/lanenet_model.py: a segmentation-style
grid of proposals with a GRU over frames): other architecture, other data draws, no weights
in common. That is the point: the MMAE's judge must not be one of the judged.

Architecture (one frame, no memory; 78,244 parameters):
  - input RGB (3, 176, 320) uint8 plus two coordinate channels (x, y in -1..1), so that the
    fully convolutional net knows where a column is: which boundary is the ego-left one depends
    on where it lies in the image, not only on what it looks like;
  - a strided CNN of depthwise-separable residual blocks down to 1/16 (11 x 20 cells), the
    last two dilated (2, 4) for context across the road, plus a global-pool context vector;
  - a top-down fusion back to 1/8 (22 x 40): the 22 rows of this map are the anchors;
  - per boundary a column logit at twice the map's width (80 bins, 4 working pixels each),
    and an "absent" logit from each row's pooled features: softmax over 81 classes per
    (boundary, anchor).
Location = the softmax's expectation over the bins near its peak (sub-bin precision); the
training loss is cross-entropy over the 81 classes plus an L1 on that location (in bins).

Boundaries are the camera's own slots (detectors/lanenet_targets.SLOTS order, the dataset's
labels): ego-left, ego-right, next-left, next-right.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F  # noqa: N812 - the usual torch alias

LANES = ("ego-left", "ego-right", "next-left", "next-right")  # slot ids 0..3 (lanenet_targets)
MIRRORED_LANES = (1, 0, 3, 2)  # a left-right mirrored frame's lane order
PEAK_HALF_WIDTH = 2  # bins either side of the peak the location's expectation reads


@dataclass(frozen=True)
class RowAnchorConfig:
    """The network's shape (stored in its weights file; another shape is another file)."""

    width: int = 320  # working frame size: the dataset's stored frames
    height: int = 176
    channels: tuple[int, ...] = (16, 32, 48, 64)  # strides 2, 4, 8, 16
    lanes: int = len(LANES)

    def __post_init__(self) -> None:
        object.__setattr__(self, "channels", tuple(int(c) for c in self.channels))
        if len(self.channels) != 4 or min(self.channels) < 4:
            raise ValueError("channels: four stages of at least 4 channels")
        if self.width % 16 or self.height % 16:
            raise ValueError("width and height must be multiples of 16")
        if not 1 <= self.lanes <= len(LANES):
            raise ValueError(f"lanes must be 1..{len(LANES)}")

    @property
    def anchors(self) -> int:
        """Anchor rows: the rows of the 1/8 map."""
        return self.height // 8

    @property
    def bins(self) -> int:
        """Column bins: twice the 1/8 map's width."""
        return self.width // 4

    def to_dict(self) -> dict:
        d = asdict(self)
        d["channels"] = list(self.channels)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> RowAnchorConfig:
        return cls(**{k: (tuple(v) if k == "channels" else v) for k, v in d.items()})


def anchor_rows(frame_height: int, anchors: int) -> np.ndarray:
    """Frame y (pixel centres at integers) of each anchor: the centre of its row band."""
    return (np.arange(anchors) + 0.5) * frame_height / anchors - 0.5


def bin_to_x(position: np.ndarray, frame_width: int, bins: int) -> np.ndarray:
    """Frame x of a location in bin units (0 = the left edge of bin 0, `bins` = the right
    edge of the last)."""
    return np.asarray(position) * frame_width / bins - 0.5


def x_to_bin(x_px: np.ndarray, frame_width: int, bins: int) -> np.ndarray:
    """Inverse of `bin_to_x`."""
    return (np.asarray(x_px) + 0.5) * bins / frame_width


class _ConvBN(nn.Sequential):
    def __init__(self, cin: int, cout: int, k: int = 3, stride: int = 1, groups: int = 1,
                 dilation: int = 1, act: bool = True) -> None:
        layers: list[nn.Module] = [
            nn.Conv2d(cin, cout, k, stride, dilation * (k // 2), dilation, groups, bias=False),
            nn.BatchNorm2d(cout)]
        if act:
            layers.append(nn.ReLU(inplace=True))
        super().__init__(*layers)


class _SepBlock(nn.Module):
    """Residual depthwise-separable block: x + pw(dw(x)), cheap on a CPU."""

    def __init__(self, c: int, dilation: int = 1) -> None:
        super().__init__()
        self.dw = _ConvBN(c, c, 3, groups=c, dilation=dilation)
        self.pw = _ConvBN(c, c, 1, act=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return F.relu(x + self.pw(self.dw(x)))


class RowAnchorNet(nn.Module):
    """Frames (B, 3, H, W) uint8 -> logits (B, lanes, anchors, bins + 1), last = absent."""

    def __init__(self, config: RowAnchorConfig | None = None, seed: int | None = None) -> None:
        super().__init__()
        self.config = config or RowAnchorConfig()
        if seed is not None:
            torch.manual_seed(seed)
        c1, c2, c3, c4 = self.config.channels
        lanes = self.config.lanes
        self.stem = _ConvBN(5, c1, 3, stride=2)
        self.stage2 = nn.Sequential(_ConvBN(c1, c2, 3, stride=2), _SepBlock(c2))
        self.stage3 = nn.Sequential(_ConvBN(c2, c3, 3, stride=2), _SepBlock(c3), _SepBlock(c3))
        self.stage4 = nn.Sequential(_ConvBN(c3, c4, 3, stride=2), _SepBlock(c4, 2),
                                    _SepBlock(c4, 4))
        self.context = nn.Linear(c4, c4)
        self.lateral = _ConvBN(c4, c3, 1, act=False)
        self.fuse = nn.Sequential(_SepBlock(c3), _SepBlock(c3, 2))
        self.columns = nn.Conv2d(c3 + 1, 2 * lanes, 1)  # two bins per 1/8 cell, per lane
        self.absent = nn.Conv1d(2 * c3, lanes, 1)  # from each row's mean and max
        coords = self._coords(self.config.height, self.config.width)
        self.register_buffer("coords", coords, persistent=False)

    @staticmethod
    def _coords(h: int, w: int) -> torch.Tensor:
        ys = torch.linspace(-1.0, 1.0, h).view(1, 1, h, 1).expand(1, 1, h, w)
        xs = torch.linspace(-1.0, 1.0, w).view(1, 1, 1, w).expand(1, 1, h, w)
        return torch.cat([xs, ys], 1)

    def forward(self, frames: torch.Tensor) -> torch.Tensor:
        b = frames.shape[0]
        x = frames.float() * (1.0 / 255.0) - 0.5
        x = torch.cat([x, self.coords.expand(b, -1, -1, -1)], 1)
        f3 = self.stage3(self.stage2(self.stem(x)))
        f4 = self.stage4(f3)
        f4 = f4 + F.relu(self.context(f4.mean(dim=(2, 3))))[:, :, None, None]
        up = F.interpolate(self.lateral(f4), size=f3.shape[-2:], mode="bilinear",
                           align_corners=False)
        f = self.fuse(f3 + up)  # (B, c3, anchors, bins / 2)
        a, half = f.shape[-2:]
        xcoord = torch.linspace(-1.0, 1.0, half, device=f.device).view(1, 1, 1, half)
        cols = self.columns(torch.cat([f, xcoord.expand(b, 1, a, half)], 1))
        lanes = self.config.lanes
        cols = cols.view(b, lanes, 2, a, half).permute(0, 1, 3, 4, 2).reshape(b, lanes, a,
                                                                              2 * half)
        pooled = torch.cat([f.mean(dim=3), f.amax(dim=3)], 1)  # (B, 2 c3, anchors)
        absent = self.absent(pooled)[..., None]  # (B, lanes, anchors, 1)
        return torch.cat([cols, absent], -1)


def expected_position(column_logits: torch.Tensor) -> torch.Tensor:
    """Location in bins (...,) from column logits (..., bins): the softmax's expectation over
    the bins within PEAK_HALF_WIDTH of the most likely one, so that a second, weaker mode (a
    neighbour line) does not pull it. Training's L1 reads the same expectation as decoding."""
    p = torch.softmax(column_logits, -1)
    bins = p.shape[-1]
    idx = torch.arange(bins, device=p.device)
    near = (idx - p.argmax(-1, keepdim=True)).abs() <= PEAK_HALF_WIDTH
    w = p * near
    return (w * (idx + 0.5)).sum(-1) / w.sum(-1).clamp_min(1e-12)


def decode(logits: torch.Tensor | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(position in bins (..., anchors), presence probability (..., anchors)) from logits
    (..., anchors, bins + 1)."""
    z = torch.as_tensor(logits, dtype=torch.float32)
    presence = 1.0 - torch.softmax(z, -1)[..., -1]
    return expected_position(z[..., :-1]).numpy(), presence.numpy()


def column_spread(logits: torch.Tensor | np.ndarray) -> np.ndarray:
    """Standard deviation in bins (..., anchors) of each point's column distribution (the
    softmax over the bins alone, "absent" left out), from logits (..., anchors, bins + 1).
    A point on paint reads narrow; one the network infers across a dash gap or an occluder
    reads wide (on case 4's rear frames a median 0.23 bins on paint, 0.86 in gaps)."""
    z = torch.as_tensor(logits, dtype=torch.float32)[..., :-1]
    p = torch.softmax(z, -1)
    centre = torch.arange(p.shape[-1], dtype=torch.float32) + 0.5
    mean = (p * centre).sum(-1, keepdim=True)
    return torch.sqrt((p * (centre - mean) ** 2).sum(-1)).numpy()


def targets(xs_px: np.ndarray, label_rows: np.ndarray, slots: np.ndarray, frame_width: int,
            frame_height: int, config: RowAnchorConfig) -> tuple[np.ndarray, np.ndarray]:
    """Training targets of one frame from its row-sampled labels: class (lanes, anchors) int64
    (a bin, or `bins` = absent) and position in bins (lanes, anchors) float32 (NaN = absent).

    Args:
      xs_px: (boundaries, len(label_rows)) x in frame pixels, NaN where not in view.
      label_rows: the frame rows the labels are sampled at (ascending).
      slots: (boundaries,) each boundary's slot (-1 = none, 0..3 = LANES, 4 = other).
    """
    rows = anchor_rows(frame_height, config.anchors)
    position = np.full((config.lanes, config.anchors), np.nan, np.float32)
    for x, slot in zip(np.asarray(xs_px, float), np.asarray(slots), strict=True):
        if not 0 <= slot < config.lanes:
            continue
        # interpolate between label rows, NaN where either neighbour is missing
        at = np.interp(rows, label_rows, x, left=np.nan, right=np.nan)
        position[slot] = x_to_bin(at, frame_width, config.bins)
    ok = np.isfinite(position) & (position >= 0) & (position < config.bins)
    position[~ok] = np.nan
    cls = np.full(position.shape, config.bins, np.int64)
    cls[ok] = np.floor(position[ok]).astype(np.int64)
    return cls, position


def mirror_targets(cls: np.ndarray, position: np.ndarray, bins: int
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The targets of the frame mirrored left-right (lanes swapped, columns reversed)."""
    lanes = list(MIRRORED_LANES[:cls.shape[0]])
    pos = bins - position[lanes]
    c = cls[lanes].copy()
    present = c < bins
    c[present] = np.minimum(np.floor(pos[present]).astype(np.int64), bins - 1)
    return c, pos.astype(np.float32)


def rowanchor_loss(logits: torch.Tensor, cls: torch.Tensor, position: torch.Tensor,
                   l1_weight: float = 0.5) -> tuple[torch.Tensor, dict[str, float]]:
    """Cross-entropy over bins + absent, plus L1 (bins, clipped) of the location where
    present."""
    n = logits.shape[-1]
    ce = F.cross_entropy(logits.reshape(-1, n), cls.reshape(-1))
    expect = expected_position(logits[..., :-1])
    present = torch.isfinite(position)
    # clipped: a point whose peak is in the wrong bins is the cross-entropy's to move; the L1
    # refines one whose peak is near (the expectation reads only PEAK_HALF_WIDTH bins around it)
    l1 = (expect[present] - position[present]).abs().clamp(max=2.0 * PEAK_HALF_WIDTH).mean() \
        if present.any() else logits.sum() * 0.0
    total = ce + l1_weight * l1
    return total, {"ce": float(ce.detach()), "l1_bins": float(l1.detach())}
