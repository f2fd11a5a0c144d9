"""Lane paint that stays a line in the distance: paint drawn as a filtered texture.

Why: beyond ~30 m a 0.15 m line is less than a pixel across, and rasterised geometry (one
sample per pixel; MuJoCo's multisampling costs 2.5x a frame on a CPU) hits or misses it pixel
by pixel, so a solid line breaks into dots that change from frame to frame. For the RGB render
each strip of fresh paint is instead a ribbon SPREAD times its width, textured opaque paint in
its middle and transparent beside it. The texture's v coordinate is the same all along the
road, so MuJoCo's isotropic mip-mapping (the level follows the larger footprint, here the one
across the line) filters only across the line: a distant line fades to a faint continuous one
instead of breaking up. The thin geometry stays, for the segmentation render only, so the
marking masks are as exact as before (lanekeep/sensing/cameras.py hides each from the other render).

What MuJoCo's translucent pass does to it (mjr_render, stated where it matters):
  - translucent geoms are drawn twice (front to back, then back to front, depth writes off),
    so a filtered alpha a shows as 1 - (1 - a)^2: where a line is far thinner than a pixel it
    looks up to twice as bright as its true coverage (still far closer than hit-or-miss);
  - translucent geoms receive no shadow map (camera shadow maps are off by default; the world's
    shadows are translucent overlays);
  - the order within each pass follows distance minus bounding radius. Overlays on the road
    (shadows, puddles, snow) must be drawn after the paint, or a shadow would not darken the
    paint it falls on: `draw_overlays_last` gives each overlay mesh a tiny buried triangle far
    away, which makes it the nearest by that measure (drawn first, and last in the second
    pass). Paint under an overlay is still darkened once, not twice: a shadow that leaves 0.4
    of the light on asphalt would leave sqrt(0.4) = 0.63 on a ribbon, so paint inside a static
    cast shadow is drawn as geometry instead (world._add_markings); under moving vehicles'
    shadows the ribbons keep that error.
"""

from __future__ import annotations

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon, ribbon

SPREAD = 4.0  # ribbon width / paint width: room for the mip levels to spread the line into
TEXELS = 64  # across the ribbon
PAINT_ALPHA = 0.99  # material alpha: below 0.995 puts the geom in MuJoCo's translucent pass
LIFT_M = 0.002  # above the thin paint geometry
FAR_M = 5000.0  # the ordering triangle's distance: beyond any bounding radius of the road
FAR_DEPTH_M = 50.0  # ... and this far under the ground, where no camera sees it
FAR_SIZE_M = 1e-4  # its size: no area to speak of (a moving overlay's inertia stays as it was)

# How paint looks on a road in use (the marking's `colour` is its pigment's hue). Road paint
# in dashcam frames stands 40-70 DN above the asphalt (TuSimple: a median of about 55 where
# paint is), not 100-150: beads wear off, tyres and dust grey it. Fresh paint reflects
# FRESH_ALBEDO, and at least PAINT_OVER_SURFACE times the surface's own grey (light concrete,
# lanekeep/world/pavement.surface_albedo: white paint on concrete is a faint line, not a dark
# one). Along the road a seeded wear drifts over WEAR_PERIOD_M / WEAR_ROWS metres: some dashes
# and stretches keep only FADED_SHARE of the paint. Wear is lost paint, so it lowers the
# paint's coverage (the texture's alpha) and the surface shows through; worn levels (faded
# chips of a worn line) fade towards the surface's grey, never below it.
FRESH_ALBEDO = 0.60
PAINT_OVER_SURFACE = 1.25
FADED_SHARE = 0.62
ROAD_ALBEDO = 0.32  # mid-tone asphalt (pavement.surface_albedo at asphalt_tone 0.5)
WEAR_PERIOD_M = 256.0  # the wear texture repeats along the road after this
WEAR_ROWS = 64  # texels along it: 4 m each, linearly filtered
EDGE_TEXELS = 2.0  # an edge's alpha ramps over this many texels (soft, as sprayed paint is)
WORN_TEXELS = 128  # worn paint texture: per metre (mesh uv in metres), 8 mm texels
WORN_HOLE_SHARE = 0.3  # of a worn chip where the paint has flaked off (asphalt shows)
# Paint in a cast shadow is opaque geometry with the grain texture (mean GRAIN_MEAN,
# lanekeep/world/textures.py); `shaded_rgb` gives it the ribbons' mean look: their mean wear
# (MEAN_WEAR of the paint shows, the surface the rest).
GRAIN_MEAN = 0.93
MEAN_WEAR = 0.82


def shaded_rgb(paint: list[float], surface: float) -> list[float]:
    """Material RGB of opaque paint in a cast shadow that looks, on average, as the worn
    ribbons of the same paint `paint` do on a surface of grey `surface`."""
    mean = MEAN_WEAR * np.asarray(paint) + (1.0 - MEAN_WEAR) * surface
    return list(mean / GRAIN_MEAN)


def paint_rgb(colour, brightness: float, surface: float = ROAD_ALBEDO) -> list[float]:
    """Material RGB of paint of pigment `colour` at `brightness` (1 fresh, lower faded) on a
    surface of grey `surface`: the fresh reflectance, faded towards the surface's grey."""
    fresh = max(FRESH_ALBEDO, PAINT_OVER_SURFACE * surface) * np.asarray(colour, dtype=float)
    return list(surface + brightness * (fresh - surface))


def wear_along(rng: np.random.Generator, rows: int = WEAR_ROWS) -> np.ndarray:
    """(rows,) reflectance factor in [FADED_SHARE, 1] along the road: smooth seeded drift
    (a few rows) plus faded stretches (about one row in six), periodic."""
    from lanekeep.world.textures import periodic_blur  # noqa: PLC0415 (a leaf; no cycle)

    drift = periodic_blur(rng.standard_normal((rows, 1)).astype(np.float32), 1.5)[:, 0]
    drift = (drift - drift.mean()) / max(float(drift.std()), 1e-6)
    faded = (rng.random(rows) < 0.17).astype(np.float32)
    level = 0.82 + 0.09 * drift - 0.2 * faded
    return np.clip(level, FADED_SHARE, 1.0)


def profile_rgba(texels: int = TEXELS, spread: float = SPREAD,
                 along: np.ndarray | None = None) -> np.ndarray:
    """(rows, texels, 4) uint8: white paint with alpha 255 across the middle 1/spread and 0
    beside it; the edge ramps over EDGE_TEXELS (the paint's exact coverage box-filtered by that
    width: the line's coverage is kept). `along` (per row, default 1) is the share of the paint
    left by wear: it scales the coverage that shows, through the alpha, which is set so that
    MuJoCo's double translucent draw (1 - (1 - a)^2, see the module docstring) shows `along`
    times what unworn paint shows."""
    fine = 16  # samples per texel
    x = (np.arange(texels * fine) + 0.5) / (texels * fine)
    lo, hi = 0.5 - 0.5 / spread, 0.5 + 0.5 / spread
    inside = ((x >= lo) & (x < hi)).astype(float)
    k = max(1, int(round(EDGE_TEXELS * fine)))
    soft = np.convolve(inside, np.ones(k) / k, mode="same")
    alpha = soft.reshape(texels, fine).mean(axis=1)
    along = np.ones(4) if along is None else np.asarray(along, dtype=float)
    out = np.empty((len(along), texels, 4), np.uint8)
    shown = along[:, None] * (1.0 - (1.0 - alpha[None, :]) ** 2)
    out[..., :3] = 255
    out[..., 3] = np.round(255.0 * (1.0 - np.sqrt(1.0 - shown)))
    return out


def add_paint_texture(spec: mujoco.MjSpec, name: str, rng: np.random.Generator | None = None
                      ) -> None:
    """The filtered ribbons' texture: the edge profile across, seeded wear along (v = s /
    WEAR_PERIOD_M), or no wear without a generator."""
    rgba = profile_rgba(along=None if rng is None else wear_along(rng))
    tex = spec.add_texture(name=name, type=mujoco.mjtTexture.mjTEXTURE_2D,
                           width=rgba.shape[1], height=rgba.shape[0], nchannel=4)
    tex.data = np.ascontiguousarray(rgba).tobytes()


def worn_rgba(rng: np.random.Generator, size: int = WORN_TEXELS) -> np.ndarray:
    """(size, size, 4) uint8 worn paint, tiling per metre: grain and scuffs in the colour, and
    WORN_HOLE_SHARE of it flaked off (alpha 0) in ragged pits and streaks along the road
    (rows are along it) a few millimetres to centimetres across, with 1-texel soft rims."""
    from lanekeep.world.textures import tiled_noise  # noqa: PLC0415

    grain = 0.92 + 0.05 * tiled_noise(rng, size, 0.7) - 0.1 * np.clip(
        tiled_noise(rng, size, 3.0) - 0.5, 0.0, None)
    pits = 0.6 * tiled_noise(rng, size, 0.8) + 0.5 * tiled_noise(rng, size, 2.5)
    streak = rng.standard_normal((size, size)).astype(np.float32)
    streak = np.fft.irfft(np.fft.rfft(streak, axis=0) * np.exp(  # blurred along the road only
        -2.0 * (np.pi * 4.0 * np.fft.rfftfreq(size)[:, None]) ** 2), n=size, axis=0)
    loss = pits / pits.std() + 0.6 * streak / streak.std()
    cut = float(np.quantile(loss, 1.0 - WORN_HOLE_SHARE))
    alpha = np.clip(0.5 - (loss - cut) / 0.4, 0.0, 1.0)
    out = np.empty((size, size, 4), np.uint8)
    out[..., :3] = np.round(255.0 * np.clip(grain, 0.0, 1.0))[..., None]
    out[..., 3] = np.round(255.0 * alpha)
    return out


def add_worn_texture(spec: mujoco.MjSpec, name: str, rng: np.random.Generator) -> None:
    rgba = worn_rgba(rng)
    tex = spec.add_texture(name=name, type=mujoco.mjtTexture.mjTEXTURE_2D,
                           width=rgba.shape[1], height=rgba.shape[0], nchannel=4)
    tex.data = np.ascontiguousarray(rgba).tobytes()


def filtered_strip(road: Road, s_start_m: float, s_end_m: float, r_m: float, width_m: float,
                   z_m: float, v_shift: float = 0.0) -> Ribbon:
    """The RGB ribbon of one paint strip: SPREAD x width_m wide, u across it from 0 to 1,
    v = s / WEAR_PERIOD_M + v_shift: so slow along the road that the mip level still follows
    the footprint across the line (4 m a texel along, 1 cm across)."""
    half = 0.5 * width_m * SPREAD
    strip = ribbon(road, s_start_m, s_end_m, r_m - half, r_m + half, z_m + LIFT_M,
                   tile_m=1.0, max_step_m=1.0)
    uv = np.empty_like(strip.texcoords)
    uv[0::2, 0], uv[1::2, 0] = 0.0, 1.0
    uv[:, 1] = strip.texcoords[:, 1] / WEAR_PERIOD_M + v_shift
    return Ribbon(strip.vertices, strip.faces, uv)


def draw_overlays_last(spec: mujoco.MjSpec, group: int, skip: set[str]) -> int:
    """Give every mesh geom of `group` (but those named in `skip`) a far, buried, tiny triangle
    so that MuJoCo draws it after the paint (see the module docstring); returns how many."""
    meshes = {m.name: m for m in spec.meshes}
    skip, done = set(skip), 0
    for geom in spec.geoms:
        if geom.group != group or geom.type != mujoco.mjtGeom.mjGEOM_MESH or geom.name in skip:
            continue
        mesh = meshes.get(geom.meshname)
        if mesh is None or mesh.name in skip:
            continue
        verts = list(mesh.uservert)
        n = len(verts) // 3
        far = [FAR_M, 0.0, -FAR_DEPTH_M, FAR_M + FAR_SIZE_M, 0.0, -FAR_DEPTH_M,
               FAR_M, FAR_SIZE_M, -FAR_DEPTH_M]
        mesh.uservert = verts + far
        mesh.userface = list(mesh.userface) + [n, n + 1, n + 2]
        if len(mesh.usertexcoord):
            mesh.usertexcoord = list(mesh.usertexcoord) + [0.0] * 6
        if len(mesh.usernormal):
            mesh.usernormal = list(mesh.usernormal) + [0.0, 0.0, 1.0] * 3
        skip.add(mesh.name)  # a mesh shared by several geoms gets one triangle
        done += 1
    return done
