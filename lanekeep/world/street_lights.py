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

No pool of light on the road: drawn as a translucent emissive overlay (as the shadows are), it
lit the asphalt twice and the paint once (MuJoCo's translucent pass draws each overlay twice,
and the paint ribbons in between: lanekeep/world/paint.py), so a lane line under a lamp came
out darker than the road beside it, the opposite of a real road. A lit pool needs real light:
a few spot lights moved from lamp to lamp ahead of the car, not done yet.
"""

from __future__ import annotations

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon
from lanekeep.scenario.schema import Scenario
from lanekeep.world.groups import GROUP_SHADOW, GROUP_WORLD
from lanekeep.world.parts import WorldLayout, add_mesh_geom
from lanekeep.world.prop_assets import pole_heads
from lanekeep.world.prop_meshes import box, ellipsoid

LAMP_RGB = (1.0, 0.78, 0.48)  # high-pressure sodium: the warm orange of most street lamps
GLOW_RADIUS_M = 0.7
GLOW_ALPHA = 0.22
HEAD_Z_M = 9.72  # underside of the lamp housing (prop_assets.light_poles)


def add_street_lights(spec: mujoco.MjSpec, scenario: Scenario, road: Road,
                      layout: WorldLayout) -> int:
    """Light the roadside's poles when it is night; returns how many lamps were lit."""
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
    return len(xy)

