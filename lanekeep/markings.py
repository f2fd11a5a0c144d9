"""Lane-marking styles and their layout as strips of paint along a lane boundary.

A strip is described in road (Frenet) coordinates only: from `s_start_m` to `s_end_m` at lateral
position `r_m`, `width_m` wide. The mesh builder in world.py samples `Road.position(s, r)` along it,
so a strip may follow a curve; solid lines are cut at segment joins and into pieces of at most
`MAX_STRIP_M` so that each is a short ribbon.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lanekeep.config_io import InvalidValue

MARKING_KINDS = ("solid", "dashed", "double", "none", "worn")
MAX_STRIP_M = 20.0  # longest solid strip; longer lines are cut into equal pieces
WORN_PERIOD_M = 4.0  # mean length of one paint run plus one gap of a worn line


@dataclass(frozen=True)
class MarkingStyle:
    """How one lane boundary is painted. Lengths in metres, colour RGB in 0..1."""

    kind: str = "solid"
    width_m: float = 0.15
    dash_m: float = 3.0  # dashed: paint length
    gap_m: float = 9.0  # dashed: gap length
    double_gap_m: float = 0.12  # double: clear gap between the two lines
    wear: float = 0.4  # worn: fraction of the line without paint, and how faded the rest is
    colour: tuple[float, float, float] = (0.95, 0.95, 0.92)

    def __post_init__(self):
        if self.kind not in MARKING_KINDS:
            raise InvalidValue("kind", f"must be one of {MARKING_KINDS}, got {self.kind!r}")
        for key in ("width_m", "dash_m", "gap_m"):
            if not getattr(self, key) > 0:
                raise InvalidValue(key, f"must be > 0, got {getattr(self, key)}")
        if not self.double_gap_m >= 0:
            raise InvalidValue("double_gap_m", f"must be >= 0, got {self.double_gap_m}")
        if not 0.0 <= self.wear <= 1.0:
            raise InvalidValue("wear", f"must be in [0, 1], got {self.wear}")
        if len(self.colour) != 3 or not all(0.0 <= c <= 1.0 for c in self.colour):
            raise InvalidValue("colour", f"must be 3 values in [0, 1], got {self.colour}")


@dataclass(frozen=True)
class MarkingPiece:
    """One strip of paint, in road coordinates, for the mesh builder."""

    boundary: int  # lane boundary index, 0 = rightmost
    s_start_m: float
    s_end_m: float
    r_m: float  # lateral position of the strip's centre line (+ = left)
    width_m: float
    brightness: float  # 1 = fresh paint; lower = faded


def default_markings(n_lanes: int) -> tuple[MarkingStyle, ...]:
    """Solid outer edges, dashed lines between lanes."""
    inner = MarkingStyle(kind="dashed")
    return (MarkingStyle(),) + (inner,) * (n_lanes - 1) + (MarkingStyle(),)


def _split(a: float, b: float, cuts: Sequence[float]) -> list[tuple[float, float]]:
    """[a, b) cut at `cuts` and then into equal pieces no longer than MAX_STRIP_M."""
    edges = [a] + [c for c in cuts if a < c < b] + [b]
    out = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        n = max(1, math.ceil((hi - lo) / MAX_STRIP_M - 1e-9))
        ends = np.linspace(lo, hi, n + 1)
        out += [(float(p), float(q)) for p, q in zip(ends[:-1], ends[1:], strict=True)]
    return out


def layout(
    style: MarkingStyle,
    boundary: int,
    r_m: float,
    length_m: float,
    joins: Sequence[float] = (),
    rng_seed: int = 0,
) -> list[MarkingPiece]:
    """Strips of paint of one boundary at lateral position `r_m`, ordered by s then r.

    Args:
      style: the marking style.
      boundary: boundary index (stored in each piece; also offsets the seed of 'worn').
      r_m: Frenet r of the boundary.
      length_m: road length; paint covers [0, length_m].
      joins: s of segment joins, where solid lines are cut.
      rng_seed: seed of a worn line; the generator is `default_rng(rng_seed + boundary)`.
    """

    def piece(a: float, b: float, r: float = r_m, brightness: float = 1.0) -> MarkingPiece:
        return MarkingPiece(boundary, a, b, r, style.width_m, brightness)

    if style.kind == "none":
        return []
    if style.kind == "solid":
        return [piece(a, b) for a, b in _split(0.0, length_m, joins)]
    if style.kind == "double":
        half = 0.5 * (style.double_gap_m + style.width_m)
        return [
            piece(a, b, r)
            for a, b in _split(0.0, length_m, joins)
            for r in (r_m - half, r_m + half)
        ]
    if style.kind == "dashed":
        period = style.dash_m + style.gap_m
        starts = np.arange(0.0, length_m, period)
        return [piece(float(a), min(float(a) + style.dash_m, length_m)) for a in starts]
    # worn: paint runs and gaps of random length (mean paint fraction 1 - wear), faded paint.
    rng = np.random.default_rng(rng_seed + boundary)
    pieces = []
    if style.wear >= 1.0:
        return pieces
    s = 0.0
    while s < length_m:
        run = WORN_PERIOD_M * (1.0 - style.wear) * rng.uniform(0.5, 1.5)
        gap = WORN_PERIOD_M * style.wear * rng.uniform(0.5, 1.5)
        brightness = max(0.05, 1.0 - style.wear * rng.uniform(0.3, 1.0))
        pieces.append(piece(s, min(s + run, length_m), brightness=brightness))
        s += run + gap
    return pieces
