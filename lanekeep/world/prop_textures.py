"""Seeded numpy textures of the roadside props: building facades with windows, signs, concrete
with joints, foliage. Real frames are full of edges above the horizon (windows, leaves, sign
lettering); flat-coloured props would leave the sky half of our frames as sterile as before.
"""

from __future__ import annotations

import numpy as np

from lanekeep.world.textures import periodic_blur, tiled_noise

FACADE_BAYS = 4  # window bays across a facade tile
FACADE_FLOORS = 4  # floors up a facade tile
FACADE_TILE_M = 12.0  # a facade tile is 4 bays of 3 m by 4 floors of 3 m
CONCRETE_TILE_M = 6.0  # barrier segments are cast 6 m long: one joint per tile
FOLIAGE_RGB = (0.3, 0.4, 0.17)  # lit leaves' albedo: dark olive green, as real crowns are


def _rgb8(rgb: np.ndarray) -> np.ndarray:
    return (np.clip(rgb, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def facade(rng: np.random.Generator, wall_rgb: tuple[float, float, float],
           size: int = 256) -> np.ndarray:
    """A facade tile (size, size, 3): FACADE_BAYS x FACADE_FLOORS windows in a grained wall.

    Windows differ pane by pane (sky reflections, blinds, a lit room) as real ones do; the tile
    repeats, so the pattern is drawn once per building kind."""
    wall = np.asarray(wall_rgb, np.float32) * (1.0 + 0.05 * tiled_noise(rng, size, 1.5))[..., None]
    img = wall.copy()
    bay, floor = size // FACADE_BAYS, size // FACADE_FLOORS
    win_w, win_h = int(bay * rng.uniform(0.45, 0.7)), int(floor * rng.uniform(0.4, 0.6))
    for i in range(FACADE_FLOORS):
        for j in range(FACADE_BAYS):
            y0 = i * floor + (floor - win_h) // 2
            x0 = j * bay + (bay - win_w) // 2
            frame = np.array([0.85, 0.85, 0.83]) if rng.random() < 0.5 else wall_rgb
            img[y0 - 2:y0 + win_h + 2, x0 - 2:x0 + win_w + 2] = np.asarray(frame) * 0.9
            glass = np.array([0.16, 0.2, 0.26]) * rng.uniform(0.7, 1.5)
            if rng.random() < 0.15:
                glass = np.array([0.55, 0.52, 0.45])  # blinds down
            ramp = np.linspace(1.25, 0.8, win_h)[:, None, None]  # sky reflected at the top
            img[y0:y0 + win_h, x0:x0 + win_w] = glass * ramp
            img[y0 + win_h // 2, x0:x0 + win_w] *= 0.6  # transom
    ledge = floor - 3
    for i in range(FACADE_FLOORS):
        img[i * floor + ledge:i * floor + ledge + 2] *= 0.75  # floor ledges cast a line
    return _rgb8(img)


def sign(rng: np.random.Generator, background: tuple[float, float, float],
         width_px: int = 256, height_px: int = 128) -> np.ndarray:
    """A direction sign: coloured panel, white border, rows of white 'lettering' blocks."""
    img = np.empty((height_px, width_px, 3), np.float32)
    img[:] = background
    b = max(height_px // 24, 2)
    img[b:2 * b] = img[-2 * b:-b] = 0.95
    img[:, b:2 * b] = img[:, -2 * b:-b] = 0.95
    rows = int(rng.integers(2, 4))
    row_h = (height_px - 6 * b) // rows
    for k in range(rows):
        y0 = 3 * b + k * row_h + row_h // 4
        x = 4 * b + int(rng.integers(0, 3 * b))
        end = width_px - 4 * b - int(rng.integers(0, width_px // 3))
        while x < end:
            w = int(rng.integers(b, 3 * b))
            img[y0:y0 + row_h // 2, x:min(x + w, end)] = 0.95
            x += w + int(rng.integers(b // 2 + 1, 2 * b)) if rng.random() < 0.8 else w + 4 * b
    return _rgb8(img)


def concrete(rng: np.random.Generator, size: int = 256) -> np.ndarray:
    """Light concrete with stains and one dark joint across the tile (CONCRETE_TILE_M)."""
    grey = 0.72 + 0.04 * tiled_noise(rng, size, 0.8) + 0.05 * tiled_noise(rng, size, 20.0)
    grey[:, :2] *= 0.55  # u runs along the road: a joint every tile
    stain = np.clip(tiled_noise(rng, size, 8.0), 0.0, None)
    grey -= 0.05 * stain * np.linspace(0.3, 1.0, size)[:, None]  # grime from the ground up
    return _rgb8(grey[..., None] * np.array([1.0, 0.99, 0.95], np.float32))


def foliage(rng: np.random.Generator, size: int = 128, underside: bool = False) -> np.ndarray:
    """Leaf clusters: clumps of lit leaves with dark gaps between them (the inside of a crown,
    in its own shade, shows through), the edges a crown shows against the sky. Real crowns
    are dark (V 40-60 of 255 in dashcam frames) with strong contrast at the clump scale.

    `underside`: the texture also darkens towards its bottom rows (v = 0: an ellipsoid's
    lowest point, prop_meshes.ellipsoid), the self-shade of a crown's underside, which the sky
    lights less than its top."""
    clumps = tiled_noise(rng, size, 3.0)
    leaves = tiled_noise(rng, size, 0.7)
    lit = 1.0 / (1.0 + np.exp(-2.2 * (clumps + 0.25)))  # 0 in the gaps between clumps
    grey = 0.16 + 0.62 * lit + 0.14 * leaves * (0.3 + lit)
    grey = periodic_blur(grey, 0.4)
    if underside:
        v = np.linspace(0.0, 1.0, size, dtype=np.float32)[:, None]
        grey = grey * (0.45 + 0.55 * np.clip(v / 0.6, 0.0, 1.0) ** 0.8)
    return _rgb8(grey[..., None] * np.array(FOLIAGE_RGB, np.float32))
