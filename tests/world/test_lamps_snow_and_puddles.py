"""Issue #59's broken world details, fixed: the tail lamps light the road behind only faintly
(lanekeep/world/lighting.py), snow lies on the crowns and the rails in a snowfall
(lanekeep/world/prop_snow.py), puddles are dark water, not a self-lit grey overlay."""

import mujoco
import numpy as np

from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build, build_spec
from lanekeep.world.prop_snow import SNOW_MATERIAL
from lanekeep.world.props import prop_kind

W, H = 320, 180


def _ground(camera, x_m, y_m=(-1.0, 1.0)) -> np.ndarray:
    v, u = np.mgrid[0:camera.height, 0:camera.width]
    xy, valid = camera.pixels_to_ground(np.stack([u, v], -1).astype(float))
    return (valid & (xy[..., 0] >= x_m[0]) & (xy[..., 0] <= x_m[1])
            & (xy[..., 1] >= y_m[0]) & (xy[..., 1] <= y_m[1]))


def test_tail_lamps_light_the_road_behind_a_tenth_as_much_as_the_low_beams_ahead():
    """Before: a red pool over 12% of the night rear frame, half as bright as the headlit
    road (the bare render's red excess behind: 0.5 of the headlit road's luma)."""
    scenario = load_scenario("night")
    world = build(scenario)
    place_on_road(world, scenario.start.s_m)
    with CameraRig(world.model, RenderSettings(W, H, show_hood=False)) as rig:
        rear = rig.render_rgb(world.data, "rear").astype(float)
        front = rig.render_rgb(world.data, "front").astype(float)
        near = _ground(rig.cameras["rear"], (-5.5, -2.5))
        lit = _ground(rig.cameras["front"], (10.0, 25.0))
    excess = rear[..., 0] - rear[..., 1:].max(-1)
    headlit = (front @ [0.299, 0.587, 0.114])[lit].mean()
    assert excess[near].mean() < 0.2 * headlit
    assert np.mean(excess > 20.0) < 0.01  # no red pool


def test_snow_lies_on_the_tree_crowns_and_the_guard_rails():
    snowy = load_scenario("snow")
    spec, _, _ = build_spec(snowy, snowy.build_road())
    leaves = np.frombuffer(spec.texture("prop_foliage").data, np.uint8).reshape(-1, 3)
    white = (leaves.min(-1) > 200).mean()
    assert white > 0.3  # the crowns carry snow (before: none)
    for name in ("prop_foliage_0", "prop_foliage_2", "prop_conifer"):
        assert min(spec.material(name).rgba[:3]) > 0.8  # the snow on them stays white
    snow = np.concatenate([np.asarray(m.uservert, float).reshape(-1, 3) for m in spec.meshes
                           if prop_kind(m.name) == "props_snow"])
    assert 0.74 < np.percentile(snow[:, 2], 90) < 0.85  # ridges on the rails' tops (0.75 m)
    assert spec.material(SNOW_MATERIAL) is not None
    plain = load_scenario("clear_straight")
    spec, _, _ = build_spec(plain, plain.build_road())
    assert not [m for m in spec.meshes if prop_kind(m.name) == "props_snow"]
    assert spec.material(SNOW_MATERIAL) is None


def test_puddles_are_dark_water_not_a_self_lit_overlay():
    scenario = load_scenario("heavy_rain")
    world = build(scenario)
    material = world.model.material("cond_puddle")
    assert float(material.emission[0]) == 0.0
    assert float(np.mean(material.rgba[:3])) < 0.1 and float(material.rgba[3]) < 0.3
    gid = mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_GEOM, "cond_puddles")
    assert gid >= 0
