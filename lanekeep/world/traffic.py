"""Other vehicles: mocap bodies moved along their lanes each control step, and how much of
the paint they hide from a camera.

Each vehicle is a car, van or truck built from primitives (lanekeep/world/vehicle_assets.py: wheels
on the ground, arches, windows, lights, bumpers) on a mocap body whose origin stays on the
ground. Camera shadow maps are off by default (they double a CPU render), so like the roadside
casters (roadside.py) a vehicle's shadow is drawn: two dark translucent polygons in group
GROUP_SHADOW (hidden from the segmentation render, so the marking masks stay exact), children of
the mocap body so they drive along:

  - a contact shadow: ambient occlusion, a soft-edged texture over the footprint grown by
    CONTACT_FRINGE_M, darkness CONTACT_DARKNESS under the body's middle (the road under a car
    gets neither sun nor most of the sky, sun or not: the dark band real cars stand on);
  - the cast shadow: the convex hull of all parts' corners cast along the sun onto the road,
    computed in the vehicle's frame for its heading at the build. As the road turns, the
    shadow turns with the vehicle: its tip errs by the turn angle times the shadow's length
    (0.72 rad in the "occlusion" scenario's bend: ~0.5 m for a car, ~1.1 m for its truck).
    Its darkness follows the sun's strength (none at night). Where it overlaps a building's
    shadow the two overlays darken each other.
"""


from __future__ import annotations

import math
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon
from lanekeep.scenario.conditions import VehicleSpec
from lanekeep.traffic.constant import ConstantFlow
from lanekeep.traffic.flow import TrafficFlow
from lanekeep.traffic.state import EgoState
from lanekeep.world.groups import GROUP_SHADOW, GROUP_WORLD
from lanekeep.world.parts import (
    OVERLAY_Z_M,
    ConditionsInfo,
    VehicleTrack,
    add_material,
    add_texture,
    yaw_quat,
)
from lanekeep.world.prop_meshes import ellipsoid
from lanekeep.world.roadside import cast_shadow, overlay_alpha
from lanekeep.world.shade import TRANSLUCENT_ALPHA
from lanekeep.world.vehicle_assets import Part, vehicle_parts
from lanekeep.world.vehicle_textures import textured_box, trailer_texture

if TYPE_CHECKING:
    from lanekeep.world.traffic_flow import TrafficPlan

SUN_SHADOW_DARKNESS = 0.55  # as a ShadowZone's default, under the full day sun
DAY_SUN_DIFFUSE = 0.75  # world_lighting.LIGHTING["day"]: the sun of SUN_SHADOW_DARKNESS
CONTACT_DARKNESS = 0.85  # the road under a car's middle gets neither sun nor most of the sky
CONTACT_FRINGE_M = 0.4  # how far beyond the footprint the body's ambient occlusion reaches
CONTACT_TEXELS = 64  # the contact shadow's texture (per vehicle: its proportions)
DAY_GLASS_GLOW = 0.35  # emission of the glass by day: the sky it mirrors
GLOW_ALPHA = 0.3  # a lit lamp's glow
LIGHTS_ON_BELOW = 0.5  # sun diffuse under which vehicles drive with lights on (dawn, dusk, night)

# role -> material attributes shared by all vehicles (paint is per vehicle). No `reflectance`:
# MuJoCo renders a reflective geom by drawing the scene again, once per geom. Glass is nearly
# black with a sharp highlight and, by day, a faint glow of the sky it mirrors (DAY_GLASS_GLOW).
SHARED_LOOK = {
    "glass": dict(rgba=[0.05, 0.065, 0.08, 1.0], specular=1.0, shininess=0.95),
    "tyre": dict(rgba=[0.035, 0.035, 0.035, 1.0], specular=0.05, shininess=0.1),
    "hub": dict(rgba=[0.55, 0.56, 0.58, 1.0], specular=0.6, shininess=0.6),
    "trim": dict(rgba=[0.1, 0.1, 0.11, 1.0], specular=0.2, shininess=0.3),
    "underbody": dict(rgba=[0.02, 0.02, 0.022, 1.0], specular=0.0, shininess=0.0),
    "plate": dict(rgba=[0.9, 0.9, 0.85, 1.0], specular=0.3, shininess=0.3),
}


def add_vehicle(spec: mujoco.MjSpec, road: Road, v: VehicleSpec, index: int,
                to_sun: np.ndarray | None = None) -> VehicleTrack:
    """Add vehicle `index` at its start pose. `to_sun` (unit vector towards the sun, world
    frame) places its cast shadow; by default it is read from the spec's light "sun"."""
    if not 0 <= v.lane < road.n_lanes:
        raise ValueError(
            f"conditions.vehicles[{index}].lane = {v.lane} not in 0..{road.n_lanes - 1}"
        )
    r = road.lane_center_r(v.lane) + v.offset_m
    name = f"cond_vehicle_{index}"
    x, y = road.position(v.s_m, r)
    yaw = float(road.heading_at(v.s_m)) + (math.pi if v.speed_mps < 0 else 0.0)
    body = spec.worldbody.add_body(name=name, mocap=True, pos=[x, y, 0.0], quat=yaw_quat(yaw))
    to_sun, sun = _sun(spec, to_sun)
    materials = _materials(spec, name, v.colour, sun)
    parts = vehicle_parts(v)
    for part in parts:
        _add_part(spec, body, name, part, materials[part.role])
    _add_shadows(spec, body, name, parts, yaw, to_sun, sun)
    if sun < LIGHTS_ON_BELOW:
        _add_glows(spec, body, name, parts)
    return VehicleTrack(name, v.s_m, r, v.speed_mps)


def _sun(spec: mujoco.MjSpec, to_sun: np.ndarray | None) -> tuple[np.ndarray | None, float]:
    """Direction towards the sun and its diffuse strength, from the spec's light "sun" where
    not given (no light: no cast shadow; full strength when only the direction is given)."""
    light = spec.light("sun")
    strength = float(np.mean(light.diffuse)) if light is not None else DAY_SUN_DIFFUSE
    if to_sun is None and light is not None:
        to_sun = -np.asarray(light.dir, dtype=float)
    if to_sun is not None:
        to_sun = np.asarray(to_sun, dtype=float) / np.linalg.norm(to_sun)
    return to_sun, strength


def _material(spec: mujoco.MjSpec, name: str, **attrs) -> str:
    if spec.material(name) is None:
        spec.add_material(name=name, **attrs)
    return name


def _materials(spec: mujoco.MjSpec, name: str, colour, sun: float) -> dict[str, str]:
    """Material per role: shared ones made once, the paint per vehicle; lamps glow when the
    sun is low (as the ego car's headlights come on)."""
    lit = sun < LIGHTS_ON_BELOW
    out = {role: _material(spec, f"cond_vehicle_{role}", **look)
           for role, look in SHARED_LOOK.items()}
    spec.material("cond_vehicle_glass").emission = DAY_GLASS_GLOW * min(1.0, sun / DAY_SUN_DIFFUSE)
    out["taillight"] = _material(spec, "cond_vehicle_taillight", rgba=[0.75, 0.04, 0.03, 1.0],
                                 emission=1.0 if lit else 0.25, specular=0.5)
    out["headlight"] = _material(spec, "cond_vehicle_headlight", rgba=[0.95, 0.93, 0.85, 1.0],
                                 emission=1.0 if lit else 0.2, specular=0.8)
    out["paint"] = _material(spec, f"{name}_paint", rgba=[*colour, 1.0], specular=0.75,
                             shininess=0.85)
    if spec.texture("cond_vehicle_trailer") is None:
        add_texture(spec, "cond_vehicle_trailer", trailer_texture())
    out["trailer"] = f"{name}_trailer"
    if spec.material(out["trailer"]) is None:
        add_material(spec, out["trailer"], "cond_vehicle_trailer", rgba=[*colour, 1.0],
                     specular=0.3, shininess=0.4)
    return out


def _add_part(spec: mujoco.MjSpec, body, name: str, part: Part, material: str) -> None:
    geom = f"{name}_{part.name}"
    common = dict(name=geom, group=GROUP_WORLD, material=material, contype=0, conaffinity=0,
                  mass=1.0)
    if part.role == "trailer":  # a textured box (lanekeep/world/vehicle_textures.py)
        mesh = textured_box(part.pos, part.size)
        spec.add_mesh(name=geom, uservert=mesh.vertices.astype(np.float32).ravel().tolist(),
                      userface=mesh.faces.ravel().tolist(),
                      usertexcoord=mesh.texcoords.astype(np.float32).ravel().tolist(),
                      inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL)
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=geom, **common)
        return
    if part.shape == "hull":
        spec.add_mesh(name=geom, uservert=np.ravel(part.points).tolist())
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=geom, **common)
        return
    kind = mujoco.mjtGeom.mjGEOM_BOX if part.shape == "box" else mujoco.mjtGeom.mjGEOM_CYLINDER
    body.add_geom(type=kind, pos=list(part.pos), size=list(part.size), quat=list(part.quat),
                  **common)


def _add_glows(spec: mujoco.MjSpec, body, name: str, parts: list[Part]) -> None:
    """A lit lamp's glow as a camera sees it in the dark: a translucent emissive ellipsoid
    around each head and tail light (GROUP_SHADOW: the colour render only), one mesh geom
    per colour and vehicle."""
    for role, rgba in (("headlight", [1.0, 0.95, 0.85, GLOW_ALPHA]),
                       ("taillight", [1.0, 0.08, 0.04, GLOW_ALPHA])):
        lamps = [p for p in parts if p.role == role]
        if not lamps:
            continue
        material = _material(spec, f"cond_vehicle_{role}_glow", rgba=rgba, emission=1.0,
                             specular=0.0, shininess=0.0)
        glow = Ribbon.concatenate([ellipsoid(p.pos, (0.25, 0.35, 0.22), 6, 3) for p in lamps])
        geom = f"{name}_{role}_glow"
        spec.add_mesh(name=geom, uservert=glow.vertices.astype(np.float32).ravel().tolist(),
                      userface=glow.faces.ravel().tolist(),
                      inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL)
        body.add_geom(name=geom, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=geom,
                      material=material, group=GROUP_SHADOW, contype=0, conaffinity=0, mass=1.0)


def contact_polygon(parts: list[Part], margin_m: float = CONTACT_FRINGE_M) -> np.ndarray:
    """Footprint of the parts (mirrors aside: they are high above the road) grown by a margin:
    the contact shadow's quad, CCW (4, 2), vehicle frame."""
    pts = np.concatenate([p.corners() for p in parts if not p.name.startswith("mirror")])
    (x0, y0), (x1, y1) = pts[:, :2].min(0) - margin_m, pts[:, :2].max(0) + margin_m
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])


def contact_darkness(length_m: float, width_m: float, texels: int = CONTACT_TEXELS
                     ) -> np.ndarray:
    """(texels, texels) darkness (1 - light kept) of the road under and around a footprint
    length_m x width_m, over the footprint grown by CONTACT_FRINGE_M: CONTACT_DARKNESS where
    the body hides nearly all the sky (more than 0.2 m inside its outline), about 0.65 of
    that at the outline, fading to none CONTACT_FRINGE_M beyond it (ambient occlusion:
    the skylight a car's body and sills block, the dark band real cars stand on)."""
    f = CONTACT_FRINGE_M
    along = (np.arange(texels) + 0.5) / texels * (length_m + 2 * f) - 0.5 * length_m - f
    across = (np.arange(texels) + 0.5) / texels * (width_m + 2 * f) - 0.5 * width_m - f
    dx = np.abs(along)[None, :] - 0.5 * length_m
    dy = np.abs(across)[:, None] - 0.5 * width_m
    outside = np.hypot(np.maximum(dx, 0.0), np.maximum(dy, 0.0))
    d = outside + np.minimum(np.maximum(dx, dy), 0.0)  # signed distance to the outline (m)
    ramp = np.clip(0.65 - d / (0.6 * f / 0.4), 0.0, 1.0)
    return (CONTACT_DARKNESS * ramp * ramp * (3.0 - 2.0 * ramp)).astype(np.float32)


def cast_polygon(parts: list[Part], to_sun_local: np.ndarray) -> np.ndarray:
    """Shadow of the vehicle's convex hull on the road, vehicle frame: CCW polygon (n, 2)."""
    return cast_shadow(np.concatenate([p.corners() for p in parts]), to_sun_local)


def _add_shadows(spec: mujoco.MjSpec, body, name: str, parts: list[Part], yaw: float,
                 to_sun: np.ndarray | None, sun: float) -> None:
    quad = contact_polygon(parts)
    length, width = quad[2] - quad[0] - 2.0 * CONTACT_FRINGE_M
    darkness = contact_darkness(float(length), float(width))
    rgba = np.zeros((*darkness.shape, 4), np.uint8)
    per_pass = 1.0 - np.sqrt(1.0 - darkness)  # overlay_alpha: MuJoCo blends it twice
    rgba[..., 3] = np.clip(np.round(255.0 * per_pass / TRANSLUCENT_ALPHA), 0, 255)
    texture = spec.add_texture(name=f"{name}_contact_shadow", nchannel=4,
                               type=mujoco.mjtTexture.mjTEXTURE_2D,
                               width=rgba.shape[1], height=rgba.shape[0])
    texture.data = np.ascontiguousarray(rgba).tobytes()
    add_material(spec, f"{name}_contact_shadow", f"{name}_contact_shadow",
                 rgba=[1.0, 1.0, 1.0, TRANSLUCENT_ALPHA], specular=0.0, shininess=0.0)
    _add_polygon(spec, body, f"{name}_contact_shadow", quad, OVERLAY_Z_M + 0.004,
                 f"{name}_contact_shadow", uv=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float))
    darkness = SUN_SHADOW_DARKNESS * min(1.0, sun / DAY_SUN_DIFFUSE)
    if to_sun is None or to_sun[2] <= 0.0 or darkness < 0.05:
        return
    c, s = math.cos(yaw), math.sin(yaw)
    local = np.array([c * to_sun[0] + s * to_sun[1], -s * to_sun[0] + c * to_sun[1], to_sun[2]])
    cast = _material(spec, "cond_vehicle_sun_shadow",
                     rgba=[0.0, 0.0, 0.0, overlay_alpha(darkness)], specular=0.0, shininess=0.0)
    _add_polygon(spec, body, f"{name}_shadow", cast_polygon(parts, local), OVERLAY_Z_M, cast)


def _add_polygon(spec: mujoco.MjSpec, body, name: str, poly: np.ndarray, z_m: float,
                 material: str, uv: np.ndarray | None = None) -> None:
    """A flat convex polygon (CCW, body frame) as a triangle-fan mesh geom in GROUP_SHADOW,
    with texture coordinates `uv` (n, 2) per corner if given."""
    n = len(poly)
    verts = np.c_[poly, np.full(n, z_m)]
    i = np.arange(1, n - 1)
    faces = np.stack([np.zeros_like(i), i, i + 1], 1)
    extra = {} if uv is None else {"usertexcoord": np.asarray(uv, float).ravel().tolist()}
    spec.add_mesh(name=name, uservert=verts.ravel().tolist(), userface=faces.ravel().tolist(),
                  inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL, **extra)
    body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name, material=material,
                  group=GROUP_SHADOW, contype=0, conaffinity=0, mass=1.0)


def make_flow(plan: TrafficPlan | None, road: Road) -> TrafficFlow | ConstantFlow | None:
    """The traffic model that drives the plan's vehicles (None without vehicles)."""
    if plan is None or not plan.vehicles:
        return None
    centres = [road.lane_center_r(k) for k in range(road.n_lanes)]
    if plan.model == "constant":
        return ConstantFlow(centres, road.length_m, road.closed, plan.setups)
    return TrafficFlow(lane_centres_m=centres, lane_directions=plan.lane_directions,
                       road_length_m=road.length_m, closed=road.closed, vehicles=plan.setups,
                       events=plan.events, lane_width_m=road.lane_width_m,
                       no_entry_lanes=(plan.ego_lane,))


def update_dynamic(world, t_s: float) -> None:
    """Move the other vehicles to their poses at sim time t_s (call every control step).

    Advances the traffic model (`world.traffic`) to t_s, the car as it now is among them,
    sets the mocap poses and runs mj_kinematics, so a render straight after sees them.
    """
    info: ConditionsInfo | None = getattr(world, "conditions", None)
    flow = getattr(world, "traffic", None)
    if info is None or not info.vehicles or flow is None:
        return
    road, data = world.road, world.data
    _advance(world, flow, t_s)
    states = {state.name: state for state in flow.states}
    for v in info.vehicles:
        if v.mocap_id < 0:
            v.mocap_id = int(world.model.body(v.name).mocapid[0])
    moving = [states[v.name] for v in info.vehicles]
    s = np.array([state.s_m for state in moving])
    # one road look-up for all (a vehicle at a time cost 50 us each, most of the stage)
    xy = np.atleast_2d(road.position(s, np.array([state.r_m for state in moving])))
    heading = np.atleast_1d(road.heading_at(s))
    for v, state, p, h in zip(info.vehicles, moving, xy, heading, strict=True):
        yaw = float(h) + (math.pi if state.direction < 0 else 0.0) + state.heading_offset_rad
        data.mocap_pos[v.mocap_id, :2] = p
        data.mocap_quat[v.mocap_id] = yaw_quat(yaw)
    mujoco.mj_kinematics(world.model, data)


def _advance(world, flow: TrafficFlow | ConstantFlow, t_s: float) -> None:
    """Step the traffic model from its time to t_s with the car's present state (the car
    moved over the same period: the others see where it is now, as a driver's glance does)."""
    dt = t_s - flow.time_s
    if dt < -1e-9:  # the physics went back in time without a reset: replay from the start
        flow.reset()
        dt = t_s
    if dt <= 1e-12:
        return
    car = world.car
    x, y, _ = car.pose()
    s, r = world.road.local_coordinates(np.array([x, y]))
    geometry = car.geometry
    ego = EgoState(s_m=float(s), r_m=float(r), speed_mps=max(0.0, car.speed_mps()),
                   length_m=geometry.length_m, width_m=geometry.width_m)
    flow.step(dt, ego)


def occluded_marking_share(world, rig, camera: str = "front",
                           boundaries: tuple[int, ...] | None = None) -> float:
    """Share of the marking pixels (of `boundaries` only, if given) that the other vehicles
    hide in one camera (0..1).

    Renders the segmentation twice, with the vehicles in place and with them lowered 1 km
    under the ground; NaN when no marking is in view.
    """
    def paint() -> int:
        seg = rig.render_segmentation(world.data, camera)
        if boundaries is None:
            return int(world.marking_mask(seg).sum())
        return sum(int(world.marking_mask(seg, b).sum()) for b in boundaries)

    info: ConditionsInfo | None = getattr(world, "conditions", None)
    seen = paint()
    if info is None or not info.vehicles:
        return 0.0
    ids = [v.mocap_id if v.mocap_id >= 0 else int(world.model.body(v.name).mocapid[0])
           for v in info.vehicles]
    saved = world.data.mocap_pos.copy()
    try:
        world.data.mocap_pos[ids, 2] -= 1000.0
        mujoco.mj_kinematics(world.model, world.data)
        total = paint()
    finally:
        world.data.mocap_pos[:] = saved
        mujoco.mj_kinematics(world.model, world.data)
    return math.nan if total == 0 else 1.0 - seen / total
