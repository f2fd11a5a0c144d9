"""Lane-marking styles and their layout as strips of paint along a lane boundary.

A strip is described in road (Frenet) coordinates only: from `s_start_m` to `s_end_m` at lateral
position `r_m`, `width_m` wide. The mesh builder in world.py samples `Road.position(s, r)` along it,
so a strip may follow a curve; solid lines are cut at segment joins and into pieces of at most
`MAX_STRIP_M` so that each is a short ribbon. A raised pavement marker (Botts' dot) is a `dot`
piece: a small dome of diameter `width_m` centred between `s_start_m` and `s_end_m`. A raised
reflective pavement marker (the Californian kind: a ~10 cm square block with sloped reflective
faces) is a `dot` piece with `reflector` set; `reflector_spacing_m` adds them to any pattern (in
the gaps of a dashed line, on the line otherwise, between the lines of a double one). Like
Botts' dots they belong to their boundary's marking, in the masks too: a detector must take a
row of them for the lane's boundary where there is no paint, as TuSimple's labels run through
them.

Worn paint, as on real roads, is the line it was (solid, dashed, double) broken into chips:
the paint flakes off in gaps a few decimetres long that grow with the wear, the chips left are
narrower and ragged, and their brightness fades with a wear that varies slowly along the line.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, setting

MARKING_KINDS = ("solid", "dashed", "double", "none", "worn", "dots")
WORN_PATTERNS = ("solid", "dashed", "double", "dots")
MAX_STRIP_M = 20.0  # longest solid strip; longer lines are cut into equal pieces
WEAR_CORRELATION_M = 8.0  # the local wear of a worn line drifts over about this length
WEAR_STEP_M = 0.05  # resolution of worn paint along the line
REFLECTOR_M = 0.10  # a raised reflective marker's side


@dataclass(frozen=True)
class MarkingStyle:
    """How one lane boundary is painted. Lengths in metres, colour RGB in 0..1."""

    kind: str = setting("solid", "Paint pattern of the boundary; dots = Botts' dots.",
                        choices=MARKING_KINDS)
    width_m: float = setting(0.15, "Width of the line.", allowed="> 0")
    dash_m: float = setting(3.0, "dashed: paint length; dots: length of a row of dots.",
                            allowed="> 0")
    gap_m: float = setting(9.0, "dashed: gap between dashes; dots: gap between rows.",
                           allowed="> 0")
    double_gap_m: float = setting(0.12, "double: clear gap between the two lines.", allowed=">= 0")
    wear: float = setting(0.4, "worn: share of the line without paint, and how faded the rest.",
                          bounds=(0.0, 1.0))
    pattern: str = setting("solid", "worn: the pattern that wore.",
                           choices=WORN_PATTERNS[:3])
    dot_diameter_m: float = setting(0.10, "dots: diameter of one dot.", allowed="> 0")
    dot_spacing_m: float = setting(0.9, "dots: spacing of the dots within a row.", allowed="> 0")
    reflector_spacing_m: float = setting(
        0.0, "Raised reflective markers (10 cm square blocks, the paint's colour) every this "
        "many metres along the boundary: on a dashed line in the middle of every k-th gap "
        "(k = spacing / (dash + gap), rounded, at least 1), else on the line (between the lines "
        "of a double one); with kind none they alone mark it. 0 = none.", allowed=">= 0")
    colour: tuple[float, float, float] = setting(
        (0.95, 0.95, 0.92), "Paint colour, RGB (yellow paint: [0.9, 0.7, 0.15]).",
        allowed="3 values in 0..1")

    def __post_init__(self):
        check_settings(self)
        for key in ("width_m", "dash_m", "gap_m", "dot_diameter_m", "dot_spacing_m"):
            if not getattr(self, key) > 0:
                raise InvalidValue(key, f"must be > 0, got {getattr(self, key)}")
        if not self.reflector_spacing_m >= 0:
            raise InvalidValue("reflector_spacing_m",
                               f"must be >= 0, got {self.reflector_spacing_m}")
        if not self.double_gap_m >= 0:
            raise InvalidValue("double_gap_m", f"must be >= 0, got {self.double_gap_m}")
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
    dot: bool = False  # a raised marker (dome of diameter width_m), not a strip
    reflector: bool = False  # a dot that is a square reflective marker of side width_m


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


def _pattern(style: MarkingStyle, kind: str, boundary: int, r_m: float, length_m: float,
             joins: Sequence[float]) -> list[MarkingPiece]:
    """Fresh pieces of a solid, dashed, double or dotted line."""

    def piece(a: float, b: float, r: float = r_m) -> MarkingPiece:
        return MarkingPiece(boundary, a, b, r, style.width_m, 1.0)

    if kind == "solid":
        return [piece(a, b) for a, b in _split(0.0, length_m, joins)]
    if kind == "double":
        half = 0.5 * (style.double_gap_m + style.width_m)
        return [
            piece(a, b, r)
            for a, b in _split(0.0, length_m, joins)
            for r in (r_m - half, r_m + half)
        ]
    starts = np.arange(0.0, length_m, style.dash_m + style.gap_m)
    if kind == "dashed":
        return [piece(float(a), min(float(a) + style.dash_m, length_m)) for a in starts]
    # dots: rows of raised markers, each row dash_m long
    d = style.dot_diameter_m
    centres = [float(a) + k for a in starts
               for k in np.arange(0.0, style.dash_m - 0.5 * d + 1e-9, style.dot_spacing_m)]
    return [MarkingPiece(boundary, c, c + d, r_m, d, 1.0, dot=True)
            for c in centres if c + d <= length_m]


def _reflectors(style: MarkingStyle, boundary: int, r_m: float, length_m: float
                ) -> list[MarkingPiece]:
    """Raised reflective markers every `reflector_spacing_m` (see MarkingStyle)."""
    spacing = style.reflector_spacing_m
    if spacing <= 0.0:
        return []
    dashed = style.kind == "dashed" or (style.kind == "worn" and style.pattern == "dashed")
    if dashed:
        period = style.dash_m + style.gap_m
        every = max(1, round(spacing / period))
        centres = np.arange(0.0, length_m, every * period) + style.dash_m + 0.5 * style.gap_m
    else:
        centres = np.arange(0.5 * spacing, length_m, spacing)
    h = 0.5 * REFLECTOR_M
    return [MarkingPiece(boundary, float(c) - h, float(c) + h, r_m, REFLECTOR_M, 1.0, dot=True,
                         reflector=True) for c in centres if h <= c <= length_m - h]


def _smooth(rng: np.random.Generator, n: int, sigma: float) -> np.ndarray:
    """Unit-std noise of n samples, correlated over `sigma` samples."""
    half = int(3 * sigma) + 1
    kernel = np.exp(-0.5 * (np.arange(-half, half + 1) / sigma) ** 2)
    noise = np.convolve(rng.standard_normal(n + 2 * half), kernel, mode="valid")
    return (noise - noise.mean()) / max(float(noise.std()), 1e-9)


def _wear(fresh: list[MarkingPiece], wear: float, rng: np.random.Generator) -> list[MarkingPiece]:
    """Fresh paint after `wear`: where a multi-scale noise along the line falls below the local
    wear the paint is gone, so holes of every size from pits to metres open up (mean painted
    share 1 - wear); the chips left are narrower, off-centre and faded, and the local wear
    drifts along the line, so some stretches are nearly whole and others nearly gone."""
    if wear >= 1.0:
        return []
    out = []
    for p in fresh:
        n = max(int(math.ceil((p.s_end_m - p.s_start_m) / WEAR_STEP_M)), 1)
        s = p.s_start_m + WEAR_STEP_M * np.arange(n + 1)
        s[-1] = p.s_end_m
        drift = _smooth(rng, n, WEAR_CORRELATION_M / WEAR_STEP_M)
        local = np.clip(wear + 0.25 * drift, 0.0, 1.0)
        texture = 0.6 * _smooth(rng, n, 0.5 / WEAR_STEP_M) + 0.8 * _smooth(rng, n, 1.5)
        cdf = 0.5 * (1.0 + np.vectorize(math.erf)(texture / math.hypot(0.6, 0.8) / math.sqrt(2)))
        painted = np.r_[False, cdf > local, False]  # uniform cdf: P(painted) = 1 - local
        edges = np.flatnonzero(np.diff(painted.astype(np.int8)))
        for a, b in zip(edges[0::2], edges[1::2], strict=True):
            if b - a < 1:
                continue
            w = float(local[a:b].mean())
            width = p.width_m * rng.uniform(1.0 - 0.5 * w, 1.0)
            r = p.r_m + rng.uniform(-0.5, 0.5) * (p.width_m - width)
            brightness = max(0.05, 1.0 - 0.8 * w * rng.uniform(0.6, 1.0))
            out.append(MarkingPiece(p.boundary, float(s[a]), float(s[b]), r, width, brightness))
    return out


def layout(
    style: MarkingStyle,
    boundary: int,
    r_m: float,
    length_m: float,
    joins: Sequence[float] = (),
    rng_seed: int = 0,
) -> list[MarkingPiece]:
    """Strips of paint (or dots) of one boundary at lateral position `r_m`, ordered by s.

    Args:
      style: the marking style.
      boundary: boundary index (stored in each piece; also offsets the seed of 'worn').
      r_m: Frenet r of the boundary.
      length_m: road length; paint covers [0, length_m].
      joins: s of segment joins, where solid lines are cut.
      rng_seed: seed of a worn line; the generator is `default_rng(rng_seed + boundary)`.
    """
    if style.kind == "none":
        pieces = []
    elif style.kind != "worn":
        pieces = _pattern(style, style.kind, boundary, r_m, length_m, joins)
    else:
        fresh = _pattern(style, style.pattern, boundary, r_m, length_m, joins)
        pieces = _wear(fresh, style.wear, np.random.default_rng(rng_seed + boundary))
    reflectors = _reflectors(style, boundary, r_m, length_m)
    if not reflectors:
        return pieces
    return sorted(pieces + reflectors, key=lambda p: (p.s_start_m, p.r_m))
