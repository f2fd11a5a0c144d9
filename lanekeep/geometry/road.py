"""Road geometry in Frenet form: a chain of straight, arc and clothoid segments with lanes.

Every segment has curvature linear in its arc length u, kappa(u) = k0 + (k1 - k0) u / L (straight:
k0 = k1 = 0; arc: k0 = k1), so the heading is a quadratic in s and the whole road is described by
one formula per segment. Positions are the integral of (cos, sin) of the heading: a table of exact
positions every <= 0.1 m (4-point Gauss-Legendre per interval, error ~1e-12 m) plus one more
Gauss-Legendre step from the nearest node to the query. Beyond its ends the road continues straight.

Frenet coordinates (s, r): s is arc length along the reference line, which is the middle of the
whole carriageway; r is lateral, positive to the left of the direction of travel. Lane boundary i
(0 = rightmost) lies at r = (i - n_lanes / 2) * lane_width_m.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, setting
from lanekeep.geometry.markings import MarkingPiece, MarkingStyle, default_markings, layout

__all__ = ["MarkingPiece", "MarkingStyle", "Road", "SegmentSpec"]

SEGMENT_KINDS = ("straight", "arc", "clothoid")
TABLE_STEP_M = 0.1  # spacing of the exact position table
# The longest road a scenario may build (its meshes and position table grow with it): 20 km,
# 18 minutes at 66 km/h; a longer drive laps a closed track (tools/soak).
MAX_ROAD_M = 20_000.0
# a five-lane carriageway: the widest the dataset (lanekeep/evaluation/dataset.py) builds
MAX_LANES = 5
# The road's lane width unless a scenario gives one: the truth, which scoring reads. The car's
# belief about lane widths is lanekeep/geometry/lane_width.py, the same number by design only.
DEFAULT_LANE_WIDTH_M = 3.7
COARSE_STEP_M = 0.5  # spacing of the nearest-point search table
LEAD_SEED_OFFSET = 7919  # worn paint before the start and after the end draws its own runs
_GL_X, _GL_W = np.polynomial.legendre.leggauss(4)  # Gauss-Legendre nodes/weights on [-1, 1]
_CHUNK = 1_000_000  # query points x coarse samples per argmin block (memory bound)


@dataclass(frozen=True)
class SegmentSpec:
    """One piece of the centreline. Curvature in 1/m, + = turning left."""

    kind: str = setting(doc="Shape of the piece: clothoid = curvature linear in s.",
                        choices=SEGMENT_KINDS)
    length_m: float = setting(doc="Arc length of the piece.",
                              allowed=f"(0, {MAX_ROAD_M:g}]; all pieces at most {MAX_ROAD_M:g}")
    curvature_1pm: float = setting(0.0, "arc: its curvature; clothoid: at its start. + = turning "
                                   "left, - = turning right (radius = 1 / |curvature|).",
                                   allowed="0 for straight")
    end_curvature_1pm: float = setting(0.0, "clothoid: curvature at its end; + = left.",
                                       allowed="0 (or equal to curvature_1pm) unless clothoid")

    def __post_init__(self):
        check_settings(self)
        if not 0 < self.length_m <= MAX_ROAD_M:
            raise InvalidValue("length_m", f"must be in (0, {MAX_ROAD_M:g}] m, got {self.length_m}")
        if self.kind == "straight" and self.curvature_1pm != 0:
            raise InvalidValue("curvature_1pm", "a straight segment has curvature 0")
        if self.kind != "clothoid" and self.end_curvature_1pm not in (0.0, self.curvature_1pm):
            raise InvalidValue("end_curvature_1pm", f"only a clothoid has one (kind {self.kind})")

    @property
    def start_curvature(self) -> float:
        return self.curvature_1pm

    @property
    def end_curvature(self) -> float:
        return self.end_curvature_1pm if self.kind == "clothoid" else self.curvature_1pm


class Road:
    """A road: centreline segments, lanes and markings. All methods are vectorised over s / xy."""

    def __init__(
        self,
        segments: Sequence[SegmentSpec],
        n_lanes: int = 2,
        lane_width_m: float = DEFAULT_LANE_WIDTH_M,
        markings: Sequence[MarkingStyle] | None = None,
        start_xy: Sequence[float] = (0.0, 0.0),
        start_heading_rad: float = 0.0,
        rng_seed: int = 0,
    ):
        if not segments:
            raise ValueError("a road needs at least one segment")
        if not 1 <= n_lanes <= MAX_LANES:
            raise ValueError(f"n_lanes must be 1..{MAX_LANES}, got {n_lanes}")
        if not lane_width_m > 0:
            raise ValueError(f"lane_width_m must be > 0, got {lane_width_m}")
        markings = tuple(markings) if markings else default_markings(n_lanes)
        if len(markings) != n_lanes + 1:
            raise ValueError(
                f"need {n_lanes + 1} marking styles (one per boundary), got {len(markings)}"
            )
        self.segments = tuple(segments)
        self.n_lanes = int(n_lanes)
        self.lane_width_m = float(lane_width_m)
        self.markings = markings
        self.rng_seed = int(rng_seed)

        # Per-segment heading polynomial: theta(s) = th0 + k0 (s - s0) + dk/2 (s - s0)^2.
        lengths = np.array([seg.length_m for seg in self.segments], dtype=float)
        self._s0 = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        self._k0 = np.array([seg.start_curvature for seg in self.segments])
        self._dk = np.array([seg.end_curvature for seg in self.segments]) - self._k0
        self._dk /= lengths
        th0 = [float(start_heading_rad)]
        for k0, dk, length in zip(self._k0, self._dk, lengths, strict=True):
            th0.append(th0[-1] + k0 * length + 0.5 * dk * length**2)
        self._th0 = np.array(th0[:-1])
        self.length_m = float(lengths.sum())

        # Exact position table: nodes at every segment start and <= TABLE_STEP_M apart.
        node_s, node_seg = [], []
        for i, (s0, length) in enumerate(zip(self._s0, lengths, strict=True)):
            n = max(1, math.ceil(length / TABLE_STEP_M))
            node_s.append(s0 + np.linspace(0.0, length, n + 1)[:-1])
            node_seg.append(np.full(n, i))
        self._node_s = np.concatenate(node_s + [[self.length_m]])
        self._node_seg = np.concatenate(node_seg)  # segment of the interval starting at node j
        steps = self._integrate(self._node_s[:-1], self._node_s[1:], self._node_seg)
        start = np.asarray(start_xy, dtype=float).reshape(1, 2)
        self._node_xy = np.concatenate([start, start + np.cumsum(steps, axis=0)])

        # Coarse table for the nearest-point search.
        n = max(2, math.ceil(self.length_m / COARSE_STEP_M) + 1)
        self._coarse_s = np.linspace(0.0, self.length_m, n)
        self._coarse_xy = self.position(self._coarse_s)

    # --- centreline ---------------------------------------------------------------------------

    def _seg_index(self, s: np.ndarray) -> np.ndarray:
        return np.clip(np.searchsorted(self._s0, s, side="right") - 1, 0, len(self.segments) - 1)

    def _theta(self, s: np.ndarray, seg: np.ndarray) -> np.ndarray:
        u = s - self._s0[seg]
        return self._th0[seg] + u * (self._k0[seg] + 0.5 * self._dk[seg] * u)

    def _integrate(self, a: np.ndarray, b: np.ndarray, seg: np.ndarray) -> np.ndarray:
        """Integral of (cos, sin)(theta) from a to b within segment `seg`; shape (..., 2)."""
        half = 0.5 * (b - a)[..., None]
        t = 0.5 * (a + b)[..., None] + half * _GL_X
        th = self._theta(t, seg[..., None])
        return np.stack([(np.cos(th) * _GL_W).sum(-1), (np.sin(th) * _GL_W).sum(-1)], -1) * half

    def heading_at(self, s):
        """Heading of the centreline at s (rad); constant beyond the ends."""
        sc = np.clip(np.asarray(s, dtype=float), 0.0, self.length_m)
        th = self._theta(sc, self._seg_index(sc))
        return float(th) if th.ndim == 0 else th

    @functools.cached_property
    def closed(self) -> bool:
        """The road ends where it starts, in the same direction (a track to lap): within
        1 mm and 1 mrad. Computed once (the road never changes; scoring asks every step)."""
        gap = np.hypot(*(self.position(self.length_m) - self.position(0.0)))
        turn = (self.heading_at(self.length_m) - self.heading_at(0.0) + math.pi) % (2 * math.pi)
        return bool(gap < 1e-3 and abs(turn - math.pi) < 1e-3)

    def curvature_at(self, s):
        """Curvature of the centreline at s (1/m, + = left); 0 beyond the ends."""
        s = np.asarray(s, dtype=float)
        seg = self._seg_index(s)
        k = self._k0[seg] + self._dk[seg] * (s - self._s0[seg])
        k = np.where((s < 0.0) | (s > self.length_m), 0.0, k)
        return float(k) if k.ndim == 0 else k

    def position(self, s, r=0.0) -> np.ndarray:
        """World XY of Frenet (s, r); shape broadcast(s, r) + (2,)."""
        return self._locate(s, r)[0]

    def geometry_at(self, s, r=0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`position(s, r)`, `heading_at(s)` and `curvature_at(s)` (as arrays, broadcast over
        s and r) from one search of the tables: each Newton step on the road (the Frenet
        projection, the truth's line points) asks for all three at the same s.

        The same numbers as the three calls: the node table's segment of a clipped s is the
        segment `_seg_index` finds (every segment starts at a node and none of its nodes
        reaches the next segment's start), and beyond the ends, where the curvature is 0, s
        clipped or not falls in the same end segment.
        """
        xy, th, s, seg = self._locate(s, r)
        k = self._k0[seg] + self._dk[seg] * (s - self._s0[seg])
        return xy, th, np.where((s < 0.0) | (s > self.length_m), 0.0, k)

    def _locate(self, s, r) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """World XY of Frenet (s, r), the heading there, s (broadcast) and its segment."""
        s, r = np.broadcast_arrays(np.asarray(s, dtype=float), np.asarray(r, dtype=float))
        sc = np.clip(s, 0.0, self.length_m)
        j = np.clip(np.searchsorted(self._node_s, sc, side="right") - 1, 0, len(self._node_seg) - 1)
        seg = self._node_seg[j]
        xy = self._node_xy[j] + self._integrate(self._node_s[j], sc, seg)
        th = self._theta(sc, seg)
        along = s - sc  # extrapolation beyond the ends, straight
        cos, sin = np.cos(th), np.sin(th)
        return xy + np.stack([along * cos - r * sin, along * sin + r * cos], -1), th, s, seg

    def local_coordinates(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """Frenet (s, r) of world points `xy` (..., 2): the nearest centreline point and offset.

        Coarse nearest sample (0.5 m table), then Newton on the exact geometry for the foot of the
        perpendicular: f(s) = (P(s) - p) . t(s) = 0, f'(s) = 1 - kappa(s) r.
        """
        xy = np.asarray(xy, dtype=float)
        shape = xy.shape[:-1]
        p = xy.reshape(-1, 2)
        s = np.empty(len(p))
        block = max(1, _CHUNK // len(self._coarse_s))
        for i in range(0, len(p), block):
            q = p[i : i + block]
            d2 = ((q[:, None, :] - self._coarse_xy[None, :, :]) ** 2).sum(-1)
            s[i : i + block] = self._coarse_s[np.argmin(d2, axis=1)]
        for _ in range(12):
            xy, th, k = self.geometry_at(s)
            d = p - xy
            t = np.stack([np.cos(th), np.sin(th)], -1)
            along = (d * t).sum(-1)
            r = d[:, 1] * t[:, 0] - d[:, 0] * t[:, 1]
            slope = np.maximum(1.0 - k * r, 0.2)
            ds = along / slope
            s = s + ds
            if np.all(np.abs(ds) < 1e-10):
                break
        xy, th, _, _ = self._locate(s, 0.0)
        d = p - xy
        r = d[:, 1] * np.cos(th) - d[:, 0] * np.sin(th)
        if not shape:
            return float(s[0]), float(r[0])
        return s.reshape(shape), r.reshape(shape)

    def segment_bounds(self) -> list[tuple[float, float]]:
        """[s_start, s_end) of each segment, in order."""
        ends = np.append(self._s0[1:], self.length_m)
        return [(float(a), float(b)) for a, b in zip(self._s0, ends, strict=True)]

    # --- lanes and markings -------------------------------------------------------------------

    def boundary_r(self, boundary: int) -> float:
        """Frenet r of lane boundary `boundary` (0 = rightmost edge, n_lanes = leftmost)."""
        if not 0 <= boundary <= self.n_lanes:
            raise IndexError(f"boundary {boundary} not in 0..{self.n_lanes}")
        return (boundary - 0.5 * self.n_lanes) * self.lane_width_m

    def lane_center_r(self, lane: int) -> float:
        """Frenet r of the centre of lane `lane` (0 = rightmost)."""
        if not 0 <= lane < self.n_lanes:
            raise IndexError(f"lane {lane} not in 0..{self.n_lanes - 1}")
        return (lane + 0.5 - 0.5 * self.n_lanes) * self.lane_width_m

    def marking_pieces(self, lead_m: float = 0.0) -> list[MarkingPiece]:
        """Every strip of paint, ordered by boundary, then s (then r for double lines).

        `lead_m` > 0 also paints the straight continuations `lead_m` before s = 0 and after
        the end (`position` extrapolates straight there), each laid out as a road of its own
        (dashes keep their period across s = 0 and the end; worn paint draws its own runs).
        The pieces on [0, length_m] do not depend on it.
        """
        joins = [a for a, _ in self.segment_bounds()[1:]]
        pieces = []
        for i, style in enumerate(self.markings):
            r = self.boundary_r(i)
            main = layout(style, i, r, self.length_m, joins, self.rng_seed)
            if lead_m <= 0.0:
                pieces += main
                continue
            periodic = style.kind in ("dashed", "dots") or (
                style.kind == "worn" and style.pattern == "dashed")
            period = style.dash_m + style.gap_m if periodic else 0.0
            before = math.ceil(lead_m / period) * period if period else lead_m
            extra = self.rng_seed + LEAD_SEED_OFFSET
            head = [replace(p, s_start_m=p.s_start_m - before, s_end_m=p.s_end_m - before)
                    for p in layout(style, i, r, before, (), extra)]
            tail_at = (math.ceil(self.length_m / period) * period if period
                       else self.length_m)
            tail_length = self.length_m + lead_m - tail_at
            tail = [replace(p, s_start_m=p.s_start_m + tail_at, s_end_m=p.s_end_m + tail_at)
                    for p in (layout(style, i, r, tail_length, (), extra + 1)
                              if tail_length > 0.0 else [])]
            pieces += head + main + tail
        return pieces
