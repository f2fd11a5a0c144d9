"""The roadside assets, each built from mesh pieces (lanekeep/world/prop_meshes.py) into a `Props`
collection: guard rails, concrete barriers, light poles, signs, sign gantries, overpasses,
trees with crowns, buildings with facades; and the textures and materials they use.

Sizes are those of real highway furniture (W-beam 0.45-0.75 m high, jersey barrier 0.81 m,
10 m light poles, gantry and bridge clearances over 5 m). Props stand beyond the gravel; only
overhead parts (gantry beams and signs, overpass decks, pole arms) span the road. Every body
that casts a shadow is registered as a convex point set (`Props.casters`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon
from lanekeep.world import prop_snow as snow_on
from lanekeep.world import prop_textures as tex
from lanekeep.world.parts import WorldLayout, add_material, add_texture
from lanekeep.world.prop_meshes import box, cone, ellipsoid, extrude, prism

FACADE_WALLS = ((0.72, 0.68, 0.6), (0.55, 0.4, 0.32), (0.8, 0.8, 0.78), (0.45, 0.47, 0.5))
SIGN_COLOURS = ((0.05, 0.38, 0.18), (0.06, 0.2, 0.55))
FOLIAGE_TINTS = ((1.0, 1.0, 1.0, 1.0), (0.8, 0.85, 0.8, 1.0), (1.0, 0.92, 0.72, 1.0))
CONIFER_TINT = (0.62, 0.7, 0.75, 1.0)  # darker and bluer than broadleaf crowns
CROWN_LOBES = (3, 5)  # extra clumps of leaves on a scenery tree's crown (`tree` with detail)
WOODS_TINT = (0.8, 0.85, 0.8, 1.0)  # the belt of woods before the hills
SHRUB_MATERIAL = "prop_foliage_1"  # the darkest broadleaf tint
CROWN_SEED = 0x920A  # the crowns' texture's stream
RAIL_PROFILE = np.array([[0.0, 0.45], [-0.08, 0.53], [-0.08, 0.67], [0.0, 0.75],
                         [0.03, 0.75], [0.03, 0.45]])  # (outwards, up) m: W-beam, closed
JERSEY_PROFILE = np.array([[0.0, 0.0], [0.0, 0.075], [0.165, 0.33], [0.23, 0.81],
                           [0.38, 0.81], [0.445, 0.33], [0.61, 0.075], [0.61, 0.0]])


def verge_r(road: Road, side: str, layout: WorldLayout) -> float:
    """Frenet r of the outer edge of the gravel on one side."""
    if side == "left":
        return road.boundary_r(road.n_lanes) + layout.shoulder_m + layout.gravel_m
    return road.boundary_r(0) - layout.shoulder_m - layout.gravel_m


def _sign_of(side: str) -> float:
    return 1.0 if side == "left" else -1.0


@dataclass
class Props:
    """Meshes collected per material, the 3D point sets of convex bodies that cast (hard)
    shadows, and per scenery tree the point sets of its pieces (one soft shadow each)."""

    meshes: dict[str, list[Ribbon]] = field(default_factory=dict)
    casters: list[np.ndarray] = field(default_factory=list)
    tree_shadows: list[list[np.ndarray]] = field(default_factory=list)  # soft, per tree

    def add(self, material: str, mesh: Ribbon, cast: bool = True) -> None:
        self.meshes.setdefault(material, []).append(mesh)
        if cast:
            self.casters.append(mesh.vertices)


def add_prop_materials(spec: mujoco.MjSpec, seed: int, night: bool = False,
                       snow: float = 0.0) -> None:
    """Textures and materials of the props (also used by the shadow zones' casters); at
    night the far hills lose the glow that stands for daylight haze; in a snowfall the crowns
    carry snow and the snow on the rails gets its material (lanekeep/world/prop_snow.py)."""
    rng = np.random.default_rng([seed, 0x9209])
    for k, wall in enumerate(FACADE_WALLS):
        add_texture(spec, f"prop_facade_{k}", tex.facade(rng, wall))
        add_material(spec, f"prop_facade_{k}", f"prop_facade_{k}", specular=0.1)
    for k, colour in enumerate(SIGN_COLOURS):
        add_texture(spec, f"prop_sign_{k}", tex.sign(rng, colour))
        add_material(spec, f"prop_sign_{k}", f"prop_sign_{k}", specular=0.3, emission=0.1)
    add_texture(spec, "prop_concrete", tex.concrete(rng))
    add_material(spec, "prop_concrete", "prop_concrete", specular=0.05)
    leaves = tex.foliage(rng)
    tint: Callable[[tuple[float, ...]], list[float]] = list
    if snow > 0.0:
        leaves = snow_on.snowy_foliage(leaves, np.random.default_rng(
            [seed, snow_on.PROP_SNOW_SEED]), snow)
        tint = snow_on.snowy_tint
        add_material(spec, snow_on.SNOW_MATERIAL, None, rgba=[*snow_on.SNOW_RGB, 1.0],
                     specular=0.15, shininess=0.2)
    # Broadleaf crowns: the leaf texture with a self-shaded underside (an ellipsoid's v runs
    # from its bottom to its top once), from a stream of its own (the draws above stay).
    crown = tex.foliage(np.random.default_rng([seed, CROWN_SEED]), underside=True)
    if snow > 0.0:
        crown = snow_on.snowy_foliage(crown, np.random.default_rng(
            [seed, snow_on.PROP_SNOW_SEED, 2]), snow)
    add_texture(spec, "prop_foliage", leaves)
    add_texture(spec, "prop_crown", crown)
    for k, rgba in enumerate(FOLIAGE_TINTS):
        add_material(spec, f"prop_foliage_{k}", "prop_crown", rgba=tint(rgba), specular=0.0)
    # Conifers: darker and bluer than the broadleaf crowns, on the leaf texture; the woods
    # before the hills on it too (their faces' v is height in metres: no underside there).
    add_material(spec, "prop_conifer", "prop_foliage", rgba=tint(CONIFER_TINT), specular=0.0)
    add_material(spec, "prop_woods", "prop_foliage", rgba=tint(WOODS_TINT), specular=0.0)
    add_material(spec, "prop_steel", None, rgba=[0.68, 0.7, 0.72, 1.0], specular=0.5,
                 shininess=0.4)
    add_material(spec, "prop_pole", None, rgba=[0.5, 0.52, 0.55, 1.0], specular=0.3)
    add_material(spec, "prop_trunk", None, rgba=[0.2, 0.16, 0.12, 1.0], specular=0.0)
    # Far hills: hazy (lighter, bluer, of little contrast) and untextured, since texture
    # detail is lost at 400 m while sampling it over a sixth of the frame costs render time.
    # Greyed towards the sky's haze: far woods and fields lose their green (aerial perspective).
    add_material(spec, "prop_hills", None, rgba=[0.37, 0.42, 0.37, 1.0], specular=0.0,
                 emission=0.02 if night else 0.25)


def tree(props: Props, rng: np.random.Generator, base_xy: np.ndarray, crown_z_m: float,
         radius_m: float, column_m: float = 0.0,
         detail: np.random.Generator | None = None) -> None:
    """A tree: a trunk and a crown around (base_xy, crown_z_m): a core ellipsoid `radius_m`
    wide (0.8 of that high) with leafy lumps bulging out of it; a tall tree (a poplar) carries
    lumps down a column `column_m` long too. One shadow for the crown, one for the trunk.

    With `detail` (a generator of its own, so `rng` draws as before) the core shrinks and
    CROWN_LOBES more clumps of leaves, drawn from `detail`, make the crown's ragged outline:
    a real crown is a few big clumps with gaps, not one ball."""
    material = f"prop_foliage_{int(rng.integers(len(FOLIAGE_TINTS)))}"
    centre = np.r_[base_xy, crown_z_m]
    core = 0.65 if detail is not None else 1.0
    crowns = [ellipsoid(centre, (core * radius_m, core * radius_m, 0.8 * core * radius_m),
                        n_lon=8, n_lat=5)]
    n = int(rng.integers(2, 4)) + int(column_m / radius_m)
    for k in range(n):
        ang, tilt = rng.uniform(0.0, 2 * np.pi), rng.uniform(-0.3, 0.8)
        size = radius_m * rng.uniform(0.4, 0.55)
        down = column_m * k / max(n - 1, 1)
        dist = 0.6 * radius_m
        lump = centre + [dist * math.cos(ang) * math.cos(tilt), dist * math.sin(ang) *
                         math.cos(tilt), 0.8 * dist * math.sin(tilt) - down]
        crowns.append(ellipsoid(lump, (size, size, size * rng.uniform(0.8, 1.2)), 6, 4))
    if detail is not None:
        lo, hi = CROWN_LOBES
        for ang in detail.uniform(0.0, 2 * np.pi) + np.linspace(0.0, 2 * np.pi,
                                                                int(detail.integers(lo, hi + 1)),
                                                                endpoint=False):
            tilt = detail.uniform(-0.35, 0.7)
            size = radius_m * detail.uniform(0.38, 0.58)
            dist = radius_m * detail.uniform(0.6, 0.85)
            down = column_m * detail.uniform(0.0, 1.0)
            lump = centre + [dist * math.cos(ang) * math.cos(tilt), dist * math.sin(ang)
                             * math.cos(tilt), 0.8 * dist * math.sin(tilt) - down]
            crowns.append(ellipsoid(lump, (size, size, size * detail.uniform(0.7, 1.0)), 6, 4))
    props.add(material, Ribbon.concatenate(crowns))
    trunk_r = 0.1 + 0.05 * radius_m
    props.add("prop_trunk", prism(np.r_[base_xy, 0.0], crown_z_m, trunk_r, sides=5))


def shrub(props: Props, rng: np.random.Generator, base_xy: np.ndarray, radius_m: float,
          height_m: float) -> None:
    """A bush: 3-5 low clumps of leaves around base_xy sitting on the ground, `radius_m`
    across and up to `height_m` high, on the darkest leaf tint (in the shade of its own
    leaves, a shrub is the darkest thing beside a road). One soft shadow for all its clumps."""
    clumps = []
    for _ in range(int(rng.integers(3, 6))):
        ang, dist = rng.uniform(0.0, 2 * np.pi), radius_m * rng.uniform(0.0, 0.55)
        size = radius_m * rng.uniform(0.45, 0.7)
        high = height_m * rng.uniform(0.6, 1.0)
        centre = np.r_[base_xy + dist * np.array([math.cos(ang), math.sin(ang)]), 0.5 * high]
        clumps.append(ellipsoid(centre, (size, size * rng.uniform(0.7, 1.0), 0.5 * high), 5, 3))
    props.add(SHRUB_MATERIAL, Ribbon.concatenate(clumps))


def conifer(props: Props, rng: np.random.Generator, base_xy: np.ndarray, height_m: float,
            radius_m: float) -> None:
    """A spruce or pine: three stacked cones, each narrower, on a short bare trunk; one
    shadow for the crown, one for the trunk."""
    tiers = []
    for k in range(3):
        z0 = (0.15 + 0.22 * k) * height_m
        tiers.append(cone(np.r_[base_xy, z0], height_m - z0 if k == 2 else 0.45 * height_m,
                          radius_m * (1.0 - 0.27 * k) * rng.uniform(0.9, 1.1)))
    props.add("prop_conifer", Ribbon.concatenate(tiers))
    props.add("prop_trunk", prism(np.r_[base_xy, 0.0], 0.3 * height_m, 0.08 + 0.04 * radius_m,
                                  sides=5))


def building(props: Props, rng: np.random.Generator, centre_xy: np.ndarray, heading: float,
             length_m: float, depth_m: float, height_m: float, cast: bool = True) -> None:
    """A building with a facade texture (one of FACADE_WALLS), standing on the ground."""
    material = f"prop_facade_{int(rng.integers(len(FACADE_WALLS)))}"
    props.add(material, box(np.r_[centre_xy, 0.5 * height_m], heading,
                            (0.5 * length_m, 0.5 * depth_m, 0.5 * height_m),
                            uv_m=tex.FACADE_TILE_M, bottom=False), cast)


def _panel(props: Props, material: str, centre: np.ndarray, heading: float,
           width_m: float, height_m: float) -> None:
    """A sign panel facing along the road, its texture stretched over each face."""
    mesh = box(centre, heading, (0.04, 0.5 * width_m, 0.5 * height_m))
    uv = mesh.texcoords.reshape(-1, 4, 2)
    lo, hi = uv.min(1, keepdims=True), uv.max(1, keepdims=True)
    uv = (uv - lo) / np.maximum(hi - lo, 1e-9)
    props.add(material, Ribbon(mesh.vertices, mesh.faces, uv.reshape(-1, 2)))


def check_s(road: Road, key: str, values: tuple[float, ...]) -> None:
    for i, s in enumerate(values):
        if not 0.0 <= s <= road.length_m:
            raise ValueError(f"roadside.{key}[{i}] = {s} is beyond the road "
                             f"(0..{road.length_m:g} m)")


def _barrier(props: Props, road: Road, r0: float, side: str, profile: np.ndarray,
             material: str, uv_m: float, layout: WorldLayout) -> None:
    """A profile (outwards, up) swept at r0 along the whole road and its straight leads (the
    rear camera at the start looks back along them), one shadow per stretch."""
    sign = _sign_of(side)
    rz = np.c_[r0 + sign * profile[:, 0], profile[:, 1]]
    mesh, slices = extrude(road, -layout.lead_m, road.length_m + layout.lead_m, rz, uv_m=uv_m)
    props.add(material, mesh, cast=False)
    props.casters.extend(slices)


def guard_rail(props: Props, road: Road, side: str, layout: WorldLayout,
               snow_rng: np.random.Generator | None = None) -> None:
    """W-beam on posts every 4 m, its face 0.5 m beyond the gravel; with `snow_rng` (in a
    snowfall) snow on its top fold and on the posts."""
    sign = _sign_of(side)
    face = verge_r(road, side, layout) + sign * 0.5
    _barrier(props, road, face, side, RAIL_PROFILE, "prop_steel", 1.0, layout)
    s = np.arange(2.0 - layout.lead_m, road.length_m + layout.lead_m, 4.0)
    posts = road.position(s, np.full(len(s), face + sign * 0.12))
    for xy, th in zip(posts, np.asarray(road.heading_at(s), float), strict=True):
        props.add("prop_pole", box(np.r_[xy, 0.4], float(th), (0.04, 0.06, 0.4), bottom=False),
                  cast=False)
    if snow_rng is not None:
        for mesh in (snow_on.ridge(road, face, sign, snow_on.RAIL_RIDGE, snow_rng, layout)
                     + snow_on.post_caps(road, s, face + sign * 0.12, 0.8)):
            props.add(snow_on.SNOW_MATERIAL, mesh, cast=False)


def jersey_barrier(props: Props, road: Road, side: str, layout: WorldLayout,
                   snow_rng: np.random.Generator | None = None) -> None:
    """A concrete barrier (jersey profile, 0.81 m high) 0.3 m beyond the gravel; with
    `snow_rng` (in a snowfall) snow on its top."""
    sign = _sign_of(side)
    r0 = verge_r(road, side, layout) + sign * 0.3
    _barrier(props, road, r0, side, JERSEY_PROFILE, "prop_concrete", tex.CONCRETE_TILE_M,
             layout)
    if snow_rng is not None:
        for mesh in snow_on.ridge(road, r0, sign, snow_on.BARRIER_RIDGE, snow_rng, layout):
            props.add(snow_on.SNOW_MATERIAL, mesh, cast=False)


def pole_s(road: Road, spacing_m: float) -> np.ndarray:
    """Arc lengths of the light poles, `spacing_m` apart from half a spacing on."""
    return np.arange(0.5 * spacing_m, road.length_m, spacing_m)


def pole_heads(road: Road, side: str, spacing_m: float,
               layout: WorldLayout) -> tuple[np.ndarray, np.ndarray]:
    """World xy (n, 2) of the light poles' lamp heads on one side and the road heading there
    (lanekeep/world/street_lights.py lights them at night)."""
    s = pole_s(road, spacing_m)
    r = verge_r(road, side, layout) + _sign_of(side) * (1.0 - 2.3)
    return road.position(s, np.full(len(s), r)), np.asarray(road.heading_at(s), float)


def light_poles(props: Props, road: Road, side: str, spacing_m: float,
                layout: WorldLayout) -> None:
    """10 m poles 1 m beyond the gravel, arms reaching 2.4 m towards the road."""
    sign = _sign_of(side)
    r_pole = verge_r(road, side, layout) + sign * 1.0
    for s in pole_s(road, spacing_m):
        th = float(road.heading_at(s))
        props.add("prop_pole", prism(np.r_[road.position(s, r_pole), 0.0], 10.0, 0.1))
        props.add("prop_pole", box(np.r_[road.position(s, r_pole - sign * 1.2), 9.9], th,
                                   (0.05, 1.2, 0.05)))
        props.add("prop_steel", box(np.r_[road.position(s, r_pole - sign * 2.3), 9.8], th,
                                    (0.2, 0.3, 0.07)))


def roadside_sign(props: Props, rng: np.random.Generator, road: Road, s: float,
                  layout: WorldLayout) -> None:
    """A 2.6 x 1.6 m sign on two posts beyond the right gravel, facing the traffic."""
    th = float(road.heading_at(s))
    r0 = verge_r(road, "right", layout)
    for dr in (-0.9, -3.5):
        props.add("prop_pole", prism(np.r_[road.position(s, r0 + dr), 0.0], 3.6, 0.06))
    _panel(props, f"prop_sign_{int(rng.integers(len(SIGN_COLOURS)))}",
           np.r_[road.position(s - 0.1, r0 - 2.2), 2.8], th, 2.6, 1.6)


def gantry(props: Props, rng: np.random.Generator, road: Road, s: float,
           layout: WorldLayout) -> None:
    """Two posts 1.3 m beyond the gravel (behind a rail or barrier), a beam across at 6.9 m,
    a sign over each lane (underside 5.3 m)."""
    th = float(road.heading_at(s))
    right, left = verge_r(road, "right", layout) - 1.3, verge_r(road, "left", layout) + 1.3
    for r in (right, left):
        props.add("prop_steel", box(np.r_[road.position(s, r), 3.6], th, (0.25, 0.25, 3.6)))
    props.add("prop_steel", box(np.r_[road.position(s, 0.5 * (right + left)), 6.9], th,
                                (0.35, 0.5 * (left - right), 0.35)))
    first = int(rng.integers(len(SIGN_COLOURS)))
    for lane in range(road.n_lanes):
        centre = np.r_[road.position(s - 0.45, road.lane_center_r(lane)), 6.4]
        material = f"prop_sign_{(first + lane) % len(SIGN_COLOURS)}"
        _panel(props, material, centre, th, 0.8 * road.lane_width_m, 2.2)


def overpass(props: Props, road: Road, s: float, layout: WorldLayout) -> None:
    """A bridge across the road: a 10 m deck (underside 5.8 m) with parapets on pillars
    beyond the gravel and on abutment walls 10 m further out."""
    th = float(road.heading_at(s))
    right, left = verge_r(road, "right", layout) - 10.0, verge_r(road, "left", layout) + 10.0
    mid, half_span = 0.5 * (right + left), 0.5 * (left - right)
    deck = [box(np.r_[road.position(s, mid), 6.4], th, (5.0, half_span, 0.6))]
    for d in (-4.8, 4.8):
        deck.append(box(np.r_[road.position(s + d, mid), 7.5], th, (0.2, half_span, 0.5)))
    deck = Ribbon.concatenate(deck)
    props.add("prop_concrete", deck, cast=False)
    props.casters.append(deck.vertices)
    for r in (verge_r(road, "right", layout) - 1.5, verge_r(road, "left", layout) + 1.5):
        for d in (-3.0, 3.0):
            props.add("prop_concrete", box(np.r_[road.position(s + d, r), 2.9], th,
                                           (0.5, 0.5, 2.9), bottom=False))
    for r in (right, left):
        props.add("prop_concrete", box(np.r_[road.position(s, r), 2.9], th,
                                       (5.0, 1.0, 2.9), bottom=False))
