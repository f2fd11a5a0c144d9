"""Model health and vehicle physics: every scene compiles and steps cleanly; the car turns and
holds speed as the kinematics say it should."""

import math
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest

from lanekeep.control.pid import SpeedController
from lanekeep.mjcf import CAR_XML, SCENE_XML
from lanekeep.scenario.schema import load_scenario, shipped_scenarios
from lanekeep.world.build import build, physics_steps_per_control
from lanekeep.world.vehicle import Car, kinematic_turn_radius


def _step_seconds(model, data, seconds, each_step=None):
    for _ in range(int(round(seconds / model.opt.timestep))):
        if each_step:
            each_step()
        mujoco.mj_step(model, data)


def _assert_no_warnings(data):
    counts = {mujoco.mjtWarning(i).name: w.number for i, w in enumerate(data.warning) if w.number}
    assert not counts, f"MuJoCo warnings: {counts}"


@pytest.mark.parametrize("name", shipped_scenarios())
def test_every_shipped_scenario_compiles_and_steps_2s_without_warnings(name):
    world = build(load_scenario(name))
    world.car.apply(0.0, 0.3)
    _step_seconds(world.model, world.data, 2.0)
    _assert_no_warnings(world.data)
    assert np.all(np.isfinite(world.data.qpos))
    # Still on the ground, upright.
    assert abs(world.data.body("car").xpos[2]) < 0.05
    assert world.car.rotation()[2, 2] > 0.99


def test_flat_scene_compiles_and_steps_2s_without_warnings():
    model = mujoco.MjModel.from_xml_path(str(SCENE_XML))
    data = mujoco.MjData(model)
    _step_seconds(model, data, 2.0)
    _assert_no_warnings(data)
    # The suspension preload keeps the cameras at their nominal 1.5 m.
    assert data.cam("front").xpos[2] == pytest.approx(1.5, abs=0.01)


def test_every_car_element_is_named():
    root = ET.parse(CAR_XML).getroot()
    sections = [root.find(s) for s in ("worldbody", "actuator", "sensor")]
    elements = [
        el for section in sections for el in section.iter()
        if el is not section and el.tag != "inertial"  # inertial cannot carry a name
    ]
    assert len(elements) > 40
    unnamed = [el.tag for el in elements if not el.get("name")]
    assert unnamed == []


def test_car_matches_the_suv_spec():
    model = mujoco.MjModel.from_xml_path(str(SCENE_XML))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    car = model.body("car").id
    assert 1900 <= model.body_subtreemass[car] <= 2150
    front = data.body("front_left_wheel").xpos
    rear = data.body("rear_left_wheel").xpos
    assert front[0] - rear[0] == pytest.approx(2.8, abs=1e-6)


@pytest.mark.parametrize("steer", [0.3, -0.5])
def test_turn_radius_at_5mps_matches_kinematic_within_5_percent(steer):
    model = mujoco.MjModel.from_xml_path(str(SCENE_XML))
    data = mujoco.MjData(model)
    car = Car(model, data)
    car.place(0.0, 0.0, 0.0, 5.0)
    speed = SpeedController(5.0, model.opt.timestep)
    path = []

    def control():
        car.apply(steer, speed(car.speed_mps()))
        x, y, yaw = car.pose()
        half_wheelbase = car.geometry.wheelbase_m / 2
        path.append((x - half_wheelbase * math.cos(yaw), y - half_wheelbase * math.sin(yaw)))

    _step_seconds(model, data, 30.0, control)
    pts = np.array(path[len(path) // 3 :])  # steady state: rear-axle centre on a circle
    a = np.c_[2 * pts, np.ones(len(pts))]
    cx, cy, c = np.linalg.lstsq(a, (pts**2).sum(1), rcond=None)[0]
    radius = math.sqrt(c + cx**2 + cy**2)
    expected = abs(kinematic_turn_radius(steer * car.geometry.max_steer_rad, car.geometry))
    assert car.speed_mps() == pytest.approx(5.0, abs=0.05)
    assert radius == pytest.approx(expected, rel=0.05)
    _assert_no_warnings(data)


def test_speed_controller_holds_15mps_on_clear_straight(straight_world):
    world = straight_world
    world.reset()
    x, y, yaw = world.scenario.start_pose(world.road)
    world.car.place(x, y, yaw, 0.0)  # from standstill
    speed = SpeedController(15.0, world.scenario.control_period_s)
    lane_r = world.road.lane_center_r(world.scenario.road.ego_lane)
    speeds = []
    for _ in range(200):  # 20 s
        x, y, yaw = world.car.pose()
        s, r = world.road.local_coordinates(np.array([x, y]))
        heading_error = yaw - float(world.road.heading_at(s))
        steer = -0.1 * (r - lane_r) - 1.0 * heading_error  # ground-truth lane hold
        world.car.apply(steer, speed(world.car.speed_mps()))
        _step_seconds(world.model, world.data, world.scenario.control_period_s)
        speeds.append(world.car.speed_mps())
    settled = np.array(speeds[100:])  # last 10 s
    assert np.all(np.abs(settled - 15.0) <= 0.2), (settled.min(), settled.max())
    assert physics_steps_per_control(world) == 20


@pytest.mark.parametrize("name", ["clear_curve", "night"])
def test_the_cameras_ground_is_drawn_last_and_the_contact_plane_is_unseen(name):
    """The cameras' ground is the world's last geom (the depth test skips what the road covers)
    and the contact plane keeps geom 0 in a group no camera draws; the rendering grid is
    coarse under directional light and fine where the car's headlamps light the grass."""
    from lanekeep.world.build import GROUND_GRID_LIT_M, GROUND_GRID_M
    from lanekeep.world.groups import GROUP_UNSEEN

    world = build(load_scenario(name))
    model = world.model
    contact, visual = model.geom("ground"), model.geom("ground_visual")
    world_geoms = [i for i in range(model.ngeom) if model.geom_bodyid[i] == 0]
    assert contact.id == 0 and visual.id == world_geoms[-1]
    assert model.geom_group[contact.id] == GROUP_UNSEEN
    assert model.geom_contype[visual.id] == 0 and model.geom_conaffinity[visual.id] == 0
    np.testing.assert_allclose(model.geom_size[visual.id][:2], model.geom_size[contact.id][:2])
    spot = any(t == mujoco.mjtLightType.mjLIGHT_SPOT for t in model.light_type)
    assert spot == (name == "night")
    assert model.geom_size[visual.id][2] == (GROUND_GRID_LIT_M if spot else GROUND_GRID_M)
