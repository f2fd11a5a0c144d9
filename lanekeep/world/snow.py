"""Snow lying on the carriageway: packed bands where the wheels do not go.

On a snowy highway the wheel paths are driven clear and the snow stays between them: down the
middle of each lane and over the lane lines, where it hides the paint in places. Each band is
an opaque mesh in GROUP_WORLD just above the paint, so the segmentation render (which shows
that group) loses the paint it hides too: the marking masks stay the visible paint. Band edges
are ragged and their width drifts along the road, so no edge runs straight and parallel to the
lanes as a painted line would (the old translucent drifts had straight edges that looked like
lane lines). The bands break where they narrow to nothing.
"""

from __future__ import annotations

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon
from lanekeep.scenario.conditions import Conditions
from lanekeep.world.groups import GROUP_SHADOW, GROUP_WORLD
from lanekeep.world.parts import MARKING_Z_M, OVERLAY_Z_M, WorldLayout, add_mesh_geom

SNOW_Z_M = 0.5 * (MARKING_Z_M + OVERLAY_Z_M)  # over the paint, under shadows and puddles
STEP_M = 0.3  # sampling of the band edges along the road
DRIFT_SIGMA_M = 4.0  # a band's width drifts over this length ...
RAGGED_SIGMA_M = 0.4  # ... and its edges are ragged at this one
WHEEL_CLEAR_M = 0.55  # half-width kept free around a lane's centre line of wheel paths: the
# wheel paths lie 0.85 m either side of a lane's centre, 1.0 m from its boundaries


def _smooth(rng: np.random.Generator, n: int, sigma_m: float) -> np.ndarray:
    """Zero-mean, unit-std noise along the road, correlated over `sigma_m`."""
    sigma = max(sigma_m / STEP_M, 0.5)
    half = int(3 * sigma) + 1
    kernel = np.exp(-0.5 * (np.arange(-half, half + 1) / sigma) ** 2)
    noise = np.convolve(rng.standard_normal(n + 2 * half), kernel, mode="valid")
    return (noise - noise.mean()) / max(float(noise.std()), 1e-9)


def _band_mesh(road: Road, s: np.ndarray, r_right: np.ndarray, r_left: np.ndarray,
               min_width_m: float = 0.03) -> Ribbon | None:
    """Quads between two ragged edges, left out where the band is narrower than
    `min_width_m` (the snow breaks there)."""
    keep = (r_left - r_right) > min_width_m
    quads = np.flatnonzero(keep[:-1] & keep[1:])
    if len(quads) == 0:
        return None
    right = road.position(s, r_right)
    left = road.position(s, r_left)
    n = len(s)
    verts = np.zeros((2 * n, 3))
    verts[0::2, :2], verts[1::2, :2] = right, left
    verts[:, 2] = SNOW_Z_M
    r0, l0, r1, l1 = 2 * quads, 2 * quads + 1, 2 * quads + 2, 2 * quads + 3
    faces = np.concatenate([np.stack([r0, r1, l0], 1), np.stack([r1, l1, l0], 1)])
    uv = np.zeros((2 * n, 2))
    uv[0::2, 0], uv[1::2, 0] = r_right / 2.0, r_left / 2.0
    uv[0::2, 1] = uv[1::2, 1] = s / 2.0
    return Ribbon(verts, faces.astype(np.int32), uv)


def add_snow_cover(spec: mujoco.MjSpec, road: Road, cond: Conditions,
                   rng: np.random.Generator, layout: WorldLayout, material: str,
                   slush_material: str) -> int:
    """Snow bands over every lane line (and the shoulders beyond the edge lines), opaque; grey
    translucent slush down every lane's middle, where no paint lies, so it may stay out of the
    segmentation render (GROUP_SHADOW); returns how many band geoms were added."""
    s = np.arange(-layout.lead_m, road.length_m + layout.lead_m + STEP_M, STEP_M)
    n = len(s)
    amount = cond.snow
    added = 0

    def band(name: str, centre: np.ndarray, half: np.ndarray, mat: str, group: int) -> None:
        nonlocal added
        ragged = 0.04 + 0.06 * amount
        right = centre - half + ragged * _smooth(rng, n, RAGGED_SIGMA_M)
        left = centre + half + ragged * _smooth(rng, n, RAGGED_SIGMA_M)
        mesh = _band_mesh(road, s, right, left)
        if mesh is not None:
            add_mesh_geom(spec, name, mesh, mat, group)
            added += 1

    for b in range(road.n_lanes + 1):  # over the lines: wander about them, hide them in places
        r_b = road.boundary_r(b)
        half = np.clip(amount * (0.03 + 0.1 * _smooth(rng, n, DRIFT_SIGMA_M)), 0.0,
                       0.5 * road.lane_width_m - WHEEL_CLEAR_M - 0.3)
        centre = r_b + 0.12 * _smooth(rng, n, DRIFT_SIGMA_M)
        if b in (0, road.n_lanes):  # the shoulder is snowed in, up to about the edge line
            outward = -1.0 if b == 0 else 1.0
            outer = r_b + outward * (layout.shoulder_m + 0.3)  # ragged edge on the gravel
            inner = r_b + outward * (0.45 - 0.3 * amount + 0.15 * _smooth(rng, n, DRIFT_SIGMA_M))
            half = np.abs(outer - inner) / 2.0
            centre = (outer + inner) / 2.0
        band(f"cond_snow_line_{b}", centre, half, material, GROUP_WORLD)
    for lane in range(road.n_lanes):  # down the middle of each lane: grey, thin slush
        half = np.clip(amount * (0.15 + 0.15 * _smooth(rng, n, DRIFT_SIGMA_M)), 0.0,
                       WHEEL_CLEAR_M)
        centre = road.lane_center_r(lane) + 0.08 * _smooth(rng, n, DRIFT_SIGMA_M)
        band(f"cond_snow_lane_{lane}", centre, half, slush_material, GROUP_SHADOW)
    return added
