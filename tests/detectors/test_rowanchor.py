"""The row-anchor rear observer (#58): network contract, weights files, targets <-> decoding, an
overfit on synthetic rear frames proving model, targets, loss and the shared ground fit work
together, and the shipped weights on one rendered rear frame. No training data needed."""

import math

import cv2
import numpy as np
import pytest
import torch

from lanekeep.detectors.lanenet_targets import slots_from_lateral
from lanekeep.detectors.network_io import one_torch_thread
from lanekeep.detectors.registry import (
    check_detectors_weights,
    check_weights,
    known_detectors,
    make_detector,
    takes_weights,
)
from lanekeep.detectors.rowanchor import (
    DEFAULT_WEIGHTS,
    RowAnchorDetector,
    RowAnchorSettings,
    WeightsError,
    load_weights,
    save_weights,
)
from lanekeep.detectors.rowanchor_model import (
    RowAnchorConfig,
    RowAnchorNet,
    anchor_rows,
    bin_to_x,
    column_spread,
    decode,
    mirror_targets,
    rowanchor_loss,
    targets,
)
from lanekeep.geometry.camera_model import CameraModel

W, H = 1280, 720
SMALL = RowAnchorConfig(width=160, height=176, channels=(8, 16, 16, 16))
ROWS = np.arange(0, H, 5, dtype=float)  # the dataset's label rows


def _rear_camera() -> CameraModel:
    """The paper's rear camera: 150 deg wide, 1.5 m high, 20 deg down, 2 m behind."""
    f = (W / 2.0) / math.tan(math.radians(75.0))
    K = np.array([[f, 0, (W - 1) / 2.0], [0, f, (H - 1) / 2.0], [0, 0, 1]])  # noqa: N806
    return CameraModel.from_mounting("rear", K, W, H, 1.5, math.radians(-20.0), -2.0,
                                     yaw_rad=math.pi)


def _row_labels(camera, offset_m, curvature, lanes_y=(1.85, -1.85, 5.55, -5.55)):
    """xs (boundaries, rows) at ROWS and the camera's slots of boundaries y = c0 + k x^2."""
    x = -np.linspace(2.2, 60.0, 600)
    lateral = np.array(lanes_y) - offset_m
    slots = slots_from_lateral(-lateral)  # a rear camera's left is the vehicle's right
    xs = np.full((len(lanes_y), len(ROWS)), np.nan)
    for b, y0 in enumerate(lanes_y):
        uv, ok = camera.project_ground(np.stack([x, y0 - offset_m + curvature * x * x], -1))
        uv = uv[ok]
        uv = uv[np.argsort(uv[:, 1])]
        xb = np.interp(ROWS, uv[:, 1], uv[:, 0], left=np.nan, right=np.nan)
        xb[(xb < 0) | (xb > W - 1)] = np.nan
        xs[b] = xb
    return xs, slots


def _synthetic_frame(camera, rng, offset_m, curvature):
    """Grey road, painted ego boundaries (one dashed) and the next ones, sky above the
    horizon, a few blotches. Returns the frame, xs and slots."""
    img = np.full((H, W, 3), 75, np.uint8)
    horizon = int(max(camera.horizon_row(), 0))
    img[:horizon] = (150, 170, 200)
    img = np.clip(img.astype(int) + rng.integers(-10, 11, img.shape), 0, 255).astype(np.uint8)
    x = -np.linspace(2.2, 60.0, 400)
    for y0, dashed in ((1.85, True), (-1.85, False), (5.55, False), (-5.55, False)):
        for x0 in np.arange(2.2, 60.0, 9.0 if dashed else 60.0):
            seg = x[(-x >= x0) & (-x <= x0 + (3.0 if dashed else 60.0))]
            edge = [np.stack([seg, y0 - offset_m + curvature * seg ** 2 + s], -1)
                    for s in (0.075, -0.075)]
            uv = np.concatenate([camera.project_ground(edge[0])[0],
                                 camera.project_ground(edge[1])[0][::-1]])
            cv2.fillPoly(img, [np.round(uv * 4).astype(np.int32)], (235, 235, 225), shift=2)
    for _ in range(5):
        c = (int(rng.uniform(0, W)), int(rng.uniform(horizon + 10, H)))
        cv2.circle(img, c, int(rng.uniform(5, 25)), (105, 105, 105), -1)
    xs, slots = _row_labels(camera, offset_m, curvature)
    return img, xs, slots


def test_output_shape_parameters_and_weights_file_size(tmp_path):
    model = RowAnchorNet(seed=0).eval()
    cfg = model.config
    frames = torch.zeros((2, 3, cfg.height, cfg.width), dtype=torch.uint8)
    with torch.no_grad():
        out = model(frames)
    assert out.shape == (2, cfg.lanes, cfg.anchors, cfg.bins + 1) == (2, 4, 22, 81)
    assert sum(p.numel() for p in model.parameters()) < 150_000
    save_weights(model, tmp_path / "w.pt")
    assert (tmp_path / "w.pt").stat().st_size < 1_000_000
    again = load_weights(tmp_path / "w.pt")
    with torch.no_grad():  # float16 storage: outputs agree to its rounding
        assert torch.allclose(again(frames), out, atol=0.05)


def test_targets_decode_back_and_mirror():
    camera = _rear_camera()
    xs, slots = _row_labels(camera, 0.3, 5e-4)
    cls, pos = targets(xs, ROWS, slots, W, H, SMALL)
    assert cls.shape == pos.shape == (SMALL.lanes, SMALL.anchors)
    present = cls < SMALL.bins
    assert present[:2].sum() >= 8  # both ego boundaries over several anchors
    logits = np.full(cls.shape + (SMALL.bins + 1,), -10.0)
    i, j = np.nonzero(present)
    logits[i, j, cls[i, j]] = 10.0
    logits[~present, SMALL.bins] = 10.0
    got, presence = decode(torch.tensor(logits))
    assert np.array_equal(presence > 0.5, present)
    assert np.all(np.abs(got[present] - pos[present]) <= 0.5 + 1e-6)  # the bin's centre
    x_back = bin_to_x(pos[present], W, SMALL.bins)
    rows = anchor_rows(H, SMALL.anchors)
    x_ref = np.array([np.interp(rows[a], ROWS, xs[list(slots).index(s)])
                      for s, a in zip(i, j, strict=True)])
    np.testing.assert_allclose(x_back, x_ref, atol=1e-3)
    # the mirrored frame's targets: lanes swapped, x mirrored
    mcls, mpos = mirror_targets(cls, pos, SMALL.bins)
    mx = bin_to_x(mpos[1], W, SMALL.bins)
    ok = np.isfinite(mx)
    np.testing.assert_allclose(mx[ok], W - 1 - bin_to_x(pos[0], W, SMALL.bins)[ok], atol=1e-3)
    assert np.array_equal(mcls[0] < SMALL.bins, cls[1] < SMALL.bins)


def test_overfit_synthetic_rear_frames_end_to_end(tmp_path):
    """A small net trained on four synthetic rear frames finds their lines again, and the
    detector turns them into the ego lane's offset at its look-ahead (4 m behind)."""
    torch.manual_seed(0)
    camera = _rear_camera()
    rng = np.random.default_rng(3)
    poses = [(-0.4, 0.0), (0.0, 1e-3), (0.35, -1e-3), (0.15, 0.0)]
    samples = [_synthetic_frame(camera, rng, o, c) for o, c in poses]
    small = [cv2.resize(f, (SMALL.width, SMALL.height), interpolation=cv2.INTER_AREA)
             for f, _, _ in samples]
    x = torch.from_numpy(np.stack(small).transpose(0, 3, 1, 2).copy())
    tg = [targets(xs, ROWS, slots, W, H, SMALL) for _, xs, slots in samples]
    cls = torch.from_numpy(np.stack([t[0] for t in tg]))
    pos = torch.from_numpy(np.stack([t[1] for t in tg]))
    model = RowAnchorNet(SMALL, seed=0)
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, 1e-2, total_steps=200)
    # One torch thread, whatever the test worker's count: the sums' order, and so this small
    # net's end point, depends on it (at two threads one offset ended 10.02 cm off, 2026-11-29).
    with one_torch_thread():
        for _ in range(200):  # ~4 s of one CPU core
            opt.zero_grad()
            loss, parts = rowanchor_loss(model(x), cls, pos)
            loss.backward()
            opt.step()
            sched.step()
    model.eval()
    with torch.no_grad():
        got, presence = decode(model(x))
    present = cls.numpy() < SMALL.bins
    assert np.mean((presence > 0.5) == present) > 0.97, parts
    err_px = np.abs(bin_to_x(got, W, SMALL.bins) - bin_to_x(pos.numpy(), W, SMALL.bins))
    assert np.median(err_px[present]) < 8.0, parts
    save_weights(model, tmp_path / "overfit.pt", half=False)
    detector = RowAnchorDetector(camera, weights=tmp_path / "overfit.pt")
    assert detector.x_ref == pytest.approx(-4.0)
    # 10 cm: this small net's bins are 32 px wide at 1280 (its points ~5 px off, median); a
    # side or sign mistake (the rear camera's left is the car's right) would be 0.7 m off
    for (frame, _, _), (offset_m, curvature) in zip(samples, poses, strict=True):
        est = detector.detect(frame)
        expected = offset_m - curvature * est.x_m ** 2
        assert est.valid and abs(est.offset_m - expected) < 0.10, (est, expected)


def test_hard_frames_give_invalid_estimates_not_errors(tmp_path):
    save_weights(RowAnchorNet(SMALL, seed=1), tmp_path / "w.pt")
    detector = RowAnchorDetector(_rear_camera(), weights=tmp_path / "w.pt")
    rng = np.random.default_rng(0)
    for frame in (np.zeros((H, W, 3), np.uint8), rng.integers(0, 256, (H, W, 3), np.uint8),
                  np.zeros((8, 8, 3), np.uint8), np.zeros((H, W), np.uint8)):
        est = detector.detect(frame)
        assert not est.valid and est.reason and est.x_m == detector.x_ref


def test_registered_lazily_with_weights_and_bad_files_named(tmp_path):
    assert "rowanchor" in known_detectors() and takes_weights("rowanchor")
    missing = tmp_path / "nope.pt"
    with pytest.raises(WeightsError, match="nope.pt: no such weights file"):
        RowAnchorDetector(_rear_camera(), weights=missing)
    with pytest.raises(ValueError, match="nope.pt: no such weights file"):
        check_weights("rowanchor", weights=str(missing))
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not a torch file")
    with pytest.raises(WeightsError, match="bad.pt: not a torch weights file"):
        load_weights(bad)
    other = tmp_path / "other.pt"
    torch.save({"format": "lanekeep-lanenet/1"}, str(other))
    with pytest.raises(WeightsError, match="not a row-anchor weights file"):
        load_weights(other)
    save_weights(RowAnchorNet(SMALL, seed=0), tmp_path / "ok.pt")
    detector = make_detector("rowanchor", _rear_camera(), weights=str(tmp_path / "ok.pt"))
    assert isinstance(detector, RowAnchorDetector) and DEFAULT_WEIGHTS.endswith("rowanchor.pt")
    # a file given where no named detector learns: any learned detector's file is accepted
    assert check_detectors_weights(["hough"], None, str(tmp_path / "ok.pt")) == [
        str(tmp_path / "ok.pt")]
    with pytest.raises(ValueError, match="bad.pt"):
        check_detectors_weights(["hough"], None, str(bad))


def test_a_scoped_weights_file_reaches_only_the_detectors_of_its_format(tmp_path):
    """`--weights W` (the `detector_weights` scope) with LaneNet in front and the row-anchor
    observer behind: W is LaneNet's, so LaneNet loads it and the observer keeps its own file
    (until 2026-11-29 W went to both, and the observer stopped the run). A file that fits none
    of the loop's learned detectors is still refused, naming what it is not."""
    from importlib import resources

    from lanekeep.detectors.lanenet import save_weights as save_lanenet
    from lanekeep.detectors.lanenet_model import LaneNet, LaneNetConfig
    from lanekeep.detectors.registry import detector_weights, weights_fit

    lanenet_file = str(tmp_path / "lanenet.pt")
    save_lanenet(LaneNet(LaneNetConfig()).eval(), lanenet_file)
    ours = str(resources.files("lanekeep.detectors").joinpath(DEFAULT_WEIGHTS))
    assert weights_fit("lanenet", lanenet_file) and not weights_fit("rowanchor", lanenet_file)
    assert check_detectors_weights(["lanenet", "rowanchor"], None, lanenet_file) == [
        lanenet_file, ours]
    with detector_weights(lanenet_file):
        assert check_weights("rowanchor") == ours
        make_detector("rowanchor", _rear_camera())  # its own file, not LaneNet's
    rowanchor_file = tmp_path / "ra.pt"
    save_weights(RowAnchorNet(SMALL, seed=0), rowanchor_file)
    with pytest.raises(ValueError, match="ra.pt: not a LaneNet weights file"):
        check_detectors_weights(["lanenet"], None, str(rowanchor_file))
    with pytest.raises(WeightsError, match="not a row-anchor weights file"):  # named, not routed
        make_detector("rowanchor", _rear_camera(), weights=lanenet_file)


@pytest.fixture(scope="module")
def rear_frame():
    """The rear camera of clear_straight at 640x360 (a quarter of the loop's pixels; the
    detector's camera model follows), the car 0.3 m left of centre, and the true offset at
    the rear window's look-ahead (4 m behind)."""
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.scoring.truth import lane_centre_at
    from lanekeep.sensing.cameras import CameraRig, RenderSettings
    from lanekeep.sensing.snapshot import place_on_road
    from lanekeep.world.build import build

    scenario = load_scenario("clear_straight")
    world = build(scenario)
    x, y, yaw = place_on_road(world, 60.0, 0.3)
    truth = -float(lane_centre_at(world.road, x, y, yaw, scenario.road.ego_lane, [-4.0])[0])
    with CameraRig(world.model, RenderSettings(640, 360)) as rig:
        return rig.render_rgb(world.data, "rear"), rig.cameras["rear"], truth


def test_shipped_weights_load_safely_and_find_the_ego_lane_behind(rear_frame):
    from importlib import resources

    path = resources.files("lanekeep.detectors").joinpath(DEFAULT_WEIGHTS)
    blob = torch.load(str(path), map_location="cpu", weights_only=True)
    assert blob["meta"]["seed"] == 58 and blob["meta"]["recipe"]["seed"] == 58
    assert path.stat().st_size < 1_000_000
    frame, camera, truth = rear_frame
    detector = RowAnchorDetector(camera)
    estimate = detector.detect(frame)
    assert estimate.valid, estimate.reason
    assert estimate.x_m == pytest.approx(-4.0)
    assert abs(estimate.offset_m - truth) < 0.10, (estimate.offset_m, truth)
    again = RowAnchorDetector(camera).detect(frame)  # deterministic
    assert again.offset_m == estimate.offset_m


def test_mirror_pass_makes_the_read_mirror_symmetric(rear_frame):
    """With `mirror` (the default) a frame and its mirror image give opposite offsets: a
    left-right lean of the network cancels (a centred camera: the image mirror is the
    world's)."""
    frame, camera, _ = rear_frame
    direct = RowAnchorDetector(camera).detect(frame)
    mirrored = RowAnchorDetector(camera).detect(np.ascontiguousarray(frame[:, ::-1]))
    assert direct.valid and mirrored.valid
    assert abs(direct.offset_m + mirrored.offset_m) < 1e-3, (direct.offset_m, mirrored.offset_m)
    single = RowAnchorDetector(camera, settings=RowAnchorSettings(mirror=False)).detect(frame)
    assert single.valid and single.offset_m != direct.offset_m


def test_column_spread_is_narrow_on_a_sure_column_and_wide_on_a_guess():
    """A point read on paint has one sharp column; one inferred across a dash gap spreads
    over several (`column_spread`, in bins; "absent" plays no part)."""
    bins = 80
    sure = torch.full((bins + 1,), -20.0)
    sure[40] = 10.0
    guess = -0.5 * ((torch.arange(bins + 1, dtype=torch.float32) - 40.0) / 3.0) ** 2
    guess[-1] = 5.0  # a likely "absent" does not widen the columns
    spread = column_spread(torch.stack([sure, guess]))
    assert spread[0] < 0.01
    assert spread[1] == pytest.approx(3.0, rel=0.02)


def test_seen_spread_weights_wide_points_as_inferred(rear_frame):
    """`seen_spread_px`: each proposal's `paint` (how surely it is seen, the lane fit's weight)
    is min(1, seen_spread_px / spread); 0 (the default) leaves every point seen, so the
    detector reads exactly as before (the paint test off: it sets `paint` too)."""
    frame, camera, _ = rear_frame
    one_frame = {"paint_test": False, "memory_frames": 0}
    plain = RowAnchorDetector(camera, settings=RowAnchorSettings(**one_frame))
    weighted = RowAnchorDetector(camera, settings=RowAnchorSettings(seen_spread_px=4.0,
                                                                    **one_frame))
    a, b = plain.proposals(frame), weighted.proposals(frame)
    np.testing.assert_array_equal(a.points_px, b.points_px)
    assert np.all(a.paint == 1.0)
    _, _, spread = weighted.read(frame)
    lane, anchor = np.nonzero(weighted.points(frame)[1] > 0.5)
    np.testing.assert_allclose(b.paint, np.minimum(1.0, 4.0 / spread[lane, anchor]))
    assert 0.0 < b.paint.min() < 1.0
    with pytest.raises(ValueError, match="seen_spread_px"):
        RowAnchorSettings(seen_spread_px=-1.0)


def test_paint_test_calls_points_on_paint_seen_and_leaves_their_places(rear_frame):
    """`paint_test`: each proposal's `paint` is 1 where a paint-wide ridge lies under it, 0
    elsewhere (detectors/seen_paint.py); the points themselves do not move."""
    frame, camera, _ = rear_frame
    plain = RowAnchorDetector(camera, settings=RowAnchorSettings(paint_test=False,
                                                                 memory_frames=0)
                              ).proposals(frame)
    tested = RowAnchorDetector(camera).proposals(frame)  # the default since 2026-12-02
    np.testing.assert_array_equal(plain.points_px, tested.points_px)
    assert set(np.unique(tested.paint)) <= {0.0, 1.0}
    ego = tested.slots <= 1
    assert 0.3 < tested.paint[ego].mean() < 1.0, tested.paint[ego].mean()


def test_memory_carries_painted_points_only_when_told_the_motion(rear_frame):
    """`memory_frames`: the ego lines' painted points are kept in ground coordinates and
    carried by the motion `move` is told (1 m back here); a detector told no motion between
    two frames reads the second as a fresh detector would."""
    frame, camera, truth = rear_frame
    settings = RowAnchorSettings(paint_test=True, memory_frames=3)
    moving = RowAnchorDetector(camera, settings=settings)
    first = moving.detect(frame)
    props = moving.proposals(frame)
    painted = (props.slots <= 1) & (props.paint >= 0.5)
    ground, ok = camera.pixels_to_ground(props.points_px[painted])
    moving.move(10.0, 0.0, 0.1)
    carried, slots = moving.memory.recall()
    np.testing.assert_allclose(carried, ground[ok] - [1.0, 0.0], atol=1e-9)
    np.testing.assert_array_equal(slots, props.slots[painted][ok])
    second = moving.detect(frame)
    assert first.valid and second.valid and second.offset_m != first.offset_m
    assert abs(second.offset_m - truth) < 0.15
    still = RowAnchorDetector(camera, settings=settings)
    still.detect(frame)
    assert still.detect(frame).offset_m == first.offset_m
    with pytest.raises(ValueError, match="paint_test"):
        RowAnchorSettings(paint_test=False, memory_frames=3)


@pytest.fixture(scope="module")
def double_line_rear_frame():
    """s_bend's rear camera at 640x360 on its first straight: a solid white line on the
    car's right, a double yellow centre line on its left."""
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.sensing.cameras import CameraRig, RenderSettings
    from lanekeep.sensing.snapshot import place_on_road
    from lanekeep.world.build import build

    world = build(load_scenario("s_bend"))
    x, y, yaw = place_on_road(world, 40.0, 0.0)
    with CameraRig(world.model, RenderSettings(640, 360)) as rig:
        return rig.render_rgb(world.data, "rear"), rig.cameras["rear"]


def test_the_double_test_sees_a_double_centre_line(double_line_rear_frame):
    """The network places a double line on its gap; the one-stripe test calls it unseen, the
    double test (`paint_double_gap_m`) paint, and leaves the solid line's points as they were."""
    frame, camera = double_line_rear_frame

    def paint_by_slot(gap_m: float) -> dict[int, np.ndarray]:
        settings = RowAnchorSettings(paint_double_gap_m=gap_m, memory_frames=0)
        props = RowAnchorDetector(camera, settings=settings).proposals(frame)
        return {int(s): props.paint[props.slots == s] for s in (0, 1)}

    single, double = paint_by_slot(0.0), paint_by_slot(0.12)
    shares = {s: (single[s].mean(), double[s].mean()) for s in (0, 1)}
    solid, centre = sorted(shares, key=lambda s: -shares[s][0])  # the solid line: seen anyway
    assert shares[solid][0] > 0.8 and np.array_equal(single[solid], double[solid]), shares
    assert shares[centre][0] < 0.5 and shares[centre][1] > 0.9, shares
