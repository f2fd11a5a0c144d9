"""Cast shadows on the road as real ones look: as dark as skylight alone makes them, with soft
edges, and dappled under trees.

How dark. Shade is lit by the sky only; the sunlit road by the sun's direct light and the sky.
On a clear day the diffuse sky gives about SKY_SHARE of what the direct sun gives a surface
facing it, so a solid caster's umbra keeps

    T_umbra = sky / (sky + sin(elevation) x direct)

of the sunlit road's light (0.2-0.35 for a sun 25-60 deg high; real dashcam frames show a
shade/sun luma of about 0.26). `direct` is the sun's diffuse strength for the time of day
(lanekeep/world/lighting.py LIGHTING, relative to the day's) times the share that fog lets
through (`direct_sun_share`); `sky` is SKY_SHARE times the ambient light for the time of day,
plus what fog scatters down. Dawn, dusk, fog: paler shade; a high sun: darker.

A scenario's `darkness` (`conditions.shadows[].darkness`, `roadside.shadow_darkness`) is the
casters' optical depth in units of a solid caster's: the shade keeps T_umbra ** (darkness /
DARKNESS_UMBRA) of the light, so 0 is no shadow, DARKNESS_UMBRA (0.55, the default) a solid
building's umbra lit by the open sky, and more is darker still (a street canyon that also
hides part of the sky); 1 keeps T_umbra ** 1.8.

Soft edges. The sun is 0.53 deg across, so a shadow's edge is a penumbra about 1/100 of the
distance from the caster's edge to the ground: 0.3-0.8 m for a building's roof line 30-80 m up
the sun's ray. Each shadow is drawn as PENUMBRA_LAYERS nested overlays, the polygon grown and
shrunk by up to PENUMBRA_M / 2, each taking an equal share of the shade's log-transmission: the
light falls in steps across the edge instead of at one line. `ConditionsInfo.shaded` keeps the
exact polygons (the middle of the penumbra).

Dapple. Under a tree's crown the sun comes through gaps as sunflecks (images of the sun, a few
centimetres to decimetres across); a tree zone's overlays carry a seeded RGBA texture whose
alpha has such holes (DAPPLE_LIGHT_SHARE of the area lit, soft-edged), tiled every
OVERLAY_TILE_M on the ground.

Trees beside the road. A scenery tree's (or shrub's) shadow is the union of its crown's lobes
and its trunk cast along the sun, so it follows the crown's outline and starts at the trunk's
foot; each is rasterised into a cell of one texture atlas (SOFT_CELL_PX texels), blurred by
SOFT_EDGE_M and holed by CROWN_GAP_SHARE of sun through the leaves, and drawn as one quad per
tree in one geom (`add_soft_shadows`): soft edges without the polygon clipping that costs
seconds for hundreds of casters.

MuJoCo blends each translucent geom twice (lanekeep/world/roadside.py `overlay_alpha`): an
overlay that should keep T of the light is given the per-pass alpha 1 - sqrt(T).
"""

from __future__ import annotations

import math

import cv2
import mujoco
import numpy as np

from lanekeep.geometry.road_mesh import Ribbon
from lanekeep.scenario.conditions import Conditions
from lanekeep.world.groups import GROUP_SHADOW
from lanekeep.world.lighting import LIGHTING, SKY_SCATTER, direct_sun_share
from lanekeep.world.parts import OVERLAY_Z_M, add_mesh_geom
from lanekeep.world.roadside import clip_half_plane, disjoint_pieces, polygon_mesh
from lanekeep.world.textures import tiled_noise

SKY_SHARE = 0.2  # clear-sky diffuse light / direct sun on a surface facing it
DARKNESS_UMBRA = 0.55  # the `darkness` of a solid caster's umbra (the keys' default)
PENUMBRA_M = 0.5  # width of a shadow's soft edge on the road
PENUMBRA_LAYERS = 3  # nested overlays that make it
OVERLAY_TILE_M = 4.0  # ground period of an overlay's texture (roadside.polygon_mesh's uv)
DAPPLE_TEXELS = 256  # texels per tile: 1.6 cm each
DAPPLE_LIGHT_SHARE = 0.22  # share of a crown's shadow that sunflecks light
TRANSLUCENT_ALPHA = 0.99  # a textured overlay's material alpha (below 1: the translucent pass)
SOFT_CELL_PX = 128  # atlas cell of one tree's soft shadow (soft_shadow_atlas)
SOFT_ATLAS_MAX_PX = 2048  # cells shrink (to 32 px) so that the atlas stays this wide
SOFT_BORDER_PX = 2  # empty texels around each cell (no bleeding between cells)
SOFT_EDGE_M = 0.2  # Gaussian sigma of a crown shadow's soft edge on the ground
CROWN_GAP_M = 0.12  # size (Gaussian sigma) of the gaps the sun finds through a crown
CROWN_GAP_SHARE = 0.15  # share of a crown's shadow that such gaps light (mostly)


def umbra_transmission(conditions: Conditions) -> float:
    """The share of the sunlit road's light that a solid caster's shade keeps (see module)."""
    sun, ambient = LIGHTING[conditions.time_of_day][:2]
    day_sun, day_ambient = LIGHTING["day"][:2]
    sin_el = max(math.sin(math.radians(conditions.sun_elevation_deg)), 0.0)
    strength = float(np.mean(sun)) / float(np.mean(day_sun))
    through = direct_sun_share(conditions)
    direct = sin_el * strength * through
    sky = SKY_SHARE * float(np.mean(ambient)) / float(np.mean(day_ambient))
    sky += SKY_SCATTER * sin_el * strength * (1.0 - through)  # fog's scattered sunlight
    return sky / (sky + direct) if sky + direct > 0.0 else 1.0


def shade_transmission(darkness: float, conditions: Conditions) -> float:
    """The share of the sunlit road's light that shade of this `darkness` keeps."""
    return float(umbra_transmission(conditions) ** (max(darkness, 0.0) / DARKNESS_UMBRA))


def changes_no_pixel(transmission: float, layers: int = 1) -> bool:
    """Whether an overlay that keeps `transmission` of the light, in `layers` nested passes,
    is too faint to change an 8-bit pixel: its per-pass alpha, as a texel, rounds to 0. Such
    an overlay still costs the rasteriser its whole area (a cast shadow under an overcast
    sky at a low sun: case 5's dusk rain keeps 0.99998 of the light under shadows 100 m
    long, which cost 60% of its render, tools/profile_render.py), so it is not drawn."""
    per_pass = 1.0 - math.sqrt(max(transmission, 0.0) ** (1.0 / layers))
    return 255.0 * per_pass / TRANSLUCENT_ALPHA < 0.5


def grown(poly: np.ndarray, by_m: float) -> np.ndarray:
    """A convex CCW polygon (n, 2) grown by `by_m` (shrunk if < 0; corners of a grown one are
    rounded); an empty (0, 2) array when shrinking leaves nothing."""
    poly = np.asarray(poly, dtype=float)
    if by_m > 0.0:  # Minkowski sum with a 16-gon
        ang = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
        ring = by_m / math.cos(np.pi / 16) * np.c_[np.cos(ang), np.sin(ang)]
        pts = (poly[:, None, :] + ring[None]).reshape(-1, 2).astype(np.float32)
        hull = cv2.convexHull(pts).reshape(-1, 2).astype(float)
        return hull if _ccw_area(hull) > 0 else hull[::-1]
    out = poly
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        normal = np.array([b[1] - a[1], a[0] - b[0]])  # outward: right of a CCW edge
        length = float(np.hypot(*normal))
        if length < 1e-9:
            continue
        out = clip_half_plane(out, normal / length, float(normal @ a) / length + by_m)
        if len(out) < 3:
            return np.zeros((0, 2))
    return out


def _ccw_area(poly: np.ndarray) -> float:
    x, y = poly[:, 0].astype(float), poly[:, 1].astype(float)
    return 0.5 * float(x @ np.roll(y, -1) - np.roll(x, -1) @ y)


def layer_offsets_m(layers: int = PENUMBRA_LAYERS, width_m: float = PENUMBRA_M) -> np.ndarray:
    """How far each nested overlay grows its polygon (m): evenly across the penumbra."""
    if layers <= 1:
        return np.zeros(1)
    return np.linspace(0.5, -0.5, layers) * width_m * (layers - 1) / layers


def dapple_transmission(rng: np.random.Generator, transmission: float,
                        texels: int = DAPPLE_TEXELS) -> np.ndarray:
    """(texels, texels) share of the light kept under a crown: `transmission` in leaf shade,
    1 in sunflecks (DAPPLE_LIGHT_SHARE of the area, blobs of 2-20 cm with soft rims)."""
    noise = 0.65 * tiled_noise(rng, texels, 2.5) + 0.75 * tiled_noise(rng, texels, 7.0)
    noise /= float(noise.std())
    cut = float(np.quantile(noise, 1.0 - DAPPLE_LIGHT_SHARE))
    light = np.clip((noise - cut) / 0.35 + 0.5, 0.0, 1.0)  # ~1-2 texels of soft rim
    light = light * light * (3.0 - 2.0 * light)
    return transmission + (1.0 - transmission) * light


def add_shadow_overlay(spec: mujoco.MjSpec, name: str, polygons: list[np.ndarray],
                       transmission: float, dapple: np.random.Generator | None = None,
                       soft: bool = True) -> int:
    """Nested overlays `name`_p0, _p1 ... (GROUP_SHADOW) of the convex CCW ground polygons,
    keeping `transmission` of the light where all lie (dappled with a texture drawn from
    `dapple` if given); returns how many geoms were added. Within one layer no ground point
    is covered twice (roadside.disjoint_pieces). `soft=False` draws one hard-edged layer of
    polygons that are already disjoint: for many small casters (poles, crowns, signs), whose
    pieces the nested layers would grow and split again at a cost of seconds a world."""
    offsets = layer_offsets_m() if soft else np.zeros(1)
    if changes_no_pixel(transmission, len(offsets)):
        return 0
    share = 1.0 / len(offsets)  # of the log-transmission, per layer
    material = f"{name}_shade"
    if dapple is not None:
        per_pass = 1.0 - np.sqrt(dapple_transmission(dapple, transmission) ** share)
        alpha = np.clip(np.round(255.0 * per_pass / TRANSLUCENT_ALPHA), 0, 255).astype(np.uint8)
        rgba = np.zeros((*alpha.shape, 4), np.uint8)
        rgba[..., 3] = alpha
        add_shade_material(spec, material, rgba)
    else:
        alpha = 1.0 - math.sqrt(max(transmission, 0.0) ** share)
        spec.add_material(name=material, rgba=[0.0, 0.0, 0.0, alpha], specular=0.0,
                          shininess=0.0)
    added = 0
    for k, by in enumerate(offsets):
        if not soft:
            pieces = [p for p in polygons if len(p) >= 3]
        else:
            layer = [p for p in (grown(poly, float(by)) for poly in polygons) if len(p) >= 3]
            pieces = disjoint_pieces(layer) if layer else []
        if not pieces:
            continue
        add_mesh_geom(spec, f"{name}_p{k}", polygon_mesh(pieces, OVERLAY_Z_M), material,
                      GROUP_SHADOW)
        added += 1
    return added


def add_shade_material(spec: mujoco.MjSpec, material: str, rgba: np.ndarray) -> None:
    """A translucent overlay's texture (black, its shade in the alpha) and material, both
    named `material`: drawn in MuJoCo's translucent pass (material alpha below 1)."""
    tex = spec.add_texture(name=material, type=mujoco.mjtTexture.mjTEXTURE_2D,
                           width=rgba.shape[1], height=rgba.shape[0], nchannel=4)
    tex.data = np.ascontiguousarray(rgba).tobytes()
    mat = spec.add_material(name=material, rgba=[1.0, 1.0, 1.0, TRANSLUCENT_ALPHA],
                            specular=0.0, shininess=0.0)
    mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = material


def soft_shadow_atlas(groups: list[list[np.ndarray]], to_sun: np.ndarray, transmission: float,
                      rng: np.random.Generator, cell_px: int = SOFT_CELL_PX
                      ) -> tuple[np.ndarray, Ribbon]:
    """Soft shadows of compound casters (a tree: its crown's lobes and its trunk, each a
    convex 3D point set) as one texture atlas and one mesh of ground quads.

    Each group gets a square cell of the atlas: the union of its pieces cast along the sun
    onto the ground (z = 0), so the shade follows the crown's outline and meets the trunk's
    foot; blurred by SOFT_EDGE_M (the penumbra of a crown's thinning rim of leaves plus the
    sun's 0.5 deg), with gaps where the sun comes through the crown (CROWN_GAP_SHARE of the
    shade, decimetre-sized). The cell's alpha is the per-pass alpha of the light kept
    (1 - sqrt(T), see the module). Returns the RGBA atlas (black, alpha) and the quads at
    OVERLAY_Z_M with their texture coordinates (texture row k at v = (k + 0.5) / height)."""
    n = len(groups)
    cols = max(1, math.ceil(math.sqrt(n)))
    rows = max(1, math.ceil(n / cols))
    cell = int(min(cell_px, max(32, SOFT_ATLAS_MAX_PX // cols)))
    alpha = np.zeros((rows * cell, cols * cell), np.float32)
    step = to_sun[:2] / to_sun[2]
    quads, uvs = [], []
    inner = cell - 2 * SOFT_BORDER_PX
    for i, group in enumerate(groups):
        flat = [p[:, :2] - p[:, 2:3] * step for p in group]
        pts = np.concatenate(flat)
        lo, hi = pts.min(0), pts.max(0)
        extent = float(np.max(hi - lo))
        margin = 3.0 * SOFT_EDGE_M + 0.02 * extent
        size = extent + 2.0 * margin
        m_px = size / inner
        origin = 0.5 * (lo + hi) - 0.5 * size - SOFT_BORDER_PX * m_px  # the cell's corner
        mask = np.zeros((cell, cell), np.float32)
        for piece in flat:
            px = np.round((piece - origin) / m_px * 16.0).astype(np.int32)  # 4 bits subpixel
            hull = cv2.convexHull(px)
            cv2.fillConvexPoly(mask, hull, 1.0, lineType=cv2.LINE_AA, shift=4)
        sigma = SOFT_EDGE_M / m_px
        mask = cv2.GaussianBlur(mask, (0, 0), max(sigma, 0.5))
        gaps = cv2.GaussianBlur(rng.standard_normal((cell, cell)).astype(np.float32), (0, 0),
                                max(CROWN_GAP_M / m_px, 0.6))
        gaps /= max(float(gaps.std()), 1e-6)
        cut = float(np.quantile(gaps, 1.0 - CROWN_GAP_SHARE))
        lit = np.clip((gaps - cut) / 0.5 + 0.5, 0.0, 1.0)
        kept = 1.0 - mask * (1.0 - transmission) * (1.0 - 0.8 * lit)
        r, c = divmod(i, cols)
        alpha[r * cell:(r + 1) * cell, c * cell:(c + 1) * cell] = 1.0 - np.sqrt(kept)
        corners = origin + cell * m_px * np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0],
                                                   [0.0, 1.0]])
        quads.append(np.c_[corners, np.full(4, OVERLAY_Z_M)])
        uvs.append((np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]) * cell
                    + [c * cell, r * cell]) / [cols * cell, rows * cell])
    rgba = np.zeros((*alpha.shape, 4), np.uint8)
    rgba[..., 3] = np.clip(np.round(255.0 * alpha / TRANSLUCENT_ALPHA), 0, 255)
    base = 4 * np.arange(n)[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]]).astype(np.int32)
    mesh = Ribbon(np.concatenate(quads), faces, np.concatenate(uvs))
    return rgba, mesh


def add_soft_shadows(spec: mujoco.MjSpec, name: str, groups: list[list[np.ndarray]],
                     to_sun: np.ndarray, transmission: float, rng: np.random.Generator) -> bool:
    """One overlay geom `name` (GROUP_SHADOW) with the soft shadows of `groups`
    (soft_shadow_atlas); False when there is nothing to cast or its shade would change no
    pixel (`changes_no_pixel`)."""
    if not groups or to_sun[2] <= 0.0 or changes_no_pixel(transmission):
        return False
    rgba, mesh = soft_shadow_atlas(groups, to_sun, transmission, rng)
    material = f"{name}_shade"
    add_shade_material(spec, material, rgba)
    add_mesh_geom(spec, name, mesh, material, GROUP_SHADOW)
    return True
