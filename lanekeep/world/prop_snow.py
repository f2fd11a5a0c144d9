"""Snow lying on the roadside props in a snowy scenario: on the tree crowns and on top of the
guard rails, their posts and the concrete barriers.

Where snow falls it lies on everything that faces up: a crown in a snowfall is patched white
over its dark leaves, and a W-beam carries a ragged white ridge along its top fold. Without it
the snow scenario showed summer-green trees and spotless rails beside white verges. Every draw
here comes from a generator of its own ([scenario seed, PROP_SNOW_SEED]), so the props' other
draws do not move.
"""

from __future__ import annotations

import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon
from lanekeep.world.parts import WorldLayout
from lanekeep.world.prop_meshes import box, extrude
from lanekeep.world.textures import tiled_noise

PROP_SNOW_SEED = 0x5A0F
SNOW_RGB = (0.93, 0.94, 0.97)  # the snow cover's tint (lanekeep/world/roadside.py add_snow)
SNOW_MATERIAL = "prop_snow"
# Share of a crown's texture under snow at snow = 1 (light leaf clusters first: their tops
# catch it), and how dark the leaves under it look (wet, in the overcast's flat light).
CROWN_COVER_AT_1 = 0.75
WINTER_LEAF = 0.7
TINT_KEPT = 0.35  # a foliage material's tint keeps this share of its colour (snow stays white)
# Snow ridges (outwards, up; m; convex, their undersides inside the body they lie on): 2-3.5
# cm on a W-beam's top fold (lanekeep/world/prop_assets.py RAIL_PROFILE), 3.5 cm on a jersey
# barrier's top; they break into pieces RIDGE_M long with gaps GAP_M between.
RAIL_RIDGE = np.array([[0.04, 0.745], [0.03, 0.76], [0.0, 0.77], [-0.05, 0.735],
                       [-0.09, 0.675], [-0.08, 0.665]])
BARRIER_RIDGE = np.array([[0.22, 0.805], [0.39, 0.805], [0.37, 0.83], [0.305, 0.845],
                          [0.24, 0.83]])
POST_CAP_M = 0.03
RIDGE_M = (2.0, 12.0)
GAP_M = (0.3, 2.5)


def snowy_foliage(leaves: np.ndarray, rng: np.random.Generator, snow: float) -> np.ndarray:
    """A foliage texture (RGB uint8) with snow on it: white where its light leaf clusters lie
    (plus seeded clumps), the leaves between darker."""
    grey = leaves.astype(np.float32).mean(-1)
    grey = (grey - grey.mean()) / max(float(grey.std()), 1e-6)
    field = grey + 0.8 * tiled_noise(rng, leaves.shape[:2], 2.0)
    cover = min(1.0, CROWN_COVER_AT_1 * snow)
    white = field >= np.quantile(field, 1.0 - cover)
    out = leaves.astype(np.float32) * WINTER_LEAF
    out[white] = np.asarray(SNOW_RGB, np.float32) * 255.0 * (0.92 + 0.08 * np.clip(
        grey[white, None] / 2.0, -1.0, 1.0))
    return np.clip(out + 0.5, 0, 255).astype(np.uint8)


def snowy_tint(rgba: tuple[float, ...]) -> list[float]:
    """A foliage material's tint under snow: mostly white, so that the snow on it stays white."""
    return [1.0 - TINT_KEPT * (1.0 - c) for c in rgba[:3]] + [float(rgba[3])]


def ridge_pieces(road: Road, s0: float, s1: float, rng: np.random.Generator
                 ) -> list[tuple[float, float]]:
    """(from, to) arc lengths of the pieces a snow ridge along s0..s1 breaks into."""
    pieces, s = [], s0 + float(rng.uniform(0.0, GAP_M[1]))
    while s < s1:
        end = min(s1, s + float(rng.uniform(*RIDGE_M)))
        pieces.append((s, end))
        s = end + float(rng.uniform(*GAP_M))
    return pieces


def ridge(road: Road, r0: float, sign: float, profile: np.ndarray, rng: np.random.Generator,
          layout: WorldLayout) -> list[Ribbon]:
    """Meshes of a ragged snow ridge (pieces and gaps) on a barrier's profile at r0 (`sign` +1
    on the left of the road), along the whole road and its leads."""
    rz = np.c_[r0 + sign * profile[:, 0], profile[:, 1]]
    return [extrude(road, s0, s1, rz)[0]
            for s0, s1 in ridge_pieces(road, -layout.lead_m, road.length_m + layout.lead_m, rng)]


def post_caps(road: Road, s: np.ndarray, r: float, top_m: float) -> list[Ribbon]:
    """A snow cap on each guard-rail post's top (posts at arc lengths s, offset r)."""
    posts = road.position(s, np.full(len(s), r))
    half = 0.5 * POST_CAP_M
    return [box(np.r_[xy, top_m + half], float(th), (0.05, 0.07, half))
            for xy, th in zip(posts, np.asarray(road.heading_at(s), float), strict=True)]
