"""The `[camera] preset = "dashcam"` front camera (lanekeep/world/camera_mount.py): its pose
against the analytic values, its horizon in a render, the rear camera left as the car's, and the
detectors finding the lane through it."""

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

import lanekeep  # noqa: F401 - MUJOCO_GL before mujoco
from lanekeep.core.config_io import InvalidValue
from lanekeep.detectors.registry import make_detector
from lanekeep.mjcf import SCENE_XML
from lanekeep.scenario.schema import CameraConfig, ScenarioError, load_scenario
from lanekeep.scoring.truth import lane_truth
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build
from lanekeep.world.camera_mount import apply_camera_mount, camera_from_model

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "dashcam_clear_straight.toml"


def _mounted(camera: CameraConfig) -> mujoco.MjModel:
    model = mujoco.MjModel.from_xml_path(str(SCENE_XML))
    apply_camera_mount(model, camera)
    return model


def test_dashcam_front_is_60_deg_at_1_4_m_with_the_horizon_on_row_300():
    front = camera_from_model(_mounted(CameraConfig(preset="dashcam")), "front")
    assert front.fovx_deg == pytest.approx(60.0, abs=1e-6)
    assert front.position_m[2] == pytest.approx(1.4)
    assert front.horizon_row() == pytest.approx(300.0, abs=1e-6)
    # horizon = cy + f tan(pitch): row 300 lies above the centre, so the camera looks down.
    f = 640.0 / math.tan(math.radians(30.0))
    assert math.degrees(front.pitch_rad) == pytest.approx(
        -math.degrees(math.atan((359.5 - 300.0) / f)), abs=1e-9)
    assert front.rotation[1, 0] == pytest.approx(-1.0)  # image right = the car's right


def test_dashcam_leaves_the_rear_camera_as_the_car_has_it():
    paper = camera_from_model(_mounted(CameraConfig()), "rear")
    dash = camera_from_model(_mounted(CameraConfig(preset="dashcam")), "rear")
    np.testing.assert_array_equal(dash.position_m, paper.position_m)
    np.testing.assert_array_equal(dash.rotation, paper.rotation)
    assert dash.fx == paper.fx


def test_mounting_keys_move_the_preset():
    front = camera_from_model(_mounted(CameraConfig(
        preset="dashcam", pitch_offset_deg=2.0, mount_height_m=1.2)), "front")
    base = camera_from_model(_mounted(CameraConfig(preset="dashcam")), "front")
    assert front.position_m[2] == pytest.approx(1.2)
    assert math.degrees(front.pitch_rad - base.pitch_rad) == pytest.approx(2.0, abs=1e-6)


def test_an_unknown_preset_is_named(tmp_path):
    with pytest.raises(InvalidValue, match="preset"):
        CameraConfig(preset="fisheye")
    bad = tmp_path / "bad.toml"
    bad.write_text(EXAMPLE.read_text().replace('preset = "dashcam"', 'preset = "gopro"'))
    with pytest.raises(ScenarioError, match="preset"):
        load_scenario(bad)


def test_rendered_horizon_is_the_analytic_row():
    """The first ground pixel down the centre column of the flat test scene: its floor ends
    500 m away (0.16 deg below the true horizon, 1.6 px at 360 rows), so the sky turns to
    ground at the projection of that far edge, itself next to the analytic horizon."""
    model = _mounted(CameraConfig(preset="dashcam"))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    with CameraRig(model, RenderSettings(640, 360)) as rig:
        seg = rig.render_segmentation(data, "front")
        cam = rig.cameras["front"]
    # row 300 of 720 at half size, pixel centres at row + 0.5
    assert cam.horizon_row() == pytest.approx((300.0 + 0.5) * 360 / 720 - 0.5, abs=1e-6)
    floor_end_m = float(model.geom("floor").size[0] - data.xpos[model.body("car").id][0])
    (edge,), _ = cam.project(np.array([[floor_end_m, 0.0, 0.0]]))
    assert 0.0 < edge[1] - cam.horizon_row() < 2.0
    first_ground = np.flatnonzero(seg[:, cam.width // 2] >= 0)[0]
    assert first_ground == math.ceil(edge[1])  # the first pixel centre below the floor's edge


@pytest.fixture(scope="module")
def dashcam_world():
    return build(load_scenario(EXAMPLE))


@pytest.mark.parametrize("name", ["hough", "sliding_window"])
def test_detectors_find_the_lane_through_the_dashcam(dashcam_world, name):
    world = dashcam_world
    lane = world.scenario.road.ego_lane
    with CameraRig(world.model, RenderSettings(640, 360)) as rig:
        detector = make_detector(name, rig.cameras["front"])
        for offset in (-0.4, 0.0, 0.4):
            x, y, yaw = place_on_road(world, 60.0, offset)
            mujoco.mj_forward(world.model, world.data)
            detector.reset()
            est = detector.detect(rig.render_rgb(world.data, "front"))
            assert est.valid, (offset, est.reason)
            truth = lane_truth(world.road, x, y, yaw, lane, lookahead_m=est.x_m)
            assert abs(est.offset_m - truth.offset_m) <= 0.10, (offset, est.offset_m)
