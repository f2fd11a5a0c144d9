"""Light of a scenario's world: the tables of sun and sky by time of day, fog visibility, the
sun's direction, and the car's own lights.

Dawn, dusk and night dim the sun, the ambient light and the sky and switch on the car's
headlights (two white spot lights, lit road ~35 m ahead) and the tail lamps' faint red light
on the road just behind the car (a tenth of the headlit road's light, falling off with the
square of the distance). MuJoCo lights per vertex, so with headlights the asphalt ribbons are
meshed as a 0.5 m grid. Fog: MuJoCo's linear fog up to the visibility distance, in the sky's
horizon colour. Rain and snow: an overcast (`cloud_cover`), no direct sun, a grey sky.
lanekeep/world/appearance.py turns these into one scenario's values.
"""


from __future__ import annotations

import math

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.scenario.conditions import Conditions

# A clear day's sky, zenith and horizon: a mid blue, not a saturated one, over a pale hazy band
# (real dashcam skies are washed out; the bright band at the horizon is the air's haze).
SKY_DAY = ((0.52, 0.65, 0.84), (0.84, 0.87, 0.90))
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

GRID_STEP_M = 0.5  # lateral/along step of the asphalt mesh under headlights

# Fog is a layer the sun shines through: its direct light falls as exp(-3 path / V), the path
# being FOG_LAYER_M over the sine of the sun's elevation, and SKY_SCATTER of what is lost comes
# down as diffuse skylight (the rest goes back up or is absorbed), in proportion to what the
# sun gave a horizontal surface (diffuse x sin elevation). At fog 1 (V = 25 m) the sun
# is gone and shadows with it, as under real fog; at a light fog (V = 400 m) about half stays.
FOG_LAYER_M = 60.0
SKY_SCATTER = 0.6

# Rain and snow fall from an overcast: cloud cover grows with them (full from 0.5), the sun's
# direct light falls to OVERCAST_DIRECT of itself under a full cover (no hard shadows; what is
# lost comes down as skylight, as under fog), and the sky turns a flat grey (OVERCAST_SKY:
# zenith, horizon, at day; scaled with the time of day's horizon).
CLOUD_COVER_PER_PRECIPITATION = 2.0
OVERCAST_DIRECT = 0.03
OVERCAST_SKY = ((0.62, 0.64, 0.67), (0.74, 0.75, 0.77))
CLEAR_SKY_CLOUDS = 0.3  # fair-weather cumulus cover of a sky without rain or snow


def cloud_cover(conditions: Conditions) -> float:
    """Share of the sky under thick cloud (0 clear .. 1 overcast), from the rain and snow."""
    return min(1.0, CLOUD_COVER_PER_PRECIPITATION * max(conditions.rain, conditions.snow))


def fog_visibility_m(fog: float) -> float:
    """Meteorological visibility (5% contrast) of a fog density in (0, 1]."""
    near, far = FOG_VISIBILITY_M
    return near * (far / near) ** fog


def direct_sun_share(conditions: Conditions) -> float:
    """The share of the sun's direct light that the scenario's fog and cloud let through (1
    without either); the sun's diffuse light and the props' cast shadows are scaled by it."""
    clouds = 1.0 - (1.0 - OVERCAST_DIRECT) * cloud_cover(conditions)
    if conditions.fog <= 0.0:
        return clouds
    sin_el = max(math.sin(math.radians(conditions.sun_elevation_deg)), 0.05)
    return clouds * math.exp(-3.0 * FOG_LAYER_M / (fog_visibility_m(conditions.fog) * sin_el))


def sun_direction(conditions: Conditions, road: Road) -> np.ndarray:
    """Unit vector from the ground towards the sun, world frame."""
    el = math.radians(conditions.sun_elevation_deg)
    az = math.radians(conditions.sun_azimuth_deg) + float(road.heading_at(0.0))
    return np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])


# The two rear position lamps as one light. A lamp gives 4-17 cd along its axis (UN ECE R7),
# a few cd down at the road behind, against 1,000-10,000 cd of a low beam towards the road
# ahead: 1.5-3 m behind the car they light the road about a tenth as much as the low beams
# light it 10-25 m ahead (0.2-0.4 lux against ~2 lux), and the light falls off with the
# square of the distance. TAIL_RGB is set so that the render agrees (night, the near road
# 0.5-3.5 m behind the rear camera: +6 DN of red over a headlit road of 64 DN luma;
# tools/broken_details.py). Deep red: a tail lamp's filter passes almost no green or blue.
TAIL_RGB = (0.45, 0.02, 0.015)
TAIL_DIR = (-1.0, 0.0, -0.1)  # the lamps' axis: backwards, slightly down
TAIL_EXPONENT = 4.0  # their beam narrows to about +-15 deg in elevation


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
    car.add_light(name="tail_light", type=spot, pos=[-2.4, 0.0, 0.8], dir=list(TAIL_DIR),
                  cutoff=80.0, exponent=TAIL_EXPONENT, diffuse=list(TAIL_RGB),
                  ambient=[0.0, 0.0, 0.0], specular=[0.0, 0.0, 0.0],
                  attenuation=[0.0, 0.0, 1.0], castshadow=False)
