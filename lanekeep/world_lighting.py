"""Light of a scenario's world: sun and sky by time of day, the car's lights, fog.

Dawn, dusk and night dim the sun, the ambient light and the sky and switch on the car's
headlights (two white spot lights, lit road ~35 m ahead) and a dim red tail light (the rear
camera sees ~8 m of road). MuJoCo lights per vertex, so with headlights the asphalt ribbons are
re-meshed as a 0.5 m grid. Fog: MuJoCo's linear fog up to the visibility distance, in the
sky's horizon colour; scenes without fog put it beyond the far clip plane.
"""


from __future__ import annotations

import math

import mujoco
import numpy as np

from lanekeep.road import Road
from lanekeep.road_mesh import Ribbon, ribbon
from lanekeep.scenario import Conditions
from lanekeep.world_parts import ROAD_Z_M, WorldLayout

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

GRID_STEP_M = 0.5  # lateral/along step of the re-meshed asphalt under headlights


def fog_visibility_m(fog: float) -> float:
    """Meteorological visibility (5% contrast) of a fog density in (0, 1]."""
    near, far = FOG_VISIBILITY_M
    return near * (far / near) ** fog


def sun_direction(conditions: Conditions, road: Road) -> np.ndarray:
    """Unit vector from the ground towards the sun, world frame."""
    el = math.radians(conditions.sun_elevation_deg)
    az = math.radians(conditions.sun_azimuth_deg) + float(road.heading_at(0.0))
    return np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])


def add_light_and_sky(spec: mujoco.MjSpec, cond: Conditions, road: Road) -> None:
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


def add_car_lights(spec: mujoco.MjSpec) -> None:
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


def densify_asphalt(spec: mujoco.MjSpec, road: Road, layout: WorldLayout) -> None:
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
