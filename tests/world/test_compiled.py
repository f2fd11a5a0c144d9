"""A scenario built again in the same process (lanekeep/world/compiled.py): the same world,
from a copy, without generating it again; what one world changes never reaches the next."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.world import build as build_module
from lanekeep.world.build import build
from lanekeep.world.compiled import COMPILED_WORLDS, Compiled, CompiledWorlds
from lanekeep.world.parts import WorldLayout

# Model arrays that differ between worlds and that an episode or a user may change.
ARRAYS = ("tex_data", "geom_rgba", "geom_pos", "geom_group", "mesh_vert", "light_pos",
          "light_diffuse", "cam_pos", "cam_quat", "cam_fovy")


@pytest.fixture
def compiles(monkeypatch):
    """How many times the world was generated (build_spec ran) during the test; the cache
    starts empty and is emptied again after."""
    calls = []
    original = build_module.build_spec

    def counted(*args, **kwargs):
        calls.append(args[0].name)
        return original(*args, **kwargs)

    monkeypatch.setattr(build_module, "build_spec", counted)
    COMPILED_WORLDS.clear()
    yield calls
    COMPILED_WORLDS.clear()


def _front(world) -> np.ndarray:
    with CameraRig(world.model, RenderSettings.of(world.scenario, 160, 90)) as rig:
        return rig.render_rgb(world.data, "front")


def test_a_second_build_is_a_copy_of_the_first_and_renders_the_same(compiles):
    scenario = load_scenario("night")  # street lamps: the episode moves lights in the model
    first = build(scenario)
    first_frame = _front(first)
    second = build(scenario)
    assert compiles == ["night"]  # generated once
    assert second.model is not first.model and second.conditions is not first.conditions
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(second.model, name), getattr(first.model, name),
                                      err_msg=name)
    np.testing.assert_array_equal(second.marking_boundary, first.marking_boundary)
    assert np.array_equal(_front(second), first_frame)
    with COMPILED_WORLDS.disabled():
        fresh = build(scenario)
    assert compiles == ["night", "night"]
    assert np.array_equal(_front(fresh), first_frame)


def test_what_one_world_changes_does_not_reach_the_next(compiles):
    scenario = load_scenario("clear_straight")
    first = build(scenario)
    before = {name: getattr(first.model, name).copy() for name in ARRAYS}
    shadows = len(first.conditions.shadow_polygons)
    for name in ARRAYS:
        getattr(first.model, name)[...] = 0
    first.conditions.shadow_polygons.clear()
    first.marking_boundary[:] = -1
    second = build(scenario)
    assert compiles == ["clear_straight"]
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(second.model, name), before[name], err_msg=name)
    assert len(second.conditions.shadow_polygons) == shadows
    assert (second.marking_boundary >= 0).any()


def test_another_seed_or_layout_is_another_world(compiles):
    scenario = load_scenario("clear_straight")
    a = build(scenario)
    b = build(dataclasses.replace(scenario, seed=scenario.seed + 1))
    c = build(scenario, WorldLayout(shoulder_m=2.0))
    assert len(compiles) == 3
    assert not np.array_equal(a.model.tex_data, b.model.tex_data)
    assert not np.array_equal(a.model.geom_pos, c.model.geom_pos)


def test_the_least_recently_used_world_goes_first():
    worlds = CompiledWorlds(slots=2)
    compiled = Compiled(build(load_scenario("clear_straight")).model, {}, None)
    for key in ("a", "b"):
        worlds.keep(key, compiled)
    assert worlds.take("a") is not None  # "a" is now the more recent
    worlds.keep("c", compiled)
    assert len(worlds) == 2 and worlds.take("b") is None
    assert worlds.take("a") is not None and worlds.take("c") is not None
    with worlds.disabled():
        assert worlds.take("a") is None
        worlds.keep("d", compiled)
    assert len(worlds) == 0  # what was kept before is forgotten, nothing was kept within
