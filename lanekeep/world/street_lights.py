"""Street lamps at night: the roadside's light poles (`[roadside] pole_spacing_m`) get lit heads
and a glow around each.

Why no MuJoCo lights: its renderer lights per vertex, so a lamp's light on the road would need
the fine road grid everywhere (the car's headlights already force a 0.5 m grid) and every light
costs every vertex of every render, on the whole road, while a road has a lamp every 30-60 m.
Instead each lamp is drawn as what a camera records of it:
  - the head: an emissive lens under the pole's lamp housing (GROUP_WORLD);
  - a glow: a translucent emissive ellipsoid around the lens (GROUP_SHADOW: colour render only,
    so the segmentation and the marking masks do not see it);
All lamps' pieces of one kind share a mesh geom: 2 geoms in all.

Pools of light on the road: a translucent emissive overlay failed (MuJoCo's translucent pass
draws each overlay twice and the paint ribbons once, lanekeep/world/paint.py, so a lane line
under a lamp came out darker than the asphalt beside it). The pools are real light instead:
POOL_LIGHTS downward spot lights owned by the world, moved every control step to the lamps
nearest a point POOL_FOCUS_M ahead of the car (`update_pools`, from World.reset / World.step),
so the front camera sees the pools ahead and the rear camera the one behind. Lit road then
takes the lamp's warm colour, falls off with the distance from the pole, and paint, being
brighter than asphalt, stays brighter under the lamp. The farthest chosen lamp fades in over
POOL_FADE_M as it becomes one of the nearest, so no pool pops on. Every pool light costs
every lit vertex (the 0.5 m night grid) of every render, hence only a few.
"""

from __future__ import annotations

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon
from lanekeep.scenario.schema import Scenario
from lanekeep.world.groups import GROUP_SHADOW, GROUP_WORLD
from lanekeep.world.parts import ConditionsInfo, WorldLayout, add_mesh_geom
from lanekeep.world.prop_assets import pole_heads
from lanekeep.world.prop_meshes import box, ellipsoid

LAMP_RGB = (1.0, 0.78, 0.48)  # high-pressure sodium: the warm orange of most street lamps
GLOW_RADIUS_M = 0.7
GLOW_ALPHA = 0.22
HEAD_Z_M = 9.72  # underside of the lamp housing (prop_assets.light_poles)
POOL_LIGHTS = 3  # spot lights moved from lamp to lamp (MuJoCo's renderer lights up to 8)
POOL_FOCUS_M = 12.0  # lamps are chosen nearest this far ahead of the car
POOL_FADE_M = 10.0  # the farthest chosen lamp's light fades in over this distance
POOL_RGB = (1.0, 0.72, 0.42)  # high-pressure sodium light on the road
POOL_CUTOFF_DEG = 66.0  # a street lamp throws light wide along the road: ~22 m around it
POOL_EXPONENT = 2.5  # brightest under the lamp, falling off towards the cutoff
POOL_ATTENUATION = (0.55, 0.0, 0.0035)  # 1 / (a0 + a1 d + a2 d^2), d in metres


def pool_light_name(k: int) -> str:
    return f"street_pool_{k}"


def add_street_lights(spec: mujoco.MjSpec, scenario: Scenario, road: Road,
                      layout: WorldLayout, info: ConditionsInfo | None = None) -> int:
    """Light the roadside's poles when it is night, with POOL_LIGHTS pool lights to move
    among them (their lamps' positions go to `info`); returns how many lamps were lit."""
    cfg = scenario.roadside
    if scenario.conditions.time_of_day != "night" or cfg.pole_spacing_m <= 0.0:
        return 0
    heads = [pole_heads(road, side, cfg.pole_spacing_m, layout) for side in cfg.pole_sides]
    xy = np.concatenate([h[0] for h in heads])
    heading = np.concatenate([h[1] for h in heads])
    if not len(xy):
        return 0
    spec.add_material(name="street_lamp", rgba=[*LAMP_RGB, 1.0], emission=1.0, specular=0.0)
    spec.add_material(name="street_lamp_glow", rgba=[*LAMP_RGB, GLOW_ALPHA], emission=1.0,
                      specular=0.0)
    lenses = [box(np.r_[p, HEAD_Z_M], float(th), (0.18, 0.24, 0.02))
              for p, th in zip(xy, heading, strict=True)]
    add_mesh_geom(spec, "street_lamp_heads", Ribbon.concatenate(lenses), "street_lamp",
                  GROUP_WORLD)
    glows = [ellipsoid(np.r_[p, HEAD_Z_M - 0.1], (GLOW_RADIUS_M, GLOW_RADIUS_M,
                                                  0.6 * GLOW_RADIUS_M), 8, 4) for p in xy]
    add_mesh_geom(spec, "street_lamp_glow", Ribbon.concatenate(glows), "street_lamp_glow",
                  GROUP_SHADOW)
    for k in range(min(POOL_LIGHTS, len(xy))):
        spec.worldbody.add_light(
            name=pool_light_name(k), type=mujoco.mjtLightType.mjLIGHT_SPOT,
            pos=[float(xy[k, 0]), float(xy[k, 1]), HEAD_Z_M - 0.05], dir=[0.0, 0.0, -1.0],
            cutoff=POOL_CUTOFF_DEG, exponent=POOL_EXPONENT, diffuse=list(POOL_RGB),
            ambient=[0.0, 0.0, 0.0], specular=[0.15, 0.11, 0.06],
            attenuation=list(POOL_ATTENUATION), castshadow=False)
    if info is not None:
        info.street_lamps_xy = xy
    return len(xy)


def pool_weights(distances_m: np.ndarray, n: int = POOL_LIGHTS) -> tuple[np.ndarray, np.ndarray]:
    """The lamps to light (indices into `distances_m`, nearest first, at most n) and each one's
    share of full light: 1 unless it is within POOL_FADE_M of losing its place to the next
    lamp, so a pool fades in and out instead of popping (both are 0 at the swap)."""
    order = np.argsort(distances_m, kind="stable")
    chosen = order[:n]
    if len(order) <= n:
        return chosen, np.ones(len(chosen))
    next_m = distances_m[order[n]]
    return chosen, np.clip((next_m - distances_m[chosen]) / POOL_FADE_M, 0.0, 1.0)


def update_pools(world) -> None:
    """Move the pool lights to the lamps nearest a point ahead of the car (every control step
    and at reset: a function of the car's pose only, so the same run gives the same frames).

    Writes the lights' positions and colours into the world's own model (a light's colour
    lives only there) and recomputes the lights' world poses (mj_camlight), so a render
    straight after sees them."""
    info: ConditionsInfo | None = getattr(world, "conditions", None)
    if info is None or info.street_lamps_xy is None or not len(info.street_lamps_xy):
        return
    model, lamps = world.model, info.street_lamps_xy
    x, y, yaw = world.car.pose()
    focus = np.array([x + POOL_FOCUS_M * np.cos(yaw), y + POOL_FOCUS_M * np.sin(yaw)])
    chosen, weights = pool_weights(np.linalg.norm(lamps - focus, axis=1))
    for k, (lamp, weight) in enumerate(zip(chosen, weights, strict=True)):
        i = model.light(pool_light_name(k)).id
        model.light_pos[i, :2] = lamps[lamp]
        model.light_diffuse[i] = weight * np.asarray(POOL_RGB)
    mujoco.mj_camlight(model, world.data)

