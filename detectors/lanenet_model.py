"""Spatiotemporal LaneNet (paper 000, section 2.1-2.2): encoder, ConvGRU, difference fusion, heads.

Per frame I_t the encoder gives F_t at 1/8 of the working size; the difference map
dF_t = F_t - F_{t-1} (zero at the first frame or after a reset) is fused as
alpha F_t + (1 - alpha) dF_t with alpha = sigmoid(raw), a learnt scalar that can never leave
[0, 1]; a convolutional GRU carries what earlier frames saw (a dash hidden by a car a moment
ago). The proposal head reads the fused map and the GRU state and, per output cell (an anchor on
a piece of marking; each feature cell answers for `rows_per_cell` row bands, so a lane gets a
point every ~16 px of frame height), says: is a lane boundary here, where in the cell (x offset
0..1), which lane slot it is (see `detectors.lanenet_targets.SLOTS`), is there paint in it.

The network is pure: state goes in and comes out of `forward`, so a sequence split in two calls
gives the same result as one call, and the detector (or a training loop) owns the state.

Working size 320x176: a 1280x720 frame is 4x smaller across (cells 32 px wide at 1280) and 176
is the multiple of 8 nearest 180 (feature cells 32.7 px tall, output row bands 16.4 px). Resize
and network take ~5 ms of one core per frame, a third of the 15 ms budget, leaving room for
decoding and a loaded machine; 384x216 would cost ~1.5x the arithmetic for finer far cells.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import NamedTuple

import cv2
import numpy as np
import torch
from torch import nn
from torch.nn import functional as F  # noqa: N812 - the usual torch alias

STRIDE = 8  # feature cells per working-image pixel, both axes


@dataclass(frozen=True)
class LaneNetConfig:
    """Architecture; stored with the weights so a file can only load into its own shape."""

    width: int = 320  # working image size (pixels); both multiples of STRIDE
    height: int = 176
    channels: tuple[int, int, int] = (16, 32, 48)  # encoder widths at 1/2, 1/4, 1/8
    hidden: int = 24  # ConvGRU state channels
    head: int = 48  # proposal-head channels
    n_slots: int = 5
    rows_per_cell: int = 2  # row bands each feature cell answers for (finer points along lanes)

    def __post_init__(self) -> None:
        if self.width % STRIDE or self.height % STRIDE or self.width <= 0 or self.height <= 0:
            raise ValueError(f"working size {self.width}x{self.height} must be multiples of "
                             f"{STRIDE}")
        if len(self.channels) != 3 or min(self.channels) <= 0 or self.hidden <= 0 or (
                self.rows_per_cell < 1):
            raise ValueError("channels must be three positive widths, hidden positive")

    @property
    def grid(self) -> tuple[int, int]:
        """(rows, cols) of the output grid: feature rows x rows_per_cell, feature columns."""
        return self.rows_per_cell * self.height // STRIDE, self.width // STRIDE

    def to_dict(self) -> dict:
        d = asdict(self)
        d["channels"] = list(self.channels)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> LaneNetConfig:
        d = dict(d)
        if "channels" in d:
            d["channels"] = tuple(int(c) for c in d["channels"])
        return cls(**d)


class LaneNetOutput(NamedTuple):
    """Per time step, all (B, T, ., rows, cols): raw logits except `x_offset` (0..1 in a cell)."""

    objectness: torch.Tensor  # (B, T, rows, cols) logit: a boundary crosses this cell's row band
    x_offset: torch.Tensor  # (B, T, rows, cols) where in the cell, 0 = left edge, 1 = right
    slot: torch.Tensor  # (B, T, n_slots, rows, cols) logits
    marking: torch.Tensor  # (B, T, rows, cols) logit: paint in the cell (dashes have gaps)


class LaneNetState(NamedTuple):
    """What one frame leaves for the next: its features F_{t-1} and the GRU state."""

    features: torch.Tensor
    hidden: torch.Tensor


def prepare_frame(frame: np.ndarray, config: LaneNetConfig) -> np.ndarray:
    """RGB uint8 (H, W, 3) at any size -> (3, height, width) uint8 at the working size.

    Area averaging, as training data must be made the same way: bilinear sampling at 4x would
    alias thin far markings away.
    """
    if frame.shape[:2] != (config.height, config.width):
        frame = _area_resize(frame, config.width, config.height)
    return np.ascontiguousarray(frame.transpose(2, 0, 1))


def _area_resize(frame: np.ndarray, width: int, height: int) -> np.ndarray:
    """`cv2.resize(frame, (width, height), interpolation=INTER_AREA)`, pixel for pixel, in less
    time where the width shrinks by a power of two and the height by a fraction (1280x720 ->
    320x176: 1.9 against 2.5 ms). OpenCV's general area resize of uint8 sums each output
    pixel's source pixels times their area share in float32 and rounds once; across, a share of
    1/2^n is exact, so those sums are exact, as are its float32 fast path's; down, a float image
    takes the same weights in the same order, and the last rounding is OpenCV's own (ties to
    even). Elsewhere (another factor across rounds its shares; a whole factor both ways takes
    OpenCV's integer fast path; a growing height interpolates) it is the plain call
    (tests/detectors/test_lanenet_speed_equivalence.py checks that the two are equal)."""
    h, w = frame.shape[:2]
    k = w // width
    if (w % width or k < 2 or k & (k - 1) or h <= height or h % height == 0
            or frame.dtype != np.uint8):
        return cv2.resize(frame, (width, height), interpolation=cv2.INTER_AREA)
    across = cv2.resize(frame.astype(np.float32), (width, h), interpolation=cv2.INTER_AREA)
    return cv2.convertScaleAbs(cv2.resize(across, (width, height),
                                          interpolation=cv2.INTER_AREA))


def _block(c_in: int, c_out: int, stride: int = 1, dilation: int = 1) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv2d(c_in, c_out, 3, stride=stride, padding=dilation, dilation=dilation,
                  bias=False),
        nn.BatchNorm2d(c_out),
        nn.ReLU(inplace=True),
    )


class ConvGRUCell(nn.Module):
    """GRU with 3x3 convolutions: h' = (1 - z) h + z tanh(W [x, r h]); gates 1x1 to save time."""

    def __init__(self, c_in: int, hidden: int) -> None:
        super().__init__()
        self.gates = nn.Conv2d(c_in + hidden, 2 * hidden, 1)  # 1x1: the candidate sees around
        self.candidate = nn.Conv2d(c_in + hidden, hidden, 3, padding=1)

    def forward(self, x: torch.Tensor, h: torch.Tensor) -> torch.Tensor:
        z, r = torch.sigmoid(self.gates(torch.cat([x, h], 1))).chunk(2, 1)
        n = torch.tanh(self.candidate(torch.cat([x, r * h], 1)))
        return (1.0 - z) * h + z * n


class LaneNet(nn.Module):
    """The network; `forward(frames, state)` -> (outputs per step, state after the last step)."""

    def __init__(self, config: LaneNetConfig | None = None, seed: int = 0) -> None:
        super().__init__()
        self.config = config = config or LaneNetConfig()
        c1, c2, c3 = config.channels
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)  # same seed, same initial weights: training is repeatable
            self.encoder = nn.Sequential(
                _block(3, c1, stride=2),
                _block(c1, c2, stride=2),
                _block(c2, c3, stride=2),
                _block(c3, c3, dilation=2),  # context: a boundary's slot depends on its
                _block(c3, c3, dilation=4),  # neighbours, tens of pixels away
            )
            self.alpha_raw = nn.Parameter(torch.zeros(()))
            self.gru = ConvGRUCell(c3, config.hidden)
            self.head = nn.Sequential(
                nn.Conv2d(c3 + config.hidden + 2, config.head, 1),
                nn.ReLU(inplace=True),
                nn.Conv2d(config.head, config.rows_per_cell * (3 + config.n_slots), 1),
            )
        rows, cols = config.height // STRIDE, config.width // STRIDE
        ys = torch.linspace(-1.0, 1.0, rows).view(1, 1, rows, 1).expand(1, 1, rows, cols)
        xs = torch.linspace(-1.0, 1.0, cols).view(1, 1, 1, cols).expand(1, 1, rows, cols)
        # Where a cell is in the image tells much of its slot (ego-left sits left of centre).
        self.register_buffer("coords", torch.cat([xs, ys], 1).contiguous(), persistent=False)
        self.register_buffer("mean", torch.tensor([0.45, 0.45, 0.45]).view(1, 3, 1, 1),
                             persistent=False)

    @property
    def alpha(self) -> torch.Tensor:
        """The fusion weight, in [0, 1] whatever the raw parameter holds."""
        return torch.sigmoid(self.alpha_raw)

    def _normalise(self, x: torch.Tensor) -> torch.Tensor:
        if x.dtype == torch.uint8:
            x = x.float() / 255.0
        if x.shape[-2:] != (self.config.height, self.config.width):
            x = F.interpolate(x, size=(self.config.height, self.config.width), mode="bilinear",
                              antialias=True, align_corners=False)
        return x - self.mean

    def forward(
        self, frames: torch.Tensor, state: LaneNetState | None = None
    ) -> tuple[LaneNetOutput, LaneNetState]:
        """frames (B, T, 3, H, W), uint8 (0..255) or float (0..1); state None = a fresh start.

        With no state, dF at the first step is zero (F_{t-1} := F_t): a single frame is seen by
        its spatial features alone.
        """
        if frames.dim() != 5 or frames.shape[2] != 3:
            raise ValueError(f"frames must be (B, T, 3, H, W), got {tuple(frames.shape)}")
        b, t = frames.shape[:2]
        feats = self.encoder(self._normalise(frames.flatten(0, 1)))
        feats = feats.view(b, t, *feats.shape[1:])
        if state is None:  # a fresh start: zero GRU state, and no previous features
            rows, cols = self.config.height // STRIDE, self.config.width // STRIDE
            prev = None
            h = feats.new_zeros(b, self.config.hidden, rows, cols)
        else:
            prev, h = state
        alpha = self.alpha
        coords = self.coords.expand(b, -1, -1, -1)
        outs = []
        for i in range(t):
            f = feats[:, i]
            diff = torch.zeros_like(f) if prev is None else f - prev
            fused = alpha * f + (1.0 - alpha) * diff
            h = self.gru(fused, h)
            outs.append(self.head(torch.cat([fused, h, coords], 1)))
            prev = f
        y = torch.stack(outs, 1)  # (B, T, rows_per_cell * (3 + n_slots), r, c)
        k, r, c = self.config.rows_per_cell, y.shape[-2], y.shape[-1]
        # Sub-row j of feature row i is output row i * k + j.
        y = y.view(b, t, k, -1, r, c).permute(0, 1, 3, 4, 2, 5).reshape(b, t, -1, r * k, c)
        out = LaneNetOutput(
            objectness=y[:, :, 0],
            x_offset=torch.sigmoid(y[:, :, 1]),
            slot=y[:, :, 3:],
            marking=y[:, :, 2],
        )
        return out, LaneNetState(prev, h)


def architecture_summary(model: LaneNet) -> dict:
    """Parameter count and the bytes its float32 weights take, for the model card."""
    n = sum(p.numel() for p in model.parameters())
    buffers = sum(b.numel() for name, b in model.named_buffers() if "running" in name)
    return {"parameters": int(n), "float32_bytes": int(4 * (n + buffers)),
            "config": model.config.to_dict()}
