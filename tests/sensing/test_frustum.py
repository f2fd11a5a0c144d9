"""Frustum culling (lanekeep/sensing/frustum.py): a geom is left out only when no part of it
can be seen, so a culled render is the unculled one pixel for pixel, and it does leave
geoms out."""

import dataclasses

import mujoco
import numpy as np
import pytest

from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.frustum import FrustumCuller
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build

# A camera at the origin looking along +x (MuJoCo cameras look along their -z: xyaxes puts
# the camera's x on -y and its y on +z), 60 deg vertical field, 2:1 image.
_BOXES = """
<mujoco>
  <worldbody>
    <camera name="eye" pos="0 0 0" xyaxes="0 -1 0 0 0 1" fovy="60"/>
    <geom name="ahead" type="box" pos="10 0 0" size="0.5 0.5 0.5"/>
    <geom name="behind" type="box" pos="-10 0 0" size="0.5 0.5 0.5"/>
    <geom name="left_out" type="box" pos="10 30 0" size="0.5 0.5 0.5"/>
    <geom name="straddles" type="box" pos="10 0 0" size="0.5 40 0.5"/>
    <geom name="above_out" type="box" pos="10 0 12" size="0.5 0.5 0.5"/>
    <geom name="long_behind" type="box" pos="-20 0 0" size="15 0.5 0.5" />
    <geom name="turned_in" type="box" pos="-3 3 0" size="8 0.2 0.2" euler="0 0 -45"/>
    <geom name="floor" type="plane" size="0 0 1"/>
  </worldbody>
</mujoco>
"""


def test_boxes_wholly_outside_a_plane_of_the_view_are_culled_and_no_other():
    model = mujoco.MjModel.from_xml_string(_BOXES)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    culled = {model.geom(i).name for i in FrustumCuller(model, 200, 100).outside(data, "eye")}
    # Half-widths: 30 deg up/down, atan(2 tan 30 deg) = 49 deg left/right.
    assert culled == {"behind", "left_out", "above_out", "long_behind"}


def test_a_box_is_culled_by_its_rotated_extent_not_its_centre():
    model = mujoco.MjModel.from_xml_string(_BOXES)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    culler = FrustumCuller(model, 200, 100)
    turned = model.geom("turned_in").id  # centred behind the camera, one end at (2.7, -2.7)
    assert turned not in culler.outside(data, "eye")
    model.geom_pos[turned] = [-12.0, 3.0, 0.0]  # the same bar moved back: now wholly behind
    assert turned in FrustumCuller(model, 200, 100).outside(data, "eye")


@pytest.mark.parametrize("name", ["clear_curve", "case1_building_shadows"])
def test_a_culled_render_is_the_unculled_one_pixel_for_pixel(name):
    scenario = load_scenario(name)
    world = build(scenario)
    settings = RenderSettings.of(scenario, 320, 180)
    with CameraRig(world.model, settings) as culled, \
            CameraRig(world.model, dataclasses.replace(settings, cull=False)) as whole:
        left_out = 0
        for ahead in (5.0, 0.5 * (world.road.length_m - scenario.start.s_m)):
            place_on_road(world, scenario.start.s_m + ahead)
            mujoco.mj_forward(world.model, world.data)
            for camera in ("front", "rear"):
                left_out += len(culled._culler.outside(world.data, camera))
                np.testing.assert_array_equal(culled.render_rgb(world.data, camera),
                                              whole.render_rgb(world.data, camera))
                np.testing.assert_array_equal(culled.render_segmentation(world.data, camera),
                                              whole.render_segmentation(world.data, camera))
        groups = world.model.geom_group.copy()
    assert left_out > 0  # something was culled, so the equality says something
    np.testing.assert_array_equal(world.model.geom_group, groups)  # the groups are put back


def test_renders_with_shadow_maps_do_not_cull():
    world = build(load_scenario("clear_straight"))
    with CameraRig(world.model, RenderSettings(160, 90, shadows=True)) as rig:
        assert rig._culler is None
