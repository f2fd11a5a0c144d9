"""Classical detectors (paper 001 models #1 and #2) against road ground truth on rendered frames.

Each scenario's 15 poses (lateral offsets x heading errors) are rendered once at 1280x720 and
shared by both detectors. Errors are measured at each estimate's own look-ahead x_m.
"""

import json
import math

import mujoco
import numpy as np
import pytest

import lanekeep  # noqa: F401 - MUJOCO_GL before mujoco
from detectors.base import LaneEstimate, poly_eval
from detectors.registry import make_detector
from detectors.tusimple import estimate_lanes, h_samples_for, record, score_frame
from lanekeep.cameras import CameraRig
from lanekeep.ground_truth import lane_truth

OFFSETS_M = (-0.8, -0.4, 0.0, 0.4, 0.8)
HEADINGS_DEG = (-3.0, 0.0, 3.0)
AT_S_M = {"clear_straight": 60.0, "clear_curve": 150.0}  # clear_curve: inside the R=150 m arc


def _render(world, s_m, cameras=("front",)):
    road, lane = world.road, world.scenario.road.ego_lane
    frames = []
    with CameraRig(world.model) as rig:
        for off in OFFSETS_M:
            for hd in HEADINGS_DEG:
                x, y = road.position(s_m, road.lane_center_r(lane) + off)
                yaw = float(road.heading_at(s_m)) + math.radians(hd)
                world.car.place(float(x), float(y), yaw, 0.0)
                mujoco.mj_forward(world.model, world.data)
                images = {c: rig.render_rgb(world.data, c).copy() for c in cameras}
                frames.append(((off, hd), (float(x), float(y), yaw), images))
        models = dict(rig.cameras)
    return frames, models


@pytest.fixture(scope="module")
def rendered(straight_world, curve_world):
    out = {}
    for world in (straight_world, curve_world):
        name = world.scenario.name
        out[name] = (world, *_render(world, AT_S_M[name]))
    return out


def _errors(world, frames, detector, camera="front", x_boundary=10.0, fit_range=(0.0, 30.0)):
    road, lane = world.road, world.scenario.road.ego_lane
    offset_err, boundary_err, invalid = [], [], []
    for key, (x, y, yaw), images in frames:
        detector.reset()
        est = detector.detect(images[camera])
        if not est.valid:
            invalid.append(key)
            continue
        truth = lane_truth(road, x, y, yaw, lane, lookahead_m=est.x_m, fit_range_m=fit_range)
        offset_err.append(abs(est.offset_m - truth.offset_m))
        for mine, true in ((est.left, truth.left), (est.right, truth.right)):
            if mine is not None:
                boundary_err.append(abs(poly_eval(mine, x_boundary) - poly_eval(true, x_boundary)))
    return np.array(offset_err), np.array(boundary_err), invalid


@pytest.mark.parametrize("scenario", ["clear_straight", "clear_curve"])
@pytest.mark.parametrize("name", ["hough", "sliding_window"])
def test_offsets_and_boundaries_match_ground_truth(rendered, scenario, name):
    world, frames, cameras = rendered[scenario]
    detector = make_detector(name, cameras["front"])
    offset_err, boundary_err, invalid = _errors(world, frames, detector)
    assert not invalid, f"{name} found no lane at {invalid}"
    assert np.median(offset_err) <= 0.10, offset_err
    assert offset_err.max() <= 0.25, offset_err
    assert boundary_err.max() <= 0.15, boundary_err
    assert len(boundary_err) >= len(frames)  # at least one boundary at 10 m in every frame


def test_sliding_window_tracks_from_its_previous_fit(rendered):
    world, frames, cameras = rendered["clear_curve"]
    detector = make_detector("sliding_window", cameras["front"])
    _, _, images = frames[7]  # centred, heading 0
    first = detector.detect(images["front"])
    second = detector.detect(images["front"])  # searches around the first fit
    assert first.valid and second.valid
    assert abs(first.offset_m - second.offset_m) < 0.03
    detector.reset()
    assert detector._previous == [None, None]


def test_sliding_window_on_the_rear_camera_reports_the_lane_behind(straight_world):
    frames, cameras = _render(straight_world, 60.0, cameras=("rear",))
    detector = make_detector("sliding_window", cameras["rear"])
    offset_err, boundary_err, invalid = _errors(
        straight_world, frames[::2], detector, camera="rear", x_boundary=-8.0,
        fit_range=(-16.0, 0.0))
    assert not invalid
    assert detector.detect(frames[0][2]["rear"]).x_m < -2.0  # behind the car
    assert np.median(offset_err) <= 0.10 and offset_err.max() <= 0.25
    assert boundary_err.max() <= 0.15


@pytest.mark.parametrize("name", ["hough", "sliding_window"])  # the shipped ones
def test_hard_frames_are_invalid_never_nan(rendered, name):
    camera = rendered["clear_straight"][2]["front"]
    detector = make_detector(name, camera)
    rng = np.random.default_rng(0)
    sky = np.zeros((720, 1280, 3), np.uint8)
    sky[:] = np.linspace([90, 140, 220], [170, 200, 240], 720)[:, None, :].astype(np.uint8)
    for frame in (np.zeros((720, 1280, 3), np.uint8), sky,
                  rng.integers(0, 256, (720, 1280, 3), dtype=np.uint8)):
        detector.reset()
        est = detector.detect(frame)
        assert not est.valid and est.reason
        assert math.isfinite(est.offset_m)
    with pytest.raises(ValueError, match="shape"):
        detector.detect(np.zeros((360, 640, 3), np.uint8))


def test_unknown_detector_names_the_known_ones(rendered):
    with pytest.raises(ValueError, match="hough, sliding_window"):
        make_detector("lanenet3000", rendered["clear_straight"][2]["front"])


def test_tusimple_output_round_trips_through_the_scorer(rendered):
    world, frames, cameras = rendered["clear_curve"]
    camera = cameras["front"]
    (_, (x, y, yaw), _) = frames[7]
    truth = lane_truth(world.road, x, y, yaw, world.scenario.road.ego_lane)
    est = LaneEstimate(valid=True, left=truth.left, right=truth.right, x_m=4.0)
    h_samples = h_samples_for(720)
    lanes = estimate_lanes(est, camera, h_samples, (4.0, 30.0))
    assert len(lanes) == 2 and all(sum(x >= 0 for x in lane) >= 5 for lane in lanes)
    line = json.loads(json.dumps(record("frame.png", lanes, h_samples, 3.0)))
    assert line["raw_file"] == "frame.png" and line["h_samples"] == h_samples
    gt = line["lanes"]
    assert score_frame(gt, gt, h_samples) == (1.0, [1.0, 1.0])
    shift = lambda lanes, dx: [[x + dx if x >= 0 else x for x in lane] for lane in lanes]  # noqa: E731
    assert score_frame(shift(gt, 15), gt, h_samples)[0] == 1.0  # inside 20 px / cos(angle)
    assert score_frame(shift(gt[:1], 60), gt[:1], h_samples)[0] == 0.0
    # One lane predicted out of two: half the frame.
    assert score_frame(gt[:1], gt, h_samples)[0] == pytest.approx(0.5)
    # The threshold widens with the lane's slant: 20 / cos(45 deg) = 28.3 px.
    ys = np.array(h_samples)
    slanted = [[int(600 - (v - 160)) for v in ys]]
    assert score_frame(shift(slanted, 25), slanted, h_samples)[0] == 1.0


def test_config_defaults_are_the_tuned_values():
    """`DetectorsConfig()` (and any key a user's TOML leaves out) is the shipped tuning."""
    from detectors.config import DetectorsConfig, load_config

    assert DetectorsConfig() == load_config()


def test_detectors_import_no_mujoco():
    """Perception runs on frames alone: the detectors and their camera model load without
    MuJoCo (a real-camera user need not have it)."""
    import subprocess
    import sys

    program = ("import sys\n"
               "import detectors.registry, detectors.hough, detectors.sliding_window\n"
               "import detectors.birds_eye, detectors.image_stage, detectors.boundaries\n"
               "import detectors.tusimple\n"
               "assert 'mujoco' not in sys.modules, 'mujoco was imported'\n"
               "print('ok')\n")
    result = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok"
