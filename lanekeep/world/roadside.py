"""What lies on and beside the road in a scenario: hard shadows and their casters, speed
bumps, wet asphalt and puddles, snow (see lanekeep/world/conditions.py for the whole list)."""


from __future__ import annotations

import math

import cv2
import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon
from lanekeep.scenario.conditions import Conditions, ShadowZone
from lanekeep.world import prop_assets as assets
from lanekeep.world import textures
from lanekeep.world.appearance import SNOW_TEXTURE
from lanekeep.world.groups import GROUP_SHADOW, GROUP_WORLD
from lanekeep.world.parts import (
    OVERLAY_Z_M,
    ConditionsInfo,
    WorldLayout,
    add_mesh_geom,
    add_texture,
    yaw_quat,
)
from lanekeep.world.snow import add_snow_cover

BUMP_LENGTH_M = 0.6  # chord of a speed bump along the road
BUMP_STRIPE_RAISE_M = 0.004  # the stripes (cylinders) stand this much proud of the bump
DRAPE_MARGIN_M = 0.004  # a shadow draped over a bump floats this far above its stripes
DRAPE_STRIPS = 12  # flat strips a draped shadow follows a bump's arc with (sagitta < 1 mm)
_MIN_PIECE_M2 = 1e-6
RUT_PUDDLE_SHARE = 0.7  # puddles that lie in a wheel path


def overlay_alpha(opacity: float) -> float:
    """Material alpha of a translucent overlay that should look `opacity` opaque.

    MuJoCo's renderer (mjr_render, unless the scene flag mjRND_ADDITIVE is set) draws every
    transparent geom twice, front to back and then back to front, with depth writes off: a flat
    overlay of alpha a blends over the asphalt twice and lets (1 - a)^2 through, not 1 - a (a
    shadow of darkness 0.6 left 0.16 of the light, not 0.4). Two blends of one colour are one
    blend of alpha 1 - (1 - a)^2, so this alpha gives `opacity` for any overlay colour.
    """
    return 1.0 - math.sqrt(1.0 - float(opacity))


def _convex_hull(points_xy: np.ndarray) -> np.ndarray:
    """Counter-clockwise (seen from above, z up) convex hull of 2D points."""
    hull = cv2.convexHull(points_xy.astype(np.float32)).reshape(-1, 2).astype(float)
    return hull if _area(hull) > 0 else hull[::-1]


def polygon_mesh(polygons: list[np.ndarray], z_m: float | None = None) -> Ribbon:
    """Triangle fans of convex CCW polygons, one mesh: 2D polygons at height z, or 3D ones."""
    verts, faces, offset = [], [], 0
    for poly in polygons:
        n = len(poly)
        verts.append(poly if z_m is None else np.c_[poly, np.full(n, z_m)])
        i = np.arange(1, n - 1)
        faces.append(np.stack([np.zeros_like(i), i, i + 1], 1) + offset)
        offset += n
    v = np.concatenate(verts)
    return Ribbon(v, np.concatenate(faces).astype(np.int32), v[:, :2] / 4.0)


def _area(poly: np.ndarray) -> float:
    """Signed (shoelace) area of a polygon (n, 2): > 0 when counter-clockwise."""
    if len(poly) < 3:
        return 0.0
    x, y = poly[:, 0], poly[:, 1]  # (slices, not np.roll: called thousands of times)
    return 0.5 * float(x[:-1] @ y[1:] - x[1:] @ y[:-1] + x[-1] * y[0] - x[0] * y[-1])


def clip_half_plane(poly: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """The part of a convex polygon (n, 2) where normal . p <= offset (Sutherland-Hodgman)."""
    if len(poly) == 0:
        return poly
    d = poly @ normal - offset
    out = []
    for k in range(len(poly)):
        j = (k + 1) % len(poly)
        if d[k] <= 0.0:
            out.append(poly[k])
        if (d[k] < 0.0 < d[j]) or (d[j] < 0.0 < d[k]):
            out.append(poly[k] + d[k] / (d[k] - d[j]) * (poly[j] - poly[k]))
    return np.array(out, dtype=float).reshape(-1, 2)


def _minus(poly: np.ndarray, hole: np.ndarray) -> list[np.ndarray]:
    """Convex pieces of a convex polygon outside a convex CCW polygon `hole`."""
    pieces, rest = [], poly
    for a, b in zip(hole, np.roll(hole, -1, axis=0), strict=True):
        normal = np.array([b[1] - a[1], a[0] - b[0]])  # outward: right of a CCW edge
        if normal @ normal < 1e-12:
            continue
        outside = clip_half_plane(rest, -normal, -float(normal @ a))
        if _area(outside) > _MIN_PIECE_M2:
            pieces.append(outside)
        rest = clip_half_plane(rest, normal, float(normal @ a))
        if _area(rest) <= _MIN_PIECE_M2:
            break
    return pieces


def disjoint_pieces(polygons: list[np.ndarray]) -> list[np.ndarray]:
    """Convex CCW pieces that cover the union of convex CCW polygons exactly once.

    Overlapping triangles of one translucent mesh blend once each: where two casters' shadows
    overlapped, the road was shaded twice. Each polygon loses what earlier ones cover.
    """
    polygons = [np.asarray(p, dtype=float) for p in polygons]
    lo = np.array([p.min(0) for p in polygons]).reshape(-1, 2)
    hi = np.array([p.max(0) for p in polygons]).reshape(-1, 2)
    out = []
    for i, poly in enumerate(polygons):
        pieces = [poly]
        near = np.flatnonzero(np.all((lo[:i] <= hi[i]) & (hi[:i] >= lo[i]), axis=1))
        for j in near:
            pieces = [p for piece in pieces for p in _minus(piece, polygons[j])]
        out.extend(pieces)
    return out


def cast_shadow(points: np.ndarray, to_sun: np.ndarray) -> np.ndarray:
    """Ground (z = 0) shadow of a convex body given by points (n, 3): CCW hull polygon (m, 2)."""
    ground = points[:, :2] - points[:, 2:3] * to_sun[:2] / to_sun[2]
    return _convex_hull(np.concatenate([ground, points[points[:, 2] < 0.05, :2]]))


def _verge_r(road: Road, side: str, layout: WorldLayout) -> float:
    """Frenet r of the outer edge of the gravel on one side."""
    if side == "left":
        return road.boundary_r(road.n_lanes) + layout.shoulder_m + layout.gravel_m
    return road.boundary_r(0) - layout.shoulder_m - layout.gravel_m


def _shadow_per_height(road: Road, s: float, to_sun: np.ndarray) -> tuple[np.ndarray, float]:
    """Ground offset of a shadow per metre of height (world XY), and its Frenet r component."""
    offset = -to_sun[:2] / to_sun[2]
    th = float(road.heading_at(s))
    normal = np.array([-math.sin(th), math.cos(th)])
    return offset, float(offset @ normal)


def add_shadow_zone(spec: mujoco.MjSpec, road: Road, zone: ShadowZone, index: int,
                    to_sun: np.ndarray, rng: np.random.Generator, info: ConditionsInfo,
                    layout: WorldLayout) -> list[np.ndarray]:
    """Buildings with facades or trees with crowns (lanekeep/world/prop_assets.py) beside the road,
    tall enough that the sun throws their shadows `zone.reach` across it: one mesh per material.
    Returns their shadows (convex CCW ground polygons, also added to `info`), which
    lanekeep/world/shade.py draws."""
    sign = 1.0 if zone.side == "left" else -1.0
    face_r = _verge_r(road, zone.side, layout) + sign * 1.0  # casters stand 1 m beyond the gravel
    width = road.boundary_r(road.n_lanes) - road.boundary_r(0)
    target_r = road.boundary_r(road.n_lanes if zone.side == "right" else 0)
    target_r += sign * width * (1.0 - zone.reach)
    casters = assets.Props()
    variety = rng.spawn(1)[0]  # facades and crowns: the zone's own stream, `rng` draws as before
    s = zone.s_start_m
    while s < zone.s_end_m:
        if zone.kind == "buildings":
            length = min(rng.uniform(10.0, 24.0), zone.s_end_m - s)
            depth = rng.uniform(8.0, 14.0)
        else:  # trees: canopy diameter along the road
            length = depth = rng.uniform(5.0, 8.0)
        s_mid = s + 0.5 * length
        offset, lateral = _shadow_per_height(road, s_mid, to_sun)
        if lateral * sign >= -1e-3:
            raise ValueError(
                f"conditions.shadows[{index}]: with this sun the shadows of casters on the "
                f"{zone.side} fall away from the road (set sun_azimuth_deg towards the "
                f"{zone.side})"
            )
        reach_height = abs(face_r - target_r) / abs(lateral) * rng.uniform(1.0, 1.15)
        th = float(road.heading_at(s_mid))
        centre = road.position(s_mid, face_r + sign * 0.5 * depth)
        if zone.kind == "buildings":
            height = float(np.clip(reach_height, 3.0, 80.0))
            rng.uniform(0.45, 0.8, 3)  # (the boxes' colour before facades: keeps the draws)
            assets.building(casters, variety, centre, th, length, depth, height)
        else:
            radius = 0.5 * length
            crown = float(np.clip(reach_height, 2.0 * radius + 2.0, 25.0))  # canopy centre
            rng.uniform(0.3, 0.42)  # (the lollipop's green before crowns: keeps the draws)
            column = max(0.0, 0.75 * (crown - radius - 3.0))  # leaves down a tall tree
            assets.tree(casters, variety, centre, crown, radius, column)
        gap = length * (1.0 - zone.coverage) / zone.coverage * rng.uniform(0.6, 1.4)
        s += length + gap
    for material, meshes in sorted(casters.meshes.items()):
        name = f"cond_{zone.kind}_{index}_{material.removeprefix('prop_')}"
        add_mesh_geom(spec, name, Ribbon.concatenate(meshes), material, GROUP_WORLD)
        info.caster_names.append(name)
    polygons = [cast_shadow(points, to_sun) for points in casters.casters]
    info.shadow_polygons.extend(polygons)
    return polygons


def add_bumps(spec: mujoco.MjSpec, road: Road, cond: Conditions, info: ConditionsInfo,
               layout: WorldLayout) -> None:
    h = cond.speed_bump_height_m
    radius = (BUMP_LENGTH_M**2 / 4.0 + h**2) / (2.0 * h)  # circle through the chord ends
    right = road.boundary_r(0) - layout.shoulder_m
    left = road.boundary_r(road.n_lanes) + layout.shoulder_m
    half = 0.5 * (left - right)
    n_stripes = int(half // 0.6)
    for i, s in enumerate(cond.speed_bumps_m):
        if not 0.0 <= s <= road.length_m:
            raise ValueError(f"conditions.speed_bumps_m[{i}] = {s} is beyond the road")
        th = float(road.heading_at(s))
        # Cylinder axis (local z) along the road normal: rotate z onto (-sin th, cos th, 0).
        quat = np.zeros(4)  # Rz(th) Rx(-pi/2): z -> y -> road normal
        mujoco.mju_mulQuat(quat, np.array(yaw_quat(th)),
                           np.array([math.cos(-math.pi / 4), math.sin(-math.pi / 4), 0.0, 0.0]))
        xy = road.position(s, 0.5 * (left + right))
        name = f"cond_bump_{i}"
        spec.worldbody.add_geom(
            name=name, type=mujoco.mjtGeom.mjGEOM_CYLINDER, group=GROUP_WORLD,
            pos=[*xy, h - radius], quat=quat.tolist(), size=[radius, half, 0],
            material="cond_bump", condim=3, friction=[1.0, 0.005, 0.0001],
        )
        info.bump_geoms.append(name)
        for j in range(-n_stripes, n_stripes + 1, 2):  # black stripes, visual only
            sxy = road.position(s, 0.5 * (left + right) + 0.6 * j)
            spec.worldbody.add_geom(
                name=f"{name}_stripe_{j + n_stripes}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                group=GROUP_WORLD, pos=[*sxy, h - radius], quat=quat.tolist(),
                size=[radius + BUMP_STRIPE_RAISE_M, 0.15, 0], rgba=[0.05, 0.05, 0.05, 1.0],
                contype=0, conaffinity=0,
            )
        _drape_shadows(spec, xy, th, half, h, radius)


def _drape_shadows(spec: mujoco.MjSpec, centre: np.ndarray, heading: float, half_width: float,
                   height: float, radius: float) -> None:
    """Lay the shadow overlays already in the spec over a bump instead of under it.

    The overlays lie flat at OVERLAY_Z_M, under a bump's top (~0.08 m): a bump in the shade
    stayed sunlit. Over the bump's footprint (where its stripes rise above the overlay, across
    its length) each overlay triangle is cut out and replaced by strips lifted onto the arc.
    """
    t_hat = np.array([math.cos(heading), math.sin(heading)])
    n_hat = np.array([-math.sin(heading), math.cos(heading)])
    top = radius + BUMP_STRIPE_RAISE_M  # radius of the stripes, the bump's outermost surface
    below = radius - height  # depth of the cylinder's axis under the ground
    rise = OVERLAY_Z_M - DRAPE_MARGIN_M + below  # axis to the height where the drape lands
    if rise >= top:
        return  # the bump stays under the overlay
    reach = math.sqrt(top**2 - rise**2)  # half chord (along the road) that needs the drape
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)  # CCW
    rect = centre + corners[:, :1] * reach * t_hat + corners[:, 1:] * half_width * n_hat
    cuts = np.linspace(-reach, reach, DRAPE_STRIPS + 1)

    def lift(poly: np.ndarray) -> np.ndarray:
        d = (poly - centre) @ t_hat
        z = np.sqrt(np.maximum(top**2 - d**2, 0.0)) - below + DRAPE_MARGIN_M
        return np.c_[poly, np.maximum(z, OVERLAY_Z_M)]

    for mesh in spec.meshes:
        if not mesh.name.startswith("cond_shadow_"):
            continue
        verts = np.asarray(mesh.uservert, dtype=float).reshape(-1, 3)
        faces = np.asarray(mesh.userface, dtype=int).reshape(-1, 3)
        lo, hi = rect.min(0), rect.max(0)
        keep, draped = [], []
        for face in faces:
            tri = verts[face]
            xy = tri[:, :2]
            flat = (np.abs(tri[:, 2] - OVERLAY_Z_M) < 1e-6).all()  # not draped over a bump yet
            if not flat or (xy.min(0) > hi).any() or (xy.max(0) < lo).any():
                keep.append(tri)
                continue
            keep.extend(np.c_[p, np.full(len(p), OVERLAY_Z_M)] for p in _minus(xy, rect))
            inside = xy
            for a, b in zip(rect, np.roll(rect, -1, axis=0), strict=True):
                normal = np.array([b[1] - a[1], a[0] - b[0]])
                inside = clip_half_plane(inside, normal, float(normal @ a))
            if _area(inside) <= _MIN_PIECE_M2:
                continue
            for d0, d1 in zip(cuts[:-1], cuts[1:], strict=True):
                strip = clip_half_plane(inside, t_hat, d1 + float(t_hat @ centre))
                strip = clip_half_plane(strip, -t_hat, -(d0 + float(t_hat @ centre)))
                if _area(strip) > _MIN_PIECE_M2:
                    draped.append(lift(strip))
        if not draped:
            continue
        mesh_arrays = polygon_mesh(keep + draped)
        mesh.uservert = mesh_arrays.vertices.astype(np.float32).ravel().tolist()
        mesh.userface = mesh_arrays.faces.ravel().tolist()
        mesh.usertexcoord = mesh_arrays.texcoords.astype(np.float32).ravel().tolist()


def add_wet(spec: mujoco.MjSpec, road: Road, cond: Conditions, rng: np.random.Generator,
             info: ConditionsInfo, layout: WorldLayout) -> None:
    """Puddles as dark glossy overlays (the wet asphalt itself is a material tint decided in
    lanekeep/world/appearance.py). Most lie in the wheel paths, where traffic wears ruts:
    long and narrow along the lane; the rest anywhere on the pavement, rounder."""
    w = cond.wet
    right = road.boundary_r(0) - layout.shoulder_m + 0.3
    left = road.boundary_r(road.n_lanes) + layout.shoulder_m - 0.3
    n = int(round(road.length_m / 12.0 * w))
    ang = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    polygons = []
    for _ in range(n):
        s = rng.uniform(0.0, road.length_m)
        if rng.random() < RUT_PUDDLE_SHARE:
            lane = int(rng.integers(road.n_lanes))
            r = road.lane_center_r(lane) + rng.choice([-0.85, 0.85]) + rng.normal(0.0, 0.08)
            a, b, turn = rng.uniform(0.6, 2.5), rng.uniform(0.15, 0.4), rng.uniform(-0.08, 0.08)
        else:
            r = rng.uniform(right, left)
            a, b, turn = rng.uniform(0.4, 1.5), rng.uniform(0.3, 0.8), rng.uniform(-0.3, 0.3)
        th = float(road.heading_at(s)) + turn
        c, sn = math.cos(th), math.sin(th)
        local = np.stack([a * np.cos(ang), b * np.sin(ang)], 1)
        rot = local @ np.array([[c, sn], [-sn, c]])
        polygons.append(road.position(s, r) + rot)
    if polygons:
        add_mesh_geom(spec, "cond_puddles", polygon_mesh(polygons, OVERLAY_Z_M - 0.002),
                  "cond_puddle", GROUP_SHADOW)
        info.puddle_polygons = polygons


def add_snow(spec: mujoco.MjSpec, road: Road, cond: Conditions,
              rng: np.random.Generator, layout: WorldLayout) -> None:
    """The snow texture that the verge materials use (lanekeep/world/appearance.py) and packed
    snow on the carriageway between the wheel paths (lanekeep/world/snow.py)."""
    tex = textures.gravel(rng)
    snow = np.clip(235 + (tex.astype(np.int16) - tex.mean()) * 0.25, 0, 255).astype(np.uint8)
    add_texture(spec, SNOW_TEXTURE, snow)
    spec.add_material(name="cond_snow_cover", rgba=[0.93, 0.94, 0.97, 1.0], specular=0.15,
                      shininess=0.2)
    spec.materials[-1].textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = SNOW_TEXTURE
    spec.add_material(name="cond_snow_slush", rgba=[0.62, 0.62, 0.63, overlay_alpha(0.5)],
                      specular=0.3, shininess=0.3)
    add_snow_cover(spec, road, cond, rng, layout, "cond_snow_cover", "cond_snow_slush")
