"""How a scenario's world looks, decided from the scenario before anything is built.

`appearance_of(scenario, road)` turns the conditions into the light (sun, ambient, sky, fog),
the surfaces (asphalt and gravel tones, wet gloss, snow-covered verges) and the asphalt mesh
density; `lanekeep.world.build` then builds each element once with these values, so no builder
patches another's elements by name afterwards.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.scenario.conditions import Conditions
from lanekeep.scenario.schema import Scenario
from lanekeep.world.lighting import (
    CLEAR_SKY_CLOUDS,
    FOG_END_OF_VISIBILITY,
    GRID_STEP_M,
    LIGHTING,
    OVERCAST_SKY,
    SKY_DAY,
    SKY_SCATTER,
    cloud_cover,
    direct_sun_share,
    fog_visibility_m,
    sun_direction,
)

MODEL_EXTENT_M = 100.0  # spec.stat.extent: MuJoCo's clip planes and fog are in these units
SNOW_TEXTURE = "cond_snow"  # made by world_roadside.add_snow, used by the verge materials

RGB = tuple[float, float, float]
RGBA = tuple[float, float, float, float]

# A night sky (zenith, horizon): near-black overhead, and low over the horizon the warm glow
# of the towns' sodium and LED light scattered in the air (lanekeep/world/sky.py lights the
# clouds with it). Also the colour of night fog, which that light lights.
NIGHT_SKY = ((0.004, 0.0045, 0.007), (0.075, 0.052, 0.034))


@dataclass(frozen=True)
class Lighting:
    """Sun, the camera headlight (MuJoCo's ambient fill), sky gradient and fog."""

    sun_dir: tuple[float, float, float]  # from the sun to the ground
    sun_diffuse: RGB
    sun_ambient: RGB
    sun_specular: float  # glare: grows with a wet road
    headlight_ambient: float
    headlight_diffuse: float
    sky_zenith: RGB
    sky_horizon: RGB  # also the fog and haze colour
    fog_start: float  # in units of MODEL_EXTENT_M; beyond the far clip plane = no fog
    fog_end: float
    clouds: float  # share of the sky under cloud (lanekeep/world/sky.py)
    overcast: float  # 0 fair-weather cumulus .. 1 a closed grey deck


@dataclass(frozen=True)
class Surfaces:
    """Material tints of the road and verges (multiplying their textures)."""

    asphalt_rgba: RGBA
    asphalt_specular: float
    asphalt_shininess: float
    gravel_rgba: RGBA
    verge_texture_grass: str  # texture of the grass material ("grass" or the snow texture)
    verge_texture_gravel: str


@dataclass(frozen=True)
class Appearance:
    lighting: Lighting
    surfaces: Surfaces
    asphalt_grid_step_m: float | None  # headlights light per vertex: a denser asphalt mesh


def lighting_of(cond: Conditions, road: Road) -> Lighting:
    """Time of day sets sun, ambient and sky; fog washes the sky grey and limits visibility."""
    sun_diffuse, sun_ambient, (head_amb, head_dif), (zenith, horizon) = LIGHTING[cond.time_of_day]
    if cond.time_of_day == "night":
        zenith, horizon = NIGHT_SKY
    glare = 0.1 + 0.6 * cond.wet if cond.time_of_day == "day" else 0.02 + 0.4 * cond.wet
    cover = cloud_cover(cond)
    if cover > 0.0:  # rain or snow: an overcast's flat grey sky
        scale = np.mean(horizon) / np.mean(SKY_DAY[1])
        zenith = tuple((1 - cover) * np.array(zenith) + cover * scale * np.array(OVERCAST_SKY[0]))
        horizon = tuple((1 - cover) * np.array(horizon)
                        + cover * scale * np.array(OVERCAST_SKY[1]))
    if cond.fog > 0.0:  # overcast: a sky washed towards the fog colour
        grey = np.array([0.72, 0.74, 0.76]) * (np.mean(horizon) / np.mean(SKY_DAY[1]))
        mix = 0.5 + 0.5 * cond.fog
        zenith = tuple((1 - mix) * np.array(zenith) + mix * grey)
        horizon = tuple((1 - mix) * np.array(horizon) + mix * grey)
        # MuJoCo's fog is linear in depth; ending it at 0.6 V follows Koschmieder's
        # exp(-3 d / V) within ~0.1 up to d = V / 2.
        fog_start = 0.0
        fog_end = FOG_END_OF_VISIBILITY * fog_visibility_m(cond.fog) / MODEL_EXTENT_M
    else:
        fog_start, fog_end = 1e3, 2e3  # beyond zfar: no fog, the render flag can stay on
    # Under fog the sun's direct light is scattered into diffuse skylight (world_lighting):
    # what it took from a horizontal surface (diffuse x sin elevation) comes back as ambient.
    direct = direct_sun_share(cond)
    on_ground = max(math.sin(math.radians(cond.sun_elevation_deg)), 0.0)
    sun_ambient = tuple(np.asarray(sun_ambient) + (1.0 - direct) * SKY_SCATTER * on_ground
                        * np.asarray(sun_diffuse))
    sun_diffuse = tuple(direct * np.asarray(sun_diffuse))
    to_sun = sun_direction(cond, road)
    return Lighting(
        sun_dir=tuple((-to_sun).tolist()), sun_diffuse=tuple(float(v) for v in sun_diffuse),
        sun_ambient=tuple(float(v) for v in sun_ambient), sun_specular=glare * direct,
        headlight_ambient=head_amb, headlight_diffuse=head_dif,
        sky_zenith=tuple(float(v) for v in zenith), sky_horizon=tuple(float(v) for v in horizon),
        fog_start=fog_start, fog_end=fog_end,
        clouds=CLEAR_SKY_CLOUDS + (1.0 - CLEAR_SKY_CLOUDS) * cover, overcast=cover,
    )


def surfaces_of(cond: Conditions) -> Surfaces:
    """Wet asphalt is darker and glossier (MuJoCo renders `reflectance` on planes only, and a
    reflective plane costs a second scene pass); snow whitens grass and gravel."""
    w = cond.wet
    snowy = cond.snow > 0.0
    return Surfaces(
        asphalt_rgba=(1.0 - 0.45 * w, 1.0 - 0.45 * w, 1.0 - 0.4 * w, 1.0),
        asphalt_specular=0.05 + 0.6 * w,
        asphalt_shininess=0.1 + 0.85 * w,
        gravel_rgba=(1.0 - 0.35 * w, 1.0 - 0.35 * w, 1.0 - 0.33 * w, 1.0),
        verge_texture_grass=SNOW_TEXTURE if snowy else "grass",
        verge_texture_gravel=SNOW_TEXTURE if snowy else "gravel",
    )


def appearance_of(scenario: Scenario, road: Road) -> Appearance:
    cond = scenario.conditions
    return Appearance(lighting_of(cond, road), surfaces_of(cond),
                      GRID_STEP_M if cond.headlights else None)
