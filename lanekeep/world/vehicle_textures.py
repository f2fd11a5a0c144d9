"""The texture of a truck's box body and the textured box it is drawn on.

Why: an untextured box 10-16 m long is the largest flat surface in a traffic frame, and a
detector learns nothing about real trailers from a slab of one colour. Real box bodies show
vertical ribs or panel joints, rails at the top and bottom, often a plain stripe, and road dirt
thrown up from the wheels and streaked down by rain. The texture is grey (1 = the paint) and
multiplied by the vehicle's paint colour; it is drawn from a fixed seed, the same for every
truck (the paint differs).
"""

from __future__ import annotations

import numpy as np

from lanekeep.geometry.road_mesh import Ribbon

TRAILER_PANEL_M = 2.4  # horizontal run of one texture tile: four ribs 0.6 m apart
TRAILER_SEED = 0x7A11
_BOX_FACES = ((0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (4, 6, 7, 5))  # no bottom


def trailer_texture(size_px: int = 256) -> np.ndarray:
    """(size, size, 3) uint8: u runs along a side (TRAILER_PANEL_M a tile), v from the box's
    floor (row size-1) to its roof (row 0)."""
    rng = np.random.default_rng(TRAILER_SEED)
    n = size_px
    v = np.linspace(1.0, 0.0, n)[:, None]  # height share, 1 at the roof
    u = np.arange(n)[None, :]
    img = np.full((n, n), 0.93)
    rib = u % (n // 4)
    img = img - 0.14 * (rib < 3) + 0.05 * ((rib >= 3) & (rib < 6))  # a rib and its lit edge
    img = np.where((v > 0.965) | (v < 0.05), 0.62, img)  # top and bottom rails
    img = np.where((v > 0.2) & (v < 0.26), 0.45 * img, img)  # a plain stripe
    dirt = np.clip((0.35 - v) / 0.35, 0.0, 1.0) ** 1.5  # thrown up from the wheels
    dirt = dirt * (0.7 + 0.3 * rng.random((1, n)))
    streaks = np.convolve(rng.random(n), np.ones(5) / 5, "same")[None, :]  # rain runs down
    img = img * (1.0 - 0.35 * dirt) * (1.0 - 0.08 * streaks * v)
    img = img * (1.0 + 0.025 * rng.standard_normal((n, n)))
    tint = np.stack([img, img * 0.97, img * 0.92], -1)  # dirt is brown, not grey
    mix = dirt[..., None]
    rgb = tint * (1.0 - 0.3 * mix) + 0.3 * mix * np.array([0.42, 0.36, 0.28]) * img[..., None]
    return (np.clip(rgb, 0.0, 1.0) * 255.0).astype(np.uint8)


def textured_box(centre: tuple[float, float, float], half: tuple[float, float, float]) -> Ribbon:
    """An axis-aligned box (vehicle frame) without its bottom, each face with its own
    vertices, texcoords as `trailer_texture` expects: u = metres along the face over
    TRAILER_PANEL_M, v = depth share below the roof (row 0 of the texture)."""
    bits = np.array([[(k >> b) & 1 for b in range(3)] for k in range(8)], float) * 2.0 - 1.0
    corners = bits * np.asarray(half) + np.asarray(centre)
    quads = corners[np.array(_BOX_FACES)]
    z0, z1 = centre[2] - half[2], centre[2] + half[2]
    uvs = np.zeros((len(quads), 4, 2))
    for k, q in enumerate(quads):
        if np.ptp(q[:, 2]) < 1e-9:  # the roof: its x and y
            uvs[k] = q[:, :2] / TRAILER_PANEL_M
            continue
        run = q[:, 0] if np.ptp(q[:, 0]) > 1e-9 else q[:, 1]
        uvs[k, :, 0] = run / TRAILER_PANEL_M
        uvs[k, :, 1] = (z1 - q[:, 2]) / (z1 - z0)  # MuJoCo: v = 0 is the image's row 0
    base = 4 * np.arange(len(quads))[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]]).astype(np.int32)
    # Wind each face counter-clockwise seen from outside (normal away from the centre).
    verts = quads.reshape(-1, 3)
    tri = verts[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    flip = np.einsum("nd,nd->n", normal, tri.mean(1) - np.asarray(centre)) < 0.0
    faces[flip] = faces[flip][:, ::-1]
    return Ribbon(verts, faces, uvs.reshape(-1, 2))
