"""Fog scatters the sun (lanekeep/world_lighting.direct_sun_share): the direct light and the
cast shadows fade with the fog, the scattered light comes down as diffuse skylight."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from lanekeep.scenario.schema import Conditions, load_scenario
from lanekeep.world.appearance import lighting_of
from lanekeep.world.build import build
from lanekeep.world.lighting import direct_sun_share
from lanekeep.world.shade import shade_transmission


def test_the_direct_share_falls_with_fog_and_with_a_low_sun():
    shares = [direct_sun_share(Conditions(fog=f)) for f in (0.0, 0.1, 0.4, 0.75, 1.0)]
    assert shares[0] == 1.0 and all(a > b for a, b in zip(shares[:-1], shares[1:], strict=True))
    assert shares[-1] < 0.01  # fog 1 (25 m visibility): no sun, no shadows
    high, low = (direct_sun_share(Conditions(fog=0.2, sun_elevation_deg=e)) for e in (70, 15))
    assert low < high


def test_fog_turns_sunlight_into_skylight():
    road = load_scenario("clear_straight").build_road()
    clear, foggy = lighting_of(Conditions(), road), lighting_of(Conditions(fog=0.75), road)
    assert np.mean(foggy.sun_diffuse) < 0.05 * np.mean(clear.sun_diffuse)
    elevation = np.radians(Conditions().sun_elevation_deg)
    ground_clear = np.mean(clear.sun_diffuse) * np.sin(elevation) + np.mean(clear.sun_ambient)
    ground_foggy = np.mean(foggy.sun_diffuse) * np.sin(elevation) + np.mean(foggy.sun_ambient)
    assert np.mean(foggy.sun_ambient) > 2.0 * np.mean(clear.sun_ambient)
    assert 0.5 * ground_clear < ground_foggy < ground_clear  # some is lost, none is made
    assert foggy.sun_specular < clear.sun_specular


@pytest.mark.parametrize("fog", [0.0, 0.3])
def test_props_shadows_fade_with_the_sun(fog):
    scenario = load_scenario("clear_straight")
    scenario = dataclasses.replace(scenario, conditions=dataclasses.replace(
        scenario.conditions, fog=fog))
    model = build(scenario).model
    alpha = float(model.mat_rgba[model.mat("props_shadow_shade").id][3])
    kept = shade_transmission(scenario.roadside.shadow_darkness, scenario.conditions)
    assert (1.0 - alpha) ** 2 == pytest.approx(kept, abs=1e-6)  # drawn twice
    clear = shade_transmission(scenario.roadside.shadow_darkness,
                               dataclasses.replace(scenario.conditions, fog=0.0))
    assert kept > clear if fog > 0.0 else kept == clear  # fog pales the shade
