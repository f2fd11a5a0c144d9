"""The shipped LaneNet weights (detectors/weights/lanenet.pt, made by tools/train_lanenet.py on
simulated frames only): they load, find the ego lane on rendered frames, and run
deterministically, from one frame or a sequence."""

import numpy as np
import pytest

from lanekeep.detectors.lanenet import LaneNetDetector, LaneNetSettings
from lanekeep.geometry.lane_poly import LanePoly
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring.truth import lane_centre_at
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build


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
        left, right = LanePoly.of(estimate.left), LanePoly.of(estimate.right)
        centre = 0.5 * float(left.y(10.0) + right.y(10.0))
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


def _sorted_points(points: np.ndarray) -> np.ndarray:
    return points[np.lexsort((points[:, 1], points[:, 0]))]


def test_mirror_pass_makes_the_fit_mirror_symmetric(clear_frames):
    """With `mirror` (the default) a frame and its mirror image give mirrored proposals and
    opposite offsets: the fit no longer inherits the network's own left-right lean."""
    frame, camera, _ = clear_frames[0]  # a centred camera: the image mirror is the world's
    width = frame.shape[1]
    detectors = [LaneNetDetector(camera), LaneNetDetector(camera)]
    direct = detectors[0].detect(frame)
    mirrored = detectors[1].detect(np.ascontiguousarray(frame[:, ::-1]))
    assert direct.valid and mirrored.valid
    points = [d.last.proposals.points_px.copy() for d in detectors]
    points[1][:, 0] = width - 1 - points[1][:, 0]
    assert len(points[0]) == len(points[1]) > 10
    np.testing.assert_allclose(_sorted_points(points[0]), _sorted_points(points[1]), atol=1e-3)
    assert abs(direct.offset_m + mirrored.offset_m) < 1e-6  # the fit is mirror-symmetric too
    # the network's own proposals (AP's candidates) are the frame's pass only
    single = LaneNetDetector(camera, settings=LaneNetSettings(mirror=False))
    single.detect(frame)
    assert np.array_equal(single.last.candidates.points_px, detectors[0].last.candidates.points_px)
    assert len(single.last.proposals.points_px) < len(points[0])
