"""What a scenario's conditions add to the MuJoCo world: light, shadows, bumps, wet, fog, traffic.

Called by `build_spec` (lanekeep/world/build.py, `add_conditions`) after the road and markings
exist; their look, the sky, sun and fog are decided from the scenario before the build
(lanekeep/world/appearance.py). Everything is seeded from the scenario seed, so one scenario
always builds the same world. The work is split by concern: lanekeep/world/lighting.py (car
lights), lanekeep/world/roadside.py (shadows and casters, bumps, wet, snow),
lanekeep/world/traffic.py (other vehicles).

  - Sun and time of day: the sun's direction comes from `Conditions.sun_*`; dawn, dusk and night
    dim the sun, the ambient light and the sky (decided before the build, appearance.py)
    and switch on the car's headlights (two white spot lights, lit road ~35 m ahead) and a dim
    red light from the tail lamps on the road just behind the car. MuJoCo lights per vertex, so with
    headlights build.py meshes the asphalt as a 0.5 m grid (lighting.py's GRID_STEP_M).
  - Cast shadows: shadow maps double the render cost on a CPU, so a building's or tree's shadow
    is its silhouette cast along the sun onto the ground: convex polygons drawn as black
    translucent overlays (group GROUP_SHADOW, hidden from the segmentation render so the marking
    masks stay exact), as dark as skylight alone leaves shade, with soft edges and, under trees,
    sunflecks (lanekeep/world/shade.py, which also says what `darkness` means). The casters
    (boxes, trees) stand beside the road and are rendered too.
  - Speed bumps: cylinders across the road sunk into the ground (a circular cap ~0.6 m long and
    `speed_bump_height_m` high) that the tyres collide with; yellow with black stripes.
  - Wet road: darker, glossier asphalt (a material tint, appearance.py) and puddles as
    dark glossy overlays (group GROUP_SHADOW); the camera mirrors the scene in both
    (lanekeep/sensing/weather.py, lanekeep/sensing/road_water.py).
  - Fog: MuJoCo's linear fog up to the visibility distance, in the sky's horizon colour.
    Scenes without fog put it beyond the far clip plane, so the render flag can stay on.
  - Snow: white verges (the grass and gravel materials use the snow texture made here) and snow
    drifts over the asphalt shoulders.
  - Other vehicles: cars, vans and trucks built from primitives (lanekeep/world/vehicle_assets.py:
    wheels on the ground, windows, lights, contact and cast shadows) on mocap bodies moved
    along their lanes by `update_dynamic(world, t_s)`; `occluded_marking_share` measures how
    much paint they hide.
"""

from __future__ import annotations

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.scenario.schema import Scenario
from lanekeep.world.lighting import (
    add_car_lights,
    fog_visibility_m,
    sun_direction,
)
from lanekeep.world.parts import ConditionsInfo, WorldLayout
from lanekeep.world.props import add_props
from lanekeep.world.roadside import add_bumps, add_shadow_zone, add_snow, add_wet, overlay_alpha
from lanekeep.world.shade import add_shadow_overlay, shade_transmission
from lanekeep.world.street_lights import add_street_lights
from lanekeep.world.traffic import add_vehicle
from lanekeep.world.traffic_flow import traffic_plan

DAPPLE_SEED = 0xDA9  # a tree zone's sunflecks: their own generator [seed, this, zone]
PUDDLE_RGB = (0.05, 0.055, 0.06)  # what the water's depth and the submerged asphalt give back
PUDDLE_DARKENING = 0.3  # how far a puddle darkens the wet asphalt towards it


def add_conditions(spec: mujoco.MjSpec, scenario: Scenario, road: Road,
                   layout: WorldLayout | None = None) -> ConditionsInfo:
    """Add the scenario's conditions to a spec that already holds the car, road and markings
    (laid out by `layout`: shoulders, gravel, texture period)."""
    layout = layout or WorldLayout()
    cond = scenario.conditions
    rng = np.random.default_rng([scenario.seed, 0xC0D])
    info = ConditionsInfo(headlights=cond.headlights)
    if cond.fog > 0.0:
        info.fog_visibility_m = fog_visibility_m(cond.fog)
    if cond.headlights:
        add_car_lights(spec)
    to_sun = sun_direction(cond, road)
    for i, zone in enumerate(cond.shadows):
        polygons = add_shadow_zone(spec, road, zone, i, to_sun, rng, info, layout)
        dapple = np.random.default_rng([scenario.seed, DAPPLE_SEED, i])
        if polygons:
            add_shadow_overlay(spec, f"cond_shadow_{i}", polygons,
                               shade_transmission(zone.darkness, cond),
                               dapple if zone.kind == "trees" else None)
    add_props(spec, scenario, road, to_sun, info, layout)  # after the zones: their shadows
    add_street_lights(spec, scenario, road, layout, info)
    if cond.speed_bumps_m:
        spec.add_material(name="cond_bump", rgba=[0.95, 0.75, 0.1, 1.0], specular=0.2)
        add_bumps(spec, road, cond, info, layout)
    if cond.wet > 0.0:
        # Standing water: the asphalt under it looks darker and smoother (PUDDLE_DARKENING);
        # what it mirrors depends on the view (Fresnel: little seen steeply near the car, much
        # at a grazing angle), so the camera adds it in image space
        # (lanekeep/sensing/weather.py). A sky-coloured, self-lit overlay was a flat grey
        # spindle a third of heavy_rain's rear frame high.
        spec.add_material(name="cond_puddle", rgba=[*PUDDLE_RGB, overlay_alpha(PUDDLE_DARKENING)],
                          specular=0.9, shininess=1.0)
        add_wet(spec, road, cond, rng, info, layout)
    if cond.snow > 0.0:
        add_snow(spec, road, cond, rng, layout)
    info.traffic_plan = traffic_plan(scenario, road)
    for i, vehicle in enumerate(info.traffic_plan.vehicles):
        info.vehicles.append(add_vehicle(spec, road, vehicle, i))
    return info
