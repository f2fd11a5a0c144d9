"""Triangle ribbons that follow the road in Frenet coordinates, for MuJoCo meshes.

A ribbon spans [s0, s1] along the road and [r_right, r_left] across it; it is sampled densely
enough along s that its chords stay within a few millimetres of the true curve. Faces wind
counter-clockwise seen from above so that their normals point up (lit, not culled).
Texture coordinates are in metres divided by the texture's tile size, so the asphalt grain has
the same scale everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lanekeep.geometry.road import Road

MAX_CHORD_ERROR_M = 0.003


@dataclass(frozen=True)
class Ribbon:
    """Mesh arrays: vertices (N, 3), faces (M, 3) int, texcoords (N, 2)."""

    vertices: np.ndarray
    faces: np.ndarray
    texcoords: np.ndarray

    @staticmethod
    def concatenate(ribbons: list[Ribbon]) -> Ribbon:
        """One mesh from many ribbons (fewer geoms render faster)."""
        verts, faces, uvs, offset = [], [], [], 0
        for ribbon in ribbons:
            verts.append(ribbon.vertices)
            faces.append(ribbon.faces + offset)
            uvs.append(ribbon.texcoords)
            offset += len(ribbon.vertices)
        return Ribbon(np.concatenate(verts), np.concatenate(faces), np.concatenate(uvs))


def sample_s(road: Road, s0: float, s1: float, max_step_m: float = 2.0) -> np.ndarray:
    """Stations from s0 to s1 whose chords deviate at most MAX_CHORD_ERROR_M from the curve.

    Chord sagitta on a curve of radius R for a step h is h^2 / (8 R), so h = sqrt(8 R e).
    """
    probe = np.linspace(s0, s1, max(int((s1 - s0) / 0.5) + 2, 2))
    kappa = float(np.max(np.abs(road.curvature_at(probe)))) if len(probe) else 0.0
    step = max_step_m if kappa < 1e-6 else min(max_step_m, np.sqrt(8.0 * MAX_CHORD_ERROR_M / kappa))
    n = max(int(np.ceil((s1 - s0) / step)), 1)
    return np.linspace(s0, s1, n + 1)


def ribbon(
    road: Road,
    s0: float,
    s1: float,
    r_right: float,
    r_left: float,
    z_m: float,
    tile_m: float = 4.0,
    max_step_m: float = 2.0,
) -> Ribbon:
    """A strip of the road surface between two lateral offsets (r_right < r_left)."""
    s = sample_s(road, s0, s1, max_step_m)
    right = road.position(s, np.full_like(s, r_right))
    left = road.position(s, np.full_like(s, r_left))
    n = len(s)
    verts = np.zeros((2 * n, 3))
    verts[0::2, :2] = right
    verts[1::2, :2] = left
    verts[:, 2] = z_m
    uv = np.zeros((2 * n, 2))
    uv[0::2, 0] = r_right / tile_m
    uv[1::2, 0] = r_left / tile_m
    uv[0::2, 1] = s / tile_m
    uv[1::2, 1] = s / tile_m
    i = np.arange(n - 1)
    r0, l0, r1, l1 = 2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3
    faces = np.concatenate([np.stack([r0, r1, l0], 1), np.stack([r1, l1, l0], 1)])
    return Ribbon(verts, faces.astype(np.int32), uv)
