"""The pavement texture: asphalt or concrete lanes with joints, cracks, patches and tyre marks,
and the structure of real roads that a lane detector may take for a line (TuSimple's frames show
all of it): tar lines (crack sealant), a longitudinal construction seam a little inside the
lane line, the dark oil stripe down the lane's centre beside polished wheel paths; and, along
the road, sections of another surface (`sections`, `section_style`: build.py gives them their
own atlas and cuts the road's mesh at their straight transverse ends).

One texture is an atlas of one lane beside one shoulder: columns [0, LANE_U) hold a lane from
its right boundary to its left one, columns [LANE_U, 1) a shoulder from the edge line outwards;
rows run along the road over `period_m`. build.py maps each lane and each shoulder of the road
onto its part, so wheel paths lie in every lane (not on the shoulders), concrete's longitudinal
joints fall on the lane lines and its transverse joints every SLAB_M across the whole road.
The period (9 m) is longer than a dash plus its gap is short, and each lane starts the texture
at a different row, so the eye finds no seam running down the road (the old 4 m asphalt tile
had two tar seams that ran the road's whole length).
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from lanekeep.scenario.pavement import PavementStyle
from lanekeep.world.textures import periodic_blur, tiled_noise, to_rgb8

LANE_U = 0.75  # share of the atlas' width that holds the lane
SLAB_M = 4.5  # concrete slab length between transverse joints
WHEEL_TRACK_M = 1.7  # distance between a car's wheel paths
ASPHALT_TINT = (1.0, 1.0, 1.02)
CONCRETE_TINT = (1.0, 0.99, 0.95)
TAR_GREY = 0.07  # crack sealant: near black, whatever the surface's age
SEAM_INSET_M = (0.12, 0.45)  # the seam's distance inside the lane's left line
SECTION_M = (25.0, 120.0)  # length of a section of another surface


def _fold(canvas: np.ndarray, rows: int) -> np.ndarray:
    """A canvas three periods tall (drawn in the middle one) folded onto one period, so that
    what crosses the top or bottom edge comes back on the other side: the texture tiles."""
    return canvas[:rows] + canvas[rows:2 * rows] + canvas[2 * rows:]


def _crack_map(rng: np.random.Generator, shape: tuple[int, int], count: int, px_per_m: float,
               concrete: bool) -> np.ndarray:
    """Darkening (0..1) of meandering cracks: on asphalt mostly lengthwise and often sealed
    (a wide band of black sealant), on concrete thin and mostly across the slab."""
    rows, cols = shape
    canvas = np.zeros((3 * rows, cols), np.uint8)
    for _ in range(count):
        lengthwise = rng.random() < (0.25 if concrete else 0.65)
        length_px = rng.uniform(0.8, 4.0) * px_per_m
        heading = (0.0 if lengthwise else np.pi / 2) + rng.normal(0.0, 0.25)
        steps = max(int(length_px / 6.0), 2)
        turn = np.cumsum(rng.normal(0.0, 0.35, steps))
        xy = np.cumsum(6.0 * np.stack([np.sin(heading + turn), np.cos(heading + turn)], 1), 0)
        xy += [rng.uniform(0, cols), rows + rng.uniform(0, rows)]
        sealed = not concrete and rng.random() < 0.6
        width = int(rng.uniform(0.015, 0.03) * px_per_m) if sealed else 1
        shade = int(rng.uniform(150, 230) if sealed else rng.uniform(120, 200))
        cv2.polylines(canvas, [np.round(xy).astype(np.int32)], False, shade, max(width, 1),
                      cv2.LINE_AA)
    return np.clip(_fold(canvas.astype(np.float32) / 255.0, rows), 0.0, 1.0)


def _patch_map(rng: np.random.Generator, shape: tuple[int, int], count: int,
               px_per_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Repairs: rectangles of newer, darker asphalt (value) and their sealed outlines."""
    rows, cols = shape
    fill = np.zeros((3 * rows, cols), np.float32)
    edge = np.zeros((3 * rows, cols), np.uint8)
    for _ in range(count):
        w, h = rng.uniform(0.5, 2.2) * px_per_m, rng.uniform(0.8, 4.0) * px_per_m
        x, y = rng.uniform(0, max(cols - w, 1)), rows + rng.uniform(0, rows)
        p0, p1 = (int(x), int(y)), (int(x + w), int(y + h))
        cv2.rectangle(fill, p0, p1, float(rng.uniform(0.6, 1.0)), -1)
        cv2.rectangle(edge, p0, p1, 255, 2)
    return np.clip(_fold(fill, rows), 0, 1), np.clip(_fold(edge / 255.0, rows), 0, 1)


def _tar_map(rng: np.random.Generator, shape: tuple[int, int], count: int,
             px_per_m: float) -> np.ndarray:
    """Coverage (0..1) of crack sealant: bands 3-7 cm wide that follow long, gently meandering
    cracks, three in four along the road (1.5-6 m), the rest across it (thermal cracks)."""
    rows, cols = shape
    canvas = np.zeros((3 * rows, cols), np.uint8)
    step_px = 4.0
    for _ in range(count):
        lengthwise = rng.random() < 0.75
        length_px = (rng.uniform(1.5, 6.0) if lengthwise else rng.uniform(0.6, 3.5)) * px_per_m
        heading = (0.0 if lengthwise else np.pi / 2) + rng.normal(0.0, 0.12)
        steps = max(int(length_px / step_px), 2)
        turn = np.cumsum(rng.normal(0.0, 0.04, steps))  # gentle drift
        turn += 0.15 * np.sin(np.linspace(0.0, rng.uniform(2.0, 8.0), steps)
                              + rng.uniform(0.0, 2.0 * np.pi))  # a slow meander
        turn += rng.normal(0.0, 0.35, steps)  # and the crack's own zigzag
        xy = np.cumsum(step_px * np.stack([np.sin(heading + turn), np.cos(heading + turn)], 1),
                       0)
        xy += [rng.uniform(0, cols), rows + rng.uniform(0, rows)]
        width = max(int(round(rng.uniform(0.025, 0.06) * px_per_m)), 2)
        shade = int(rng.uniform(170, 255))  # older sealant is greyer
        cv2.polylines(canvas, [np.round(xy).astype(np.int32)], False, shade, width, cv2.LINE_AA)
    return np.clip(_fold(canvas.astype(np.float32) / 255.0, rows), 0.0, 1.0)


def _seam(rng: np.random.Generator, shape: tuple[int, int], lane_width_m: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """A straight longitudinal construction seam SEAM_INSET_M inside the lane's left line (the
    atlas' last column): its darkening (0..1; about 2 cm wide, in places sealed wider and
    darker) and the strip beyond it (0..1, soft-edged), laid by the other paving pass."""
    rows, cols = shape
    px_per_m = cols / lane_width_m
    x0 = cols - rng.uniform(*SEAM_INSET_M) * px_per_m
    x = x0 + 0.6 * tiled_noise(rng, (rows, 1), 30.0)  # barely wanders
    col = np.arange(cols)[None, :] + 0.5
    sealed = np.clip(0.5 + 0.8 * tiled_noise(rng, (rows, 1), 60.0), 0.0, 1.0)
    sigma = 0.008 * px_per_m * (1.0 + 1.5 * sealed)
    line = (0.45 + 0.55 * sealed) * np.exp(-0.5 * ((col - x) / np.maximum(sigma, 0.7)) ** 2)
    beyond = np.clip(col - x, 0.0, 1.0)
    return line.astype(np.float32), beyond.astype(np.float32)


def _lane_profile(cols: int, lane_width_m: float, sigma_m: float) -> tuple[np.ndarray, ...]:
    """Across one lane: the two wheel paths and the oil strip between them (0..1)."""
    r = (np.arange(cols) + 0.5) / cols * lane_width_m - 0.5 * lane_width_m
    paths = sum(np.exp(-0.5 * ((r - c) / sigma_m) ** 2)
                for c in (-0.5 * WHEEL_TRACK_M, 0.5 * WHEEL_TRACK_M))
    oil = np.exp(-0.5 * (r / 0.3) ** 2)
    return paths.astype(np.float32), oil.astype(np.float32)


def surface_albedo(style: PavementStyle) -> float:
    """The base reflectance (grey) of the carriageway's surface, before grain, marks and cracks:
    light concrete slabs, or asphalt from fresh black to sun-bleached grey."""
    return 0.62 if style.surface == "concrete" else 0.24 + 0.16 * style.asphalt_tone


def _part(rng: np.random.Generator, style: PavementStyle, rows: int, cols: int,
          width_m: float, period_m: float, lane: bool) -> np.ndarray:
    """Grey (rows, cols) of the lane or the shoulder part of the atlas."""
    concrete = style.surface == "concrete"
    px_per_m = rows / period_m
    shape = (rows, cols)
    base = surface_albedo(style)
    grey = np.full(shape, base, np.float32)
    grey += (0.02 if concrete else 0.05) * tiled_noise(rng, shape, 0.6)  # aggregate grain
    stones = rng.random(shape)
    grey += np.where(stones > 0.985, 0.10, 0.0) - np.where(stones < 0.01, 0.06, 0.0)
    grey += 0.012 * tiled_noise(rng, shape, 12.0) + 0.025 * tiled_noise(rng, shape, 80.0)
    if lane and style.tyre_marks > 0.0:
        paths, oil = _lane_profile(cols, width_m, 0.28)
        along = 0.7 + 0.3 * tiled_noise(rng, shape, 40.0)
        blotch = np.clip(0.6 + 0.6 * tiled_noise(rng, shape, 8.0), 0.0, 1.0)
        k = style.tyre_marks * (2.0 if concrete else 1.0)
        grey -= k * (0.09 * paths[None, :] * along + 0.07 * oil[None, :] * blotch)
    n_patches = rng.poisson(style.patches * (2.0 if lane else 0.7))
    if n_patches:
        fill, outline = _patch_map(rng, shape, n_patches, px_per_m)
        patch_grey = (0.30 if concrete else base - 0.07) + 0.04 * tiled_noise(rng, shape, 0.6)
        grey = grey * (1 - fill) + patch_grey * fill - 0.06 * outline
    n_cracks = rng.poisson(style.cracks * (12.0 if lane else 3.0))
    if n_cracks:
        grey -= (0.25 if concrete else 0.18) * _crack_map(rng, shape, n_cracks, px_per_m,
                                                          concrete)
    if concrete:
        joints = np.zeros(shape, np.float32)
        for s_m in np.arange(0.0, period_m - 1e-6, SLAB_M):  # transverse joints
            joints[int(round(s_m * px_per_m)) % rows, :] = 1.0
            slab = slice(int(round(s_m * px_per_m)), int(round((s_m + SLAB_M) * px_per_m)))
            grey[slab] += rng.normal(0.0, 0.02)  # each slab's own shade
        if lane:
            joints[:, 0] = joints[:, -1] = 1.0  # longitudinal joints under the lane lines
        grey -= 0.22 * np.clip(periodic_blur(joints, 0.7) * 2.0, 0.0, 1.0)
    # The structure keys draw after everything above, and only when set: a scenario without
    # them keeps its texture to the texel.
    if lane and style.oil_stripe > 0.0:
        paths, _ = _lane_profile(cols, width_m, 0.3)
        r = (np.arange(cols) + 0.5) / cols * width_m - 0.5 * width_m
        stripe = np.exp(-0.5 * (np.abs(r) / 0.32) ** 4)  # flat-topped, ~0.7 m wide
        drips = np.clip(0.55 + 0.5 * tiled_noise(rng, shape, 10.0)
                        + 0.25 * tiled_noise(rng, shape, 2.0), 0.0, 1.2)
        k = style.oil_stripe * (1.6 if concrete else 1.0)
        grey -= k * 0.09 * stripe[None, :] * drips
        grey += k * 0.025 * paths[None, :] * (0.8 + 0.2 * tiled_noise(rng, shape, 40.0))
    if lane and style.seams > 0.0:
        line, beyond = _seam(rng, shape, width_m)
        grey += style.seams * rng.choice([-1.0, 1.0]) * rng.uniform(0.02, 0.04) * beyond
        grey -= style.seams * (0.22 if concrete else 0.18) * line
    n_tar = rng.poisson(style.tar_lines * (9.0 if lane else 2.5)) if style.tar_lines else 0
    if n_tar:
        tar = _tar_map(rng, shape, n_tar, px_per_m)
        tar_grey = (TAR_GREY + (0.10 if concrete else 0.0)  # on concrete: dust-greyed
                    + 0.015 * tiled_noise(rng, shape, 1.0))
        grey = grey * (1.0 - 0.9 * tar) + tar_grey * 0.9 * tar
    return grey


def pavement(rng: np.random.Generator, style: PavementStyle, lane_width_m: float,
             shoulder_m: float, period_m: float, rows: int = 1024) -> np.ndarray:
    """The atlas RGB (rows, rows // 2, 3) uint8: one lane, then one shoulder (see the module)."""
    cols = rows // 2
    lane_cols = int(round(LANE_U * cols))
    lane = _part(rng, style, rows, lane_cols, lane_width_m, period_m, lane=True)
    shoulder = _part(rng, style, rows, cols - lane_cols, shoulder_m, period_m, lane=False)
    grey = np.clip(np.concatenate([lane, shoulder], axis=1), 0.02, 1.0)
    return to_rgb8(grey, CONCRETE_TINT if style.surface == "concrete" else ASPHALT_TINT)


def section_style(style: PavementStyle) -> PavementStyle:
    """The surface of the road's sections of `style.section_surface`: repaved is new, dark
    asphalt (no cracks, patches or tar yet, faint wheel paths, the seams of its paving passes);
    asphalt and concrete keep the road's wear."""
    if style.section_surface == "repaved":
        return dataclasses.replace(style, surface="asphalt", asphalt_tone=0.05, cracks=0.0,
                                   patches=0.0, tyre_marks=0.3 * style.tyre_marks,
                                   tar_lines=0.0, oil_stripe=0.4 * style.oil_stripe,
                                   surface_changes=0.0)
    return dataclasses.replace(style, surface=style.section_surface, surface_changes=0.0)


def sections(rng: np.random.Generator, s0: float, s1: float, share: float
             ) -> list[tuple[float, float]]:
    """[s0, s1) intervals of the other surface: SECTION_M long, about `share` of the road,
    alternating with the road's own surface, which starts (the car's start sees it)."""
    if share <= 0.0:
        return []
    mean_other = 0.5 * sum(SECTION_M)
    out, s = [], s0 + rng.exponential(mean_other * (1.0 - share) / share)
    while s < s1:
        end = s + rng.uniform(*SECTION_M)
        out.append((s, min(end, s1)))
        s = end + rng.exponential(mean_other * (1.0 - share) / share)
    return out
