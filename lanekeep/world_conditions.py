"""What a scenario's conditions add to the MuJoCo world: light, shadows, bumps, wet, fog, traffic.

Called by `world.build_spec` after the road and markings exist (`add_conditions`); everything is
seeded from the scenario seed, so one scenario always builds the same world.

  - Sun and time of day: the sun's direction comes from `Conditions.sun_*`; dawn, dusk and night
    dim the sun, the ambient light and the sky and switch on the car's headlights (two white spot
    lights, lit road ~35 m ahead) and a dim red tail light (the rear camera sees ~8 m of road).
    MuJoCo lights per vertex, so with headlights the asphalt ribbons are re-meshed as a 0.5 m grid.
  - Hard shadows: shadow maps double the render cost on a CPU, so a building's or tree's shadow is
    its silhouette cast along the sun onto the ground: a convex polygon drawn as a black
    translucent overlay (group GROUP_SHADOW, hidden from the segmentation render so the marking
    masks stay exact). The casters (boxes, trees) stand beside the road and are rendered too.
  - Speed bumps: cylinders across the road sunk into the ground (a circular cap ~0.6 m long and
    `speed_bump_height_m` high) that the tyres collide with; yellow with black stripes.
  - Wet road: darker, glossier asphalt (MuJoCo renders `reflectance` on planes only, and a
    reflective plane costs a second scene pass, so wetness is a material change) and puddles as
    dark glossy overlays (group GROUP_SHADOW).
  - Fog: MuJoCo's linear fog up to the visibility distance, in the sky's horizon colour.
    Scenes without fog put it beyond the far clip plane, so the render flag can stay on.
  - Snow: white verges (grass and gravel textures) and snow drifts over the asphalt shoulders.
  - Other vehicles: mocap bodies (body box + cabin + axles) moved along their lanes by
    `update_dynamic(world, t_s)`; `occluded_marking_share` measures how much paint they hide.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import mujoco
import numpy as np

from lanekeep import textures
from lanekeep.cameras import GROUP_SHADOW, GROUP_WORLD
from lanekeep.road import Road
from lanekeep.road_mesh import Ribbon, ribbon
from lanekeep.scenario import Conditions, Scenario, ShadowZone, VehicleSpec
from lanekeep.world_parts import OVERLAY_Z_M, ROAD_Z_M, WorldLayout, add_mesh_geom, yaw_quat

SKY_DAY = ((0.45, 0.62, 0.88), (0.88, 0.92, 0.97))  # zenith, horizon (as in world.py)
# time of day -> (sun diffuse, sun ambient, camera headlight ambient/diffuse, sky zenith/horizon)
LIGHTING = {
    "day": ((0.75, 0.75, 0.72), (0.15, 0.15, 0.15), (0.35, 0.25), SKY_DAY),
    "dawn": ((0.45, 0.38, 0.32), (0.07, 0.07, 0.09), (0.10, 0.05),
             ((0.22, 0.27, 0.42), (0.62, 0.55, 0.52))),
    "dusk": ((0.40, 0.30, 0.22), (0.06, 0.05, 0.07), (0.08, 0.04),
             ((0.16, 0.18, 0.32), (0.52, 0.42, 0.40))),
    "night": ((0.03, 0.03, 0.05), (0.015, 0.015, 0.025), (0.02, 0.0),
              ((0.005, 0.006, 0.015), (0.03, 0.035, 0.06))),
}
FOG_VISIBILITY_M = (400.0, 25.0)  # visibility at fog = 0+ and at fog = 1 (log-linear between)
FOG_END_OF_VISIBILITY = 0.6  # linear fog ends at this fraction of the visibility
BUMP_LENGTH_M = 0.6  # chord of a speed bump along the road
GRID_STEP_M = 0.5  # lateral/along step of the re-meshed asphalt under headlights


@dataclass
class VehicleTrack:
    """A moving occluder: mocap body `name` at Frenet (s_m + speed_mps * t, r_m)."""

    name: str
    s_m: float
    r_m: float
    speed_mps: float
    mocap_id: int = -1  # resolved on first use


@dataclass
class ConditionsInfo:
    """What add_conditions put in the world, for the episode, the tests and the reports."""

    shadow_polygons: list[np.ndarray] = field(default_factory=list)  # world XY (n, 2) each
    caster_names: list[str] = field(default_factory=list)
    bump_geoms: list[str] = field(default_factory=list)  # collision geoms of the speed bumps
    puddle_polygons: list[np.ndarray] = field(default_factory=list)
    vehicles: list[VehicleTrack] = field(default_factory=list)
    fog_visibility_m: float = math.inf
    headlights: bool = False

    def shaded(self, xy: np.ndarray) -> np.ndarray:
        """Whether world points (..., 2) lie in any cast shadow."""
        xy = np.asarray(xy, dtype=float)
        out = np.zeros(xy.shape[:-1], bool)
        for poly in self.shadow_polygons:
            out |= _inside_convex(poly, xy)
        return out


# -- geometry helpers ------------------------------------------------------------------------
def _inside_convex(poly: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Points inside a counter-clockwise convex polygon."""
    edges = np.roll(poly, -1, axis=0) - poly
    rel = xy[..., None, :] - poly
    cross = edges[:, 0] * rel[..., 1] - edges[:, 1] * rel[..., 0]
    return np.all(cross >= 0.0, axis=-1)


def _convex_hull(points_xy: np.ndarray) -> np.ndarray:
    """Counter-clockwise (seen from above, z up) convex hull of 2D points."""
    hull = cv2.convexHull(points_xy.astype(np.float32)).reshape(-1, 2).astype(float)
    x, y = hull[:, 0], hull[:, 1]
    area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    return hull if area > 0 else hull[::-1]


def _polygon_mesh(polygons: list[np.ndarray], z_m: float) -> Ribbon:
    """Triangle fans of convex CCW polygons at height z, one mesh."""
    verts, faces, offset = [], [], 0
    for poly in polygons:
        n = len(poly)
        verts.append(np.c_[poly, np.full(n, z_m)])
        i = np.arange(1, n - 1)
        faces.append(np.stack([np.zeros_like(i), i, i + 1], 1) + offset)
        offset += n
    v = np.concatenate(verts)
    return Ribbon(v, np.concatenate(faces).astype(np.int32), v[:, :2] / 4.0)


def fog_visibility_m(fog: float) -> float:
    """Meteorological visibility (5% contrast) of a fog density in (0, 1]."""
    near, far = FOG_VISIBILITY_M
    return near * (far / near) ** fog


def sun_direction(conditions: Conditions, road: Road) -> np.ndarray:
    """Unit vector from the ground towards the sun, world frame."""
    el = math.radians(conditions.sun_elevation_deg)
    az = math.radians(conditions.sun_azimuth_deg) + float(road.heading_at(0.0))
    return np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])


def cast_shadow(points: np.ndarray, to_sun: np.ndarray) -> np.ndarray:
    """Ground (z = 0) shadow of a convex body given by points (n, 3): CCW hull polygon (m, 2)."""
    ground = points[:, :2] - points[:, 2:3] * to_sun[:2] / to_sun[2]
    return _convex_hull(np.concatenate([ground, points[points[:, 2] < 0.05, :2]]))


# -- light, sky, fog ---------------------------------------------------------------------------
def _add_light_and_sky(spec: mujoco.MjSpec, cond: Conditions, road: Road) -> None:
    sun_diffuse, sun_ambient, (head_amb, head_dif), (zenith, horizon) = LIGHTING[cond.time_of_day]
    to_sun = sun_direction(cond, road)
    sun = spec.light("sun")
    sun.dir = (-to_sun).tolist()
    sun.specular = [0.1 + 0.6 * cond.wet] * 3  # glare off wet asphalt
    if cond.time_of_day != "day":
        sun.diffuse, sun.ambient = list(sun_diffuse), list(sun_ambient)
        sun.specular = [0.02 + 0.4 * cond.wet] * 3
        spec.visual.headlight.ambient = [head_amb] * 3
        spec.visual.headlight.diffuse = [head_dif] * 3
    if cond.fog > 0.0:  # overcast: a sky washed towards the fog colour
        grey = np.array([0.72, 0.74, 0.76]) * (np.mean(horizon) / np.mean(SKY_DAY[1]))
        mix = 0.5 + 0.5 * cond.fog
        zenith = tuple((1 - mix) * np.array(zenith) + mix * grey)
        horizon = tuple((1 - mix) * np.array(horizon) + mix * grey)
    sky = spec.texture("sky")
    sky.rgb1, sky.rgb2 = list(zenith), list(horizon)
    # Fog, in units of the model extent (see world._add_environment). MuJoCo's fog is linear in
    # depth; ending it at 0.6 V follows Koschmieder's exp(-3 d / V) within ~0.1 up to d = V / 2.
    extent = spec.stat.extent
    if cond.fog > 0.0:
        spec.visual.map.fogstart = 0.0
        spec.visual.map.fogend = FOG_END_OF_VISIBILITY * fog_visibility_m(cond.fog) / extent
    else:
        spec.visual.map.fogstart, spec.visual.map.fogend = 1e3, 2e3  # beyond zfar: no fog
    spec.visual.rgba.fog = [*horizon, 1.0]
    spec.visual.rgba.haze = [*horizon, 1.0]


def _add_car_lights(spec: mujoco.MjSpec) -> None:
    """Low-beam headlights (forward, 2 deg down) and a dim red tail light on the body 'car'."""
    car = spec.body("car")
    spot = mujoco.mjtLightType.mjLIGHT_SPOT
    for side, y in (("left", 0.7), ("right", -0.7)):
        car.add_light(name=f"headlight_{side}", type=spot, pos=[2.35, y, 0.75],
                      dir=[1.0, 0.0, -0.035], cutoff=32.0, exponent=6.0,
                      diffuse=[1.0, 0.97, 0.9], ambient=[0.0, 0.0, 0.0],
                      specular=[0.4, 0.4, 0.4], attenuation=[0.25, 0.02, 0.0],
                      castshadow=False)
    car.add_light(name="tail_light", type=spot, pos=[-2.4, 0.0, 0.8], dir=[-1.0, 0.0, -0.45],
                  cutoff=70.0, exponent=2.0, diffuse=[0.55, 0.08, 0.06],
                  ambient=[0.0, 0.0, 0.0], specular=[0.0, 0.0, 0.0],
                  attenuation=[0.3, 0.1, 0.0], castshadow=False)


def _densify_asphalt(spec: mujoco.MjSpec, road: Road, layout: WorldLayout) -> None:
    """Re-mesh the asphalt ribbons as a grid so per-vertex spot lighting looks right."""
    right = road.boundary_r(0) - layout.shoulder_m
    left = road.boundary_r(road.n_lanes) + layout.shoulder_m
    n = max(1, math.ceil((left - right) / GRID_STEP_M))
    cuts = np.linspace(right, left, n + 1)
    for i, (s0, s1) in enumerate(road.segment_bounds()):
        grid = Ribbon.concatenate([
            ribbon(road, s0, s1, a, b, ROAD_Z_M, layout.tile_m, max_step_m=2 * GRID_STEP_M)
            for a, b in zip(cuts[:-1], cuts[1:], strict=True)
        ])
        mesh = spec.mesh(f"road_{i}")
        mesh.uservert = grid.vertices.astype(np.float32).ravel().tolist()
        mesh.userface = grid.faces.ravel().tolist()
        mesh.usertexcoord = grid.texcoords.astype(np.float32).ravel().tolist()


# -- shadows and their casters ---------------------------------------------------------------
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


def _add_zone(spec: mujoco.MjSpec, road: Road, zone: ShadowZone, index: int, to_sun: np.ndarray,
              rng: np.random.Generator, info: ConditionsInfo, layout: WorldLayout) -> None:
    sign = 1.0 if zone.side == "left" else -1.0
    face_r = _verge_r(road, zone.side, layout) + sign * 1.0  # casters stand 1 m beyond the gravel
    width = road.boundary_r(road.n_lanes) - road.boundary_r(0)
    target_r = road.boundary_r(road.n_lanes if zone.side == "right" else 0)
    target_r += sign * width * (1.0 - zone.reach)
    polygons = []
    s = zone.s_start_m
    k = 0
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
        t_hat = np.array([math.cos(th), math.sin(th)])
        n_hat = np.array([-math.sin(th), math.cos(th)])
        centre = road.position(s_mid, face_r + sign * 0.5 * depth)
        name = f"cond_{zone.kind}_{index}_{k}"
        if zone.kind == "buildings":
            height = float(np.clip(reach_height, 3.0, 80.0))
            shade = rng.uniform(0.45, 0.8)
            spec.worldbody.add_geom(
                name=name, type=mujoco.mjtGeom.mjGEOM_BOX, group=GROUP_WORLD,
                pos=[*centre, 0.5 * height], quat=yaw_quat(th),
                size=[0.5 * length, 0.5 * depth, 0.5 * height],
                rgba=[shade, shade * rng.uniform(0.85, 1.0), shade * rng.uniform(0.75, 0.95), 1.0],
                contype=0, conaffinity=0,
            )
            corners = np.array([[a, b] for a in (-0.5, 0.5) for b in (-0.5, 0.5)])
            foot = centre + corners[:, :1] * length * t_hat + corners[:, 1:] * depth * n_hat
            box = np.concatenate([np.c_[foot, np.zeros(4)], np.c_[foot, np.full(4, height)]])
            polygons.append(cast_shadow(box, to_sun))
        else:
            radius = 0.5 * length
            crown = float(np.clip(reach_height, 2.0 * radius + 2.0, 25.0))  # canopy centre
            trunk = crown - 0.8 * radius
            spec.worldbody.add_geom(
                name=f"{name}_trunk", type=mujoco.mjtGeom.mjGEOM_CYLINDER, group=GROUP_WORLD,
                pos=[*centre, 0.5 * trunk], size=[0.25, 0.5 * trunk, 0],
                rgba=[0.3, 0.22, 0.15, 1.0], contype=0, conaffinity=0,
            )
            spec.worldbody.add_geom(
                name=name, type=mujoco.mjtGeom.mjGEOM_ELLIPSOID, group=GROUP_WORLD,
                pos=[*centre, crown], size=[radius, radius, 0.8 * radius],
                rgba=[0.12, rng.uniform(0.3, 0.42), 0.1, 1.0], contype=0, conaffinity=0,
            )
            ang = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)
            ring = np.stack([np.cos(ang), np.sin(ang)], 1)
            canopy = np.concatenate([
                np.c_[centre + radius * ring, np.full(24, crown)],
                np.c_[centre + 0.6 * radius * ring, np.full(24, crown + 0.6 * radius)],
                np.c_[centre + 0.6 * radius * ring, np.full(24, crown - 0.6 * radius)],
            ])
            polygons.append(cast_shadow(canopy, to_sun))
        info.caster_names.append(name)
        gap = length * (1.0 - zone.coverage) / zone.coverage * rng.uniform(0.6, 1.4)
        s += length + gap
        k += 1
    if polygons:
        add_mesh_geom(spec, f"cond_shadow_{index}", _polygon_mesh(polygons, OVERLAY_Z_M),
                  f"cond_shadow_{index}", GROUP_SHADOW)
        info.shadow_polygons.extend(polygons)


# -- road surface ------------------------------------------------------------------------------
def _add_bumps(spec: mujoco.MjSpec, road: Road, cond: Conditions, info: ConditionsInfo,
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
                size=[radius + 0.004, 0.15, 0], rgba=[0.05, 0.05, 0.05, 1.0],
                contype=0, conaffinity=0,
            )


def _add_wet(spec: mujoco.MjSpec, road: Road, cond: Conditions, rng: np.random.Generator,
             info: ConditionsInfo, layout: WorldLayout) -> None:
    w = cond.wet
    asphalt = spec.material("asphalt")
    asphalt.rgba = [1.0 - 0.45 * w, 1.0 - 0.45 * w, 1.0 - 0.4 * w, 1.0]
    asphalt.specular = 0.05 + 0.6 * w
    asphalt.shininess = 0.1 + 0.85 * w
    spec.material("gravel").rgba = [1.0 - 0.35 * w, 1.0 - 0.35 * w, 1.0 - 0.33 * w, 1.0]
    right = road.boundary_r(0) - layout.shoulder_m + 0.3
    left = road.boundary_r(road.n_lanes) + layout.shoulder_m - 0.3
    n = int(round(road.length_m / 12.0 * w))
    ang = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    polygons = []
    for _ in range(n):
        s, r = rng.uniform(0.0, road.length_m), rng.uniform(right, left)
        a, b = rng.uniform(0.4, 1.5), rng.uniform(0.3, 0.8)
        th = float(road.heading_at(s)) + rng.uniform(-0.3, 0.3)
        c, sn = math.cos(th), math.sin(th)
        local = np.stack([a * np.cos(ang), b * np.sin(ang)], 1)
        rot = local @ np.array([[c, sn], [-sn, c]])
        polygons.append(road.position(s, r) + rot)
    if polygons:
        add_mesh_geom(spec, "cond_puddles", _polygon_mesh(polygons, OVERLAY_Z_M - 0.002),
                  "cond_puddle", GROUP_SHADOW)
        info.puddle_polygons = polygons


def _add_snow(spec: mujoco.MjSpec, road: Road, cond: Conditions,
              rng: np.random.Generator, layout: WorldLayout) -> None:
    tex = textures.gravel(rng)
    snow = np.clip(235 + (tex.astype(np.int16) - tex.mean()) * 0.25, 0, 255).astype(np.uint8)
    t = spec.add_texture(name="cond_snow", type=mujoco.mjtTexture.mjTEXTURE_2D,
                         width=snow.shape[1], height=snow.shape[0], nchannel=3)
    t.data = np.ascontiguousarray(snow).tobytes()
    for name in ("grass", "gravel"):
        spec.material(name).textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "cond_snow"
    spec.add_material(name="cond_snowdrift", rgba=[0.95, 0.96, 0.98, 0.35 + 0.55 * cond.snow],
                      specular=0.1, shininess=0.1)
    inner = 0.25 + 0.9 * (1.0 - cond.snow)  # distance kept clear of the edge lines (m)
    for i, (s0, s1) in enumerate(road.segment_bounds()):
        drifts = Ribbon.concatenate([
            ribbon(road, s0, s1, road.boundary_r(0) - layout.shoulder_m,
                   road.boundary_r(0) - inner, OVERLAY_Z_M, layout.tile_m),
            ribbon(road, s0, s1, road.boundary_r(road.n_lanes) + inner,
                   road.boundary_r(road.n_lanes) + layout.shoulder_m, OVERLAY_Z_M, layout.tile_m),
        ])
        add_mesh_geom(spec, f"cond_snowdrift_{i}", drifts, "cond_snowdrift", GROUP_SHADOW)


# -- traffic -----------------------------------------------------------------------------------
def _add_vehicle(spec: mujoco.MjSpec, road: Road, v: VehicleSpec, index: int) -> VehicleTrack:
    if not 0 <= v.lane < road.n_lanes:
        raise ValueError(
            f"conditions.vehicles[{index}].lane = {v.lane} not in 0..{road.n_lanes - 1}"
        )
    r = road.lane_center_r(v.lane) + v.offset_m
    name = f"cond_vehicle_{index}"
    x, y = road.position(v.s_m, r)
    yaw = float(road.heading_at(v.s_m)) + (math.pi if v.speed_mps < 0 else 0.0)
    body = spec.worldbody.add_body(name=name, mocap=True, pos=[x, y, 0.0], quat=yaw_quat(yaw))
    L, W, H = v.length_m, v.width_m, v.height_m  # noqa: N806
    clearance = 0.25
    lower = 0.55 * (H - clearance)
    paint = [*v.colour, 1.0]
    body.add_geom(name=f"{name}_body", type=mujoco.mjtGeom.mjGEOM_BOX, group=GROUP_WORLD,
                  pos=[0, 0, clearance + 0.5 * lower], size=[0.5 * L, 0.5 * W, 0.5 * lower],
                  rgba=paint, contype=0, conaffinity=0, mass=1.0)
    cabin = H - clearance - lower
    body.add_geom(name=f"{name}_cabin", type=mujoco.mjtGeom.mjGEOM_BOX, group=GROUP_WORLD,
                  pos=[-0.08 * L, 0, clearance + lower + 0.5 * cabin],
                  size=[0.3 * L, 0.46 * W, 0.5 * cabin],
                  rgba=[0.5 * c for c in v.colour] + [1.0], contype=0, conaffinity=0, mass=1.0)
    for j, ax in enumerate((0.32 * L, -0.32 * L)):
        body.add_geom(name=f"{name}_axle_{j}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                      group=GROUP_WORLD, pos=[ax, 0, 0.34], euler=[math.pi / 2, 0, 0],
                      size=[0.34, 0.5 * W - 0.02, 0], rgba=[0.05, 0.05, 0.05, 1.0],
                      contype=0, conaffinity=0, mass=1.0)
    return VehicleTrack(name, v.s_m, r, v.speed_mps)


def update_dynamic(world, t_s: float) -> None:
    """Move the other vehicles to their poses at sim time t_s (call every control step).

    Sets the mocap poses and runs mj_kinematics, so a render straight after sees them.
    """
    info: ConditionsInfo | None = getattr(world, "conditions", None)
    if info is None or not info.vehicles:
        return
    road, data = world.road, world.data
    for v in info.vehicles:
        if v.mocap_id < 0:
            v.mocap_id = int(world.model.body(v.name).mocapid[0])
        s = v.s_m + v.speed_mps * t_s
        data.mocap_pos[v.mocap_id, :2] = road.position(s, v.r_m)
        yaw = float(road.heading_at(s)) + (math.pi if v.speed_mps < 0 else 0.0)
        data.mocap_quat[v.mocap_id] = yaw_quat(yaw)
    mujoco.mj_kinematics(world.model, data)


def occluded_marking_share(world, rig, camera: str = "front") -> float:
    """Share of the marking pixels that the other vehicles hide in one camera (0..1).

    Renders the segmentation twice, with the vehicles in place and with them lowered 1 km
    under the ground; NaN when no marking is in view.
    """
    info: ConditionsInfo | None = getattr(world, "conditions", None)
    seen = int(world.marking_mask(rig.render_segmentation(world.data, camera)).sum())
    if info is None or not info.vehicles:
        return 0.0
    ids = [v.mocap_id if v.mocap_id >= 0 else int(world.model.body(v.name).mocapid[0])
           for v in info.vehicles]
    saved = world.data.mocap_pos.copy()
    try:
        world.data.mocap_pos[ids, 2] -= 1000.0
        mujoco.mj_kinematics(world.model, world.data)
        total = int(world.marking_mask(rig.render_segmentation(world.data, camera)).sum())
    finally:
        world.data.mocap_pos[:] = saved
        mujoco.mj_kinematics(world.model, world.data)
    return math.nan if total == 0 else 1.0 - seen / total


# -- entry point -------------------------------------------------------------------------------
def add_conditions(spec: mujoco.MjSpec, scenario: Scenario, road: Road,
                   layout: WorldLayout | None = None) -> ConditionsInfo:
    """Add the scenario's conditions to a spec that already holds the car, road and markings
    (laid out by `layout`: shoulders, gravel, texture period)."""
    layout = layout or WorldLayout()
    cond = scenario.conditions
    rng = np.random.default_rng([scenario.seed, 0xC0D])
    info = ConditionsInfo(headlights=cond.headlights)
    _add_light_and_sky(spec, cond, road)
    if cond.fog > 0.0:
        info.fog_visibility_m = fog_visibility_m(cond.fog)
    if cond.headlights:
        _add_car_lights(spec)
        _densify_asphalt(spec, road, layout)
    to_sun = sun_direction(cond, road)
    for i, zone in enumerate(cond.shadows):
        spec.add_material(name=f"cond_shadow_{i}", rgba=[0.0, 0.0, 0.0, zone.darkness],
                          specular=0.0, shininess=0.0)
        _add_zone(spec, road, zone, i, to_sun, rng, info, layout)
    if cond.speed_bumps_m:
        spec.add_material(name="cond_bump", rgba=[0.95, 0.75, 0.1, 1.0], specular=0.2)
        _add_bumps(spec, road, cond, info, layout)
    if cond.wet > 0.0:
        # At a camera's grazing angle water mirrors the sky: sky-coloured, self-lit, glossy.
        horizon = LIGHTING[cond.time_of_day][3][1]
        spec.add_material(name="cond_puddle", rgba=[*(0.4 * np.array(horizon)), 0.55],
                          emission=0.3, specular=0.9, shininess=1.0)
        _add_wet(spec, road, cond, rng, info, layout)
    if cond.snow > 0.0:
        _add_snow(spec, road, cond, rng, layout)
    for i, vehicle in enumerate(cond.vehicles):
        info.vehicles.append(_add_vehicle(spec, road, vehicle, i))
    return info
