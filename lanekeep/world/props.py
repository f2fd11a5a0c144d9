"""Roadside props from a scenario's `[roadside]` table (lanekeep/scenario/roadside.py) put into
the world: guard rails, barriers, poles, signs, gantries, overpasses
(lanekeep/world/prop_assets.py),
scenery trees and buildings placed by the seed, and hills or a city at the horizon.

Real frames are full of edges above the horizon (2-14% edge pixels) where ours had none. Each
material's pieces are merged into one mesh geom (a geom costs render time, triangles hardly
do), all visual only (contype 0) in GROUP_WORLD: the segmentation render shows them as
non-marking pixels that hide the paint behind them. Everything the sun reaches casts its
silhouette on the ground as one translucent overlay (GROUP_SHADOW, like the shadow zones in
roadside.py, cut so that no ground point is shaded twice, also where a shadow zone's
shadow lies); the scenery trees and shrubs cast soft shadows that follow their crowns down to
their trunks, all in one textured overlay (lanekeep/world/shade.py `add_soft_shadows`). At night
there is no sun to cast them.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon
from lanekeep.scenario.roadside import SIDES
from lanekeep.scenario.schema import Scenario
from lanekeep.world import prop_assets as assets
from lanekeep.world.groups import GROUP_WORLD
from lanekeep.world.parts import ConditionsInfo, WorldLayout, add_mesh_geom
from lanekeep.world.prop_meshes import hill_ring, tree_belt
from lanekeep.world.prop_snow import PROP_SNOW_SEED
from lanekeep.world.roadside import cast_shadow, disjoint_pieces
from lanekeep.world.shade import add_shadow_overlay, add_soft_shadows, shade_transmission

TREE_OFFSET_M = (4.0, 40.0)  # scenery trees: from the gravel's outer edge (m)
BUILDING_OFFSET_M = (15.0, 60.0)
HILL_WIDTH_M = 200.0
BELT_COLUMNS = 6  # columns of a woods face (prop_meshes.tree_belt's ragged top)
SHRUBS_PER_TREE = 1.0  # bushes per scenery tree (roadside.trees_per_100m)
SHRUB_OFFSET_M = (2.0, 25.0)  # from the gravel's outer edge (m)
TREE_DETAIL_SEED = 0x920B  # the stream of the scenery crowns' lobes (`rng` draws as before)
TREE_SHADE_SEED = 0x920C  # the stream of the gaps in their soft shadows
TREE_KINDS = {"broadleaf": 0.55, "poplar": 0.15, "conifer": 0.3}  # shares of scenery trees
PROP_CELL_M = 40.0  # the props' geoms: one per material and cell this wide (_add_prop_geoms)


def add_props(spec: mujoco.MjSpec, scenario: Scenario, road: Road, to_sun: np.ndarray,
              info: ConditionsInfo, layout: WorldLayout) -> None:
    """Add the scenario's roadside props and their shadows (after the shadow zones, whose
    casters use the props' materials and whose shadows the props' shadows leave out)."""
    cfg = scenario.roadside
    snow = scenario.conditions.snow
    assets.add_prop_materials(spec, scenario.seed, scenario.conditions.time_of_day == "night",
                              snow)
    for key in ("signs_m", "gantries_m", "overpasses_m"):
        assets.check_s(road, key, getattr(cfg, key))
    rng = np.random.default_rng([scenario.seed, 0x9205])
    # Snow on the rails and barriers: its own generator, so no other draw moves.
    snow_rng = (np.random.default_rng([scenario.seed, PROP_SNOW_SEED, 1]) if snow > 0.0
                else None)
    props = assets.Props()
    for side in cfg.guard_rail_sides:
        assets.guard_rail(props, road, side, layout, snow_rng)
    for side in cfg.barrier_sides:
        assets.jersey_barrier(props, road, side, layout, snow_rng)
    for side in cfg.pole_sides if cfg.pole_spacing_m > 0.0 else ():
        assets.light_poles(props, road, side, cfg.pole_spacing_m, layout)
    for s in cfg.signs_m:
        assets.roadside_sign(props, rng, road, s, layout)
    for s in cfg.gantries_m:
        assets.gantry(props, rng, road, s, layout)
    for s in cfg.overpasses_m:
        assets.overpass(props, road, s, layout)
    _scenery(props, rng, road, scenario, layout, to_sun)
    _skyline(props, rng, road, cfg.skyline, layout,
             np.random.default_rng([scenario.seed, TREE_DETAIL_SEED, 1]))
    _add_prop_geoms(spec, props)
    if scenario.conditions.time_of_day != "night":
        transmission = shade_transmission(cfg.shadow_darkness, scenario.conditions)
        if props.casters:
            _add_shadows(spec, props, to_sun, info, transmission)
        if props.tree_shadows and to_sun[2] > 0.0:
            # The shade zones stay where the sun puts them even when too faint to draw.
            add_soft_shadows(spec, "props_shadow_trees", props.tree_shadows, to_sun,
                             transmission, np.random.default_rng([scenario.seed, TREE_SHADE_SEED]))
            info.shadow_polygons.extend(cast_shadow(points, to_sun)
                                        for group in props.tree_shadows for points in group)


def prop_kind(geom_name: str) -> str:
    """The material-wide name of a prop geom ("props_conifer" for "props_conifer@3")."""
    return geom_name.split("@", 1)[0]


def _add_prop_geoms(spec: mujoco.MjSpec, props: assets.Props) -> None:
    """One mesh geom per material and square cell of PROP_CELL_M (named kind@k, k in the
    cells' sorted order), each prop in the cell of its bounding box's centre. Why cells: few
    geoms render fast, but the software renderer transforms all of a geom's vertices even
    when most of them lie behind the camera; per cell, the cameras leave out the cells they
    cannot see (lanekeep/sensing/frustum.py)."""
    for material, meshes in sorted(props.meshes.items()):
        cells: dict[tuple[int, int], list[Ribbon]] = {}
        for mesh in meshes:
            centre = 0.5 * (mesh.vertices[:, :2].min(axis=0) + mesh.vertices[:, :2].max(axis=0))
            cell = np.floor(centre / PROP_CELL_M).astype(int)
            cells.setdefault((int(cell[0]), int(cell[1])), []).append(mesh)
        kind = material.replace("prop_", "props_", 1)
        for k, cell in enumerate(sorted(cells)):
            add_mesh_geom(spec, f"{kind}@{k}", Ribbon.concatenate(cells[cell]), material,
                          GROUP_WORLD)


def _add_shadows(spec: mujoco.MjSpec, props: assets.Props, to_sun: np.ndarray,
                 info: ConditionsInfo, transmission: float) -> None:
    """The props' cast shadows, as dark as skylight alone leaves shade (fog scatters the sun:
    lanekeep/world/shade.py), left out where a shadow zone's shadow already lies. Hard-edged:
    soft edges for hundreds of small casters cost ~8 s a world build in polygon clipping
    (2026-11-27, cProfile of a dataset world), and a pole's penumbra is narrow near the
    ground, where the shadow is seen. The scenery trees' shadows are soft
    (shade.add_soft_shadows: a texture atlas, no clipping)."""
    polygons = [cast_shadow(points, to_sun) for points in props.casters]
    polygons = [p for p in polygons if len(p) >= 3]
    earlier = list(info.shadow_polygons)
    pieces = disjoint_pieces(earlier + polygons)[len(disjoint_pieces(earlier)):]
    if not pieces:
        return
    add_shadow_overlay(spec, "props_shadow", pieces, transmission, soft=False)
    info.shadow_polygons.extend(polygons)


def _clear_of_road(road: Road, xy: np.ndarray, margin_m: float) -> bool:
    """Whether world points (n, 2) all lie further than margin_m from the reference line
    (on a curve a point beside one stretch of road can lie near another)."""
    _, r = road.local_coordinates(np.atleast_2d(xy))
    return bool(np.all(np.abs(r) > margin_m))


def _keep_out(scenario: Scenario, side: str) -> list[tuple[float, float, float]]:
    """(s_from, s_to, offset_m) boxes beside the gravel that other props already occupy."""
    cfg = scenario.roadside
    boxes = [(z.s_start_m - 5.0, z.s_end_m + 5.0, 20.0)
             for z in scenario.conditions.shadows if z.side == side]
    boxes += [(s - 20.0, s + 20.0, 16.0) for s in cfg.overpasses_m]
    boxes += [(s - 6.0, s + 6.0, 6.0) for s in (*cfg.gantries_m, *cfg.signs_m)]
    return boxes


def _towards_road(road: Road, s: float, sign: float, to_sun: np.ndarray) -> float:
    """How far (m) a shadow reaches towards the road per metre of its caster's height, beside
    the road at s on the side `sign` (+1 left); <= 0 when shadows fall away from it."""
    th = float(road.heading_at(s))
    normal = np.array([-math.sin(th), math.cos(th)])
    return float(to_sun[:2] @ normal) / float(to_sun[2]) * sign


def _scenery(props: assets.Props, rng: np.random.Generator, road: Road, scenario: Scenario,
             layout: WorldLayout, to_sun: np.ndarray) -> None:
    """Trees and buildings beside the road, Poisson numbers per side, places and looks drawn
    from the seed; none inside another prop's place, none nearer any stretch of road. Their
    shadows stop 1 m short of the gravel (lower buildings, no tree where it would shade the
    road): shade on the road is what a scenario's `conditions.shadows` zones decide."""
    cfg = scenario.roadside
    detail = np.random.default_rng([scenario.seed, TREE_DETAIL_SEED])  # crowns' extra lobes
    for side in SIDES:
        sign = 1.0 if side == "left" else -1.0
        verge = assets.verge_r(road, side, layout)
        blocked = _keep_out(scenario, side)
        n_trees = rng.poisson(cfg.trees_per_100m * road.length_m / 100.0)
        for _ in range(n_trees):
            s = rng.uniform(0.0, road.length_m)
            off = min(TREE_OFFSET_M[0] + rng.exponential(10.0), TREE_OFFSET_M[1])
            kind, radius, crown_z, column, top = _tree_shape(rng)
            xy = road.position(s, verge + sign * (off + radius))
            if not _placeable(road, s, off, xy, radius, top, sign, verge, blocked, to_sun):
                continue
            first = len(props.casters)
            if kind == "conifer":
                assets.conifer(props, rng, xy, top, radius)
            else:
                assets.tree(props, rng, xy, crown_z, radius, column, detail)
            props.tree_shadows.append(props.casters[first:])  # soft, one per tree
            del props.casters[first:]
        _shrubs(props, detail, road, side, verge, blocked, cfg.trees_per_100m, to_sun)
        placed: list[tuple[np.ndarray, float]] = []
        n_buildings = rng.poisson(cfg.buildings_per_100m * road.length_m / 100.0)
        for _ in range(n_buildings):
            s = rng.uniform(0.0, road.length_m)
            off = rng.uniform(*BUILDING_OFFSET_M)
            length, depth = rng.uniform(10.0, 30.0), rng.uniform(10.0, 20.0)
            height = float(np.clip(rng.lognormal(math.log(12.0), 0.5), 5.0, 45.0))
            towards = _towards_road(road, s, sign, to_sun)
            if towards > 0.0:
                height = min(height, (off - 1.0) / towards)
            xy = road.position(s, verge + sign * (off + 0.5 * depth))
            reach = 0.5 * math.hypot(length, depth)
            if any(np.hypot(*(xy - c)) < reach + rc + 2.0 for c, rc in placed):
                continue
            th = float(road.heading_at(s))
            corners = xy + np.array([[a * length * math.cos(th) - b * depth * math.sin(th),
                                      a * length * math.sin(th) + b * depth * math.cos(th)]
                                     for a in (-0.5, 0.5) for b in (-0.5, 0.5)])
            if height >= 4.0 and _clear_of_road(road, corners, abs(verge) + 5.0):
                placed.append((xy, reach))
                assets.building(props, rng, xy, th, length, depth, height)


def _placeable(road: Road, s: float, off: float, xy: np.ndarray, radius: float, height: float,
               sign: float, verge: float, blocked: list[tuple[float, float, float]],
               to_sun: np.ndarray) -> bool:
    """Whether a plant `off` metres beyond the gravel at `s` may stand: not in another prop's
    place, its shadow not reaching the gravel, its crown clear of the road."""
    reach = _towards_road(road, s, sign, to_sun) * height
    if any(a <= s <= b and off < o for a, b, o in blocked) or reach > off - 1.0:
        return False
    return _clear_of_road(road, xy, abs(verge) + radius + 1.0)


def _shrubs(props: assets.Props, detail: np.random.Generator, road: Road, side: str,
            verge: float, blocked: list[tuple[float, float, float]], trees_per_100m: float,
            to_sun: np.ndarray) -> None:
    """Bushes beside the gravel on one side, SHRUBS_PER_TREE per scenery tree (real verges
    have dark scrub among the dry grass), 2-25 m beyond the gravel, drawn from `detail` (the
    trees' and buildings' draws stay); as the trees, none whose shadow would reach the gravel
    or that stands in another prop's place."""
    sign = 1.0 if side == "left" else -1.0
    for _ in range(detail.poisson(SHRUBS_PER_TREE * trees_per_100m * road.length_m / 100.0)):
        s = detail.uniform(0.0, road.length_m)
        off = min(SHRUB_OFFSET_M[0] + detail.exponential(6.0), SHRUB_OFFSET_M[1])
        radius, height = detail.uniform(0.7, 1.8), detail.uniform(0.8, 2.2)
        xy = road.position(s, verge + sign * (off + radius))
        if not _placeable(road, s, off, xy, radius, height, sign, verge, blocked, to_sun):
            continue
        first = len(props.casters)
        assets.shrub(props, detail, xy, radius, height)
        props.tree_shadows.append(props.casters[first:])
        del props.casters[first:]


def _tree_shape(rng: np.random.Generator) -> tuple[str, float, float, float, float]:
    """(kind, crown radius, crown centre height, column, top height) of a scenery tree: a
    broadleaf (crowns 4-8 m across on 2-3 m of bare trunk), a poplar (a narrow crown carried
    down a 4-8 m column) or a conifer 7-16 m high, in the proportions TREE_KINDS gives."""
    kind = str(rng.choice(list(TREE_KINDS), p=list(TREE_KINDS.values())))
    if kind == "conifer":
        radius = float(rng.uniform(1.5, 3.0))
        top = float(rng.uniform(7.0, 16.0))
        return kind, radius, 0.5 * top, 0.0, top
    if kind == "poplar":
        radius, column = float(rng.uniform(1.2, 1.8)), float(rng.uniform(4.0, 8.0))
        crown_z = column + float(rng.uniform(2.0, 3.0))
        return kind, radius, crown_z, column, crown_z + 0.8 * radius
    radius = float(rng.uniform(2.0, 4.0))
    crown_z = 0.75 * radius + float(rng.uniform(2.0, 3.0))
    return kind, radius, crown_z, 0.0, crown_z + radius


def _skyline(props: assets.Props, rng: np.random.Generator, road: Road, skyline: str,
             layout: WorldLayout, detail: np.random.Generator) -> None:
    """Hills in a ring around the whole road, where the ground plane ends; "city" puts far
    buildings in front of lower hills. Too far to cast a shadow on anything we see."""
    if skyline == "none":
        return
    pts = road.position(np.linspace(0.0, road.length_m, 64))
    centre = pts.mean(axis=0)
    plane_half = float(np.max(np.abs(pts - centre))) + 200.0  # world.py's ground plane
    reach = float(np.max(np.hypot(*(pts - centre).T))) + layout.lead_m
    radius = max(0.95 * plane_half, reach + 60.0)
    n = 192
    ang = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    shape = sum(rng.normal() / k * np.cos(k * ang + rng.uniform(0, 2 * np.pi))
                for k in range(1, 13))
    shape = (shape - shape.min()) / max(float(np.ptp(shape)), 1e-9)
    low, high = (8.0, 30.0) if skyline == "city" else (12.0, 55.0)
    apron = min(radius, 0.9 * plane_half)
    props.add("prop_hills", hill_ring(centre, apron, radius, HILL_WIDTH_M,
                                      low + (high - low) * shape), cast=False)
    # Woods between the road and the hills: groups of trees, too far for single trees to
    # matter, whose leaves and ragged tops are most of the edges real frames have up there.
    belt = max(reach + 40.0, 0.75 * radius)
    if belt < radius - 20.0:
        jitter = rng.uniform(-15.0, 15.0, n)
        tops = rng.uniform(6.0, 14.0, n) * (1.0 + 0.3 * shape)
        keep = np.repeat(rng.random(n // 4) < 0.6, 4)  # woods ~4 steps long, gaps between
        # Ragged tops (`detail`: the other draws stay): crowns 3-4 m apart rising and falling.
        ragged = detail.uniform(-0.3, 0.15, (n, BELT_COLUMNS))
        ragged[:, 1::2] += 0.12
        props.add("prop_woods", tree_belt(centre, belt + jitter, tops, keep, ragged=ragged),
                  cast=False)
    if skyline != "city":
        return
    for a in rng.uniform(0.0, 2 * np.pi, 90):
        dist = radius - rng.uniform(10.0, 60.0)
        xy = centre + dist * np.array([math.cos(a), math.sin(a)])
        height = float(np.clip(rng.lognormal(math.log(30.0), 0.5), 12.0, 110.0))
        if _clear_of_road(road, xy, 80.0):
            assets.building(props, rng, xy, a + 0.5 * math.pi, rng.uniform(20.0, 45.0),
                            rng.uniform(15.0, 30.0), height, cast=False)
