"""The shipped LaneNet weights (detectors/weights/lanenet.pt, made by tools/train_lanenet.py on
simulated frames only): they load, find the ego lane on rendered frames, and run
deterministically, from one frame or a sequence."""

import numpy as np
import pytest

from lanekeep.cameras import CameraRig, RenderSettings
from lanekeep.detectors.base import poly_eval
from lanekeep.detectors.lanenet import LaneNetDetector
from lanekeep.ground_truth import lane_centre_at
from lanekeep.render import place_on_road
from lanekeep.scenario import load_scenario
from lanekeep.world import build


@pytest.fixture(scope="module")
def clear_frames():
    """Front frames of clear_straight and clear_curve at 1280x720, with the true lane centre's
    y at 10 m ahead and the camera."""
    out = []
    for name, s, offset in (("clear_straight", 40.0, 0.3), ("clear_curve", 90.0, -0.25)):
        scenario = load_scenario(name)
        world = build(scenario)
        x, y, yaw = place_on_road(world, s, offset)
        truth = float(lane_centre_at(world.road, x, y, yaw, scenario.road.ego_lane, [10.0])[0])
        with CameraRig(world.model, RenderSettings(1280, 720)) as rig:
            out.append((rig.render_rgb(world.data, "front"), rig.cameras["front"], truth))
    return out


def test_shipped_weights_find_the_ego_lane_within_10_cm_at_10_m(clear_frames):
    for frame, camera, truth in clear_frames:
        detector = LaneNetDetector(camera)
        estimate = detector.detect(frame)
        assert estimate.valid, estimate.reason
        centre = 0.5 * float(poly_eval(estimate.left, 10.0) + poly_eval(estimate.right, 10.0))
        assert abs(centre - truth) < 0.10, (centre, truth)


def test_shipped_weights_are_deterministic_and_alpha_in_unit_interval(clear_frames):
    frame, camera, _ = clear_frames[0]
    runs = []
    for _ in range(2):
        detector = LaneNetDetector(camera)
        decoded = [detector.infer(frame) for _ in range(3)]  # T = 1, then state carried
        runs.append([(d.proposals.points_px, d.proposals.scores) for d in decoded])
    for (pa, sa), (pb, sb) in zip(runs[0], runs[1], strict=True):
        assert np.array_equal(pa, pb) and np.array_equal(sa, sb)
    assert 0.0 <= detector.model.alpha.item() <= 1.0
    assert len(runs[0][0][0]) > 10  # a single frame (zero state) already gives proposals
