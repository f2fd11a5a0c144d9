"""Spatiotemporal LaneNet: network contract, weights files, targets <-> decoding, RANSAC, and an
overfit run proving that model, targets, loss and decoding fit together (no simulator data)."""

import math

import cv2
import numpy as np
import pytest
import torch

from lanekeep.detectors.lanenet import (
    LaneNetDetector,
    LaneNetSettings,
    WeightsError,
    load_weights,
    save_weights,
)
from lanekeep.detectors.lanenet_decode import (
    DecodeSettings,
    ego_estimate,
    fit_boundaries,
    proposals,
    ransac_fit,
)
from lanekeep.detectors.lanenet_model import LaneNet, LaneNetConfig, prepare_frame
from lanekeep.detectors.lanenet_targets import (
    BoundaryLabel,
    CellGrid,
    FrameLabel,
    collate,
    encode,
    lanenet_loss,
    slots_from_lateral,
)
from lanekeep.detectors.network_io import one_torch_thread
from lanekeep.geometry.camera_model import CameraModel

W, H = 1280, 720
SMALL = LaneNetConfig(width=160, height=88, channels=(8, 16, 16), hidden=8, head=16)


def _camera(pitch_deg: float = -2.0, rear: bool = False) -> CameraModel:
    f = (H / 2.0) / math.tan(math.radians(50.0) / 2.0)
    K = np.array([[f, 0, (W - 1) / 2.0], [0, f, (H - 1) / 2.0], [0, 0, 1]])  # noqa: N806
    if rear:
        return CameraModel.from_mounting("rear", K, W, H, 1.4, math.radians(pitch_deg), -1.5,
                                         yaw_rad=math.pi)
    return CameraModel.from_mounting("front", K, W, H, 1.4, math.radians(pitch_deg), 1.0)


def _label(camera: CameraModel, offset_m: float = 0.0, curvature: float = 0.0,
           lanes_y: tuple[float, ...] = (1.85, -1.85, 5.55, -5.55)) -> tuple[FrameLabel, list]:
    """Boundaries y = c0 + curvature x^2 (vehicle frame), projected from 4 to 80 m away."""
    rear = camera.rotation[0, 2] > 0
    x = np.linspace(4.0, 80.0, 200) * (-1.0 if rear else 1.0)
    lateral = np.array(lanes_y) - offset_m
    slots = slots_from_lateral(-lateral if rear else lateral)  # slots are the camera's
    out, polys = [], []
    for y0, slot in zip(lanes_y, slots, strict=True):
        c = np.array([y0 - offset_m, 0.0, curvature])
        uv, ok = camera.project_ground(np.stack([x, c[0] + c[2] * x * x], -1))
        uv = uv[ok & (uv[:, 0] > -0.5) & (uv[:, 0] < W - 0.5) & (uv[:, 1] < H - 0.5)]
        out.append(BoundaryLabel(uv, int(slot)))
        polys.append(c)
    return FrameLabel(tuple(out)), polys


def _x_of_label(bl: BoundaryLabel, rows: np.ndarray) -> np.ndarray:
    p = bl.points_px[np.argsort(bl.points_px[:, 1])]
    return np.interp(rows, p[:, 1], p[:, 0], left=np.nan, right=np.nan)


def _perfect_logits(t, n_slots: int = 5):
    obj = np.where(t.objectness > 0, 12.0, -12.0)
    slot = np.full((n_slots,) + t.objectness.shape, -12.0)
    r, c = np.nonzero(t.objectness)
    slot[t.slot[r, c], r, c] = 12.0
    return obj, t.x_offset, slot


def test_slots_counted_outwards_from_camera():
    assert slots_from_lateral(np.array([1.8, -1.9, 5.5, -5.6, 9.0, -9.1])).tolist() == [
        0, 1, 2, 3, 4, 4]
    assert slots_from_lateral(np.array([-0.3, -4.0, 3.4])).tolist() == [1, 3, 0]


def test_shapes_and_resize():
    model = LaneNet(SMALL).eval()
    rows, cols = SMALL.grid
    frames = torch.randint(0, 256, (2, 3, 3, 176, 320), dtype=torch.uint8)
    out, state = model(frames)
    assert out.objectness.shape == (2, 3, rows, cols) and out.marking.shape == (2, 3, rows, cols)
    assert out.slot.shape == (2, 3, 5, rows, cols)
    assert float(out.x_offset.detach().min()) >= 0.0 and float(out.x_offset.detach().max()) <= 1.0
    assert state.hidden.shape == (2, SMALL.hidden, rows // SMALL.rows_per_cell, cols)
    assert prepare_frame(np.zeros((H, W, 3), np.uint8), SMALL).shape == (3, 88, 160)


@pytest.mark.parametrize("raw", [-1e4, -30.0, 0.0, 30.0, 1e4])
def test_alpha_stays_in_unit_interval(raw):
    model = LaneNet(SMALL).eval()
    with torch.no_grad():
        model.alpha_raw.fill_(raw)
    assert 0.0 <= float(model.alpha.detach()) <= 1.0
    out, _ = model(torch.rand(1, 2, 3, 88, 160))
    assert torch.isfinite(out.objectness).all()


def test_single_frame_is_first_step_and_state_splits_a_sequence():
    model = LaneNet(SMALL).eval()
    frames = torch.rand(1, 4, 3, 88, 160, generator=torch.Generator().manual_seed(1))
    with torch.no_grad():
        whole, _ = model(frames)
        first, state = model(frames[:, :1])
        rest, _ = model(frames[:, 1:], state)
    torch.testing.assert_close(first.objectness[:, 0], whole.objectness[:, 0])
    torch.testing.assert_close(rest.objectness, whole.objectness[:, 1:])
    torch.testing.assert_close(rest.slot, whole.slot[:, 1:])
    # The state matters: the same frame after others is not seen as a fresh frame.
    assert not torch.allclose(whole.objectness[:, 3], model(frames[:, 3:])[0].objectness[:, 0])


def test_deterministic():
    frames = torch.randint(0, 256, (1, 3, 3, 88, 160), dtype=torch.uint8,
                           generator=torch.Generator().manual_seed(2))
    outs = []
    for _ in range(2):
        model = LaneNet(SMALL, seed=7).eval()
        with torch.no_grad():
            outs.append(model(frames)[0])
    assert all(torch.equal(a, b) for a, b in zip(outs[0], outs[1], strict=True))
    other = LaneNet(SMALL, seed=8).eval()
    with torch.no_grad():
        assert not torch.equal(other(frames)[0].objectness, outs[0].objectness)


@pytest.fixture
def weights_file(tmp_path):
    path = tmp_path / "lanenet.pt"
    save_weights(LaneNet(SMALL, seed=3), path, meta={"note": "random"})
    return path


def test_weights_round_trip(weights_file):
    model = load_weights(weights_file)
    ref = LaneNet(SMALL, seed=3).eval()
    for (k, a), b in zip(model.state_dict().items(), ref.state_dict().values(), strict=True):
        assert torch.equal(a, b), k


def test_bad_weights_files_name_the_file(tmp_path, weights_file):
    empty = tmp_path / "empty.pt"
    empty.write_bytes(b"")
    corrupt = tmp_path / "corrupt.pt"
    corrupt.write_bytes(weights_file.read_bytes()[:300])
    noise = tmp_path / "noise.pt"
    noise.write_bytes(np.random.default_rng(0).integers(0, 256, 4000, np.uint8).tobytes())
    foreign = tmp_path / "foreign.pt"
    torch.save({"state_dict": {"w": torch.zeros(3)}}, foreign)
    wrong = tmp_path / "wrong_shapes.pt"
    blob = torch.load(weights_file, weights_only=True)
    blob["config"] = LaneNetConfig().to_dict()  # claims the default architecture
    torch.save(blob, wrong)
    alien = tmp_path / "alien_arch.pt"
    blob["config"] = dict(SMALL.to_dict(), layers=9)
    torch.save(blob, alien)
    for path in (tmp_path / "missing.pt", empty, corrupt, noise, foreign, wrong, alien):
        with pytest.raises(WeightsError) as err:
            load_weights(path)
        assert str(path) in str(err.value) and isinstance(err.value, ValueError)
    with pytest.raises(WeightsError, match="wrong_shapes.pt"):
        LaneNetDetector(_camera(), weights=wrong)


def test_detector_state_reset_and_scene_change(weights_file):
    rng = np.random.default_rng(4)
    a = rng.integers(0, 256, (H, W, 3), np.uint8)
    b = np.clip(a.astype(int) + rng.integers(-6, 7, a.shape), 0, 255).astype(np.uint8)
    night = (a // 6).astype(np.uint8)
    det, fresh = LaneNetDetector(_camera(), weights=weights_file), LaneNetDetector(
        _camera(), weights=weights_file)
    det.infer(a)
    streamed = det.infer(b)
    assert not streamed.scene_change
    alone = fresh.infer(b)
    assert not np.array_equal(det._state.hidden.numpy(), fresh._state.hidden.numpy())
    det.reset()
    again = det.infer(b)
    assert np.array_equal(det._state.hidden.numpy(), fresh._state.hidden.numpy())
    assert np.array_equal(again.proposals.scores, alone.proposals.scores)
    cut = det.infer(night)  # another scene: the state is dropped
    assert cut.scene_change
    fresh.reset()
    fresh.infer(night)
    assert np.array_equal(det._state.hidden.numpy(), fresh._state.hidden.numpy())
    estimate = det.detect(b)
    assert not estimate.valid or math.isfinite(estimate.offset_m)


@pytest.mark.parametrize("curvature", [0.0, 1.5e-3, -2.5e-3])
def test_targets_decode_round_trip(curvature):
    camera = _camera()
    label, polys = _label(camera, offset_m=0.3, curvature=curvature)
    grid = CellGrid(W, H, *LaneNetConfig().grid)
    t = encode(label, grid)
    assert t.objectness.sum() > 20 and set(np.unique(t.slot[t.objectness > 0])) == {0, 1, 2, 3}
    props = proposals(*_perfect_logits(t), grid, 0.5)
    assert len(props.scores) == int(t.objectness.sum())
    settings = DecodeSettings(inlier_px=2.0)
    for cam in (camera, None):
        bounds = {b.slot: b for b in fit_boundaries(props, grid, settings, cam)}
        assert set(bounds) == {0, 1, 2, 3}
        for bl in label.boundaries:
            rows = np.arange(360, H, 5.0)
            ref = _x_of_label(bl, rows)
            got = bounds[bl.slot].x_at_rows(rows, cam)
            ok = np.isfinite(ref) & np.isfinite(got)
            assert ok.sum() >= 5
            assert np.max(np.abs(got[ok] - ref[ok])) < 2.0, (cam is None, bl.slot)
    est = ego_estimate(list(fit_boundaries(props, grid, settings, camera)), camera, 8.0, 3.7,
                       0.8)
    assert est.valid and abs(est.offset_m - (0.3 - curvature * 8.0 ** 2)) < 0.02
    np.testing.assert_allclose(est.left, polys[0], atol=0.05)


def test_marking_mask_targets_and_loss():
    camera = _camera()
    label, _ = _label(camera, lanes_y=(1.85, -1.85))
    mask = np.zeros((H, W), np.uint8)
    mask[600:640, 200:230] = 1  # one dash
    grid = CellGrid(W, H, *LaneNetConfig().grid)
    t = encode(FrameLabel(label.boundaries, mask), grid)
    assert t.marking.sum() >= 1 and t.marking[int(620 / grid.cell_h), int(215 / grid.cell_w)] == 1
    assert t.marking[:5].sum() == 0
    batch = collate([[t, t]])
    assert batch["marking"].shape == (1, 2, grid.rows, grid.cols)
    assert batch["slot"].dtype == torch.int64
    model = LaneNet(LaneNetConfig())
    x = torch.zeros(1, 2, 3, 176, 320)
    loss, parts = lanenet_loss(model(x)[0], batch)
    assert set(parts) == {"objectness", "x_offset", "slot", "marking", "total"}
    loss.backward()
    assert model.alpha_raw.grad is not None and torch.isfinite(loss)
    no_mask = collate([[encode(label, grid)]])
    assert "marking" not in no_mask


def test_rear_camera_slots_are_its_own():
    camera = _camera(rear=True)
    label, polys = _label(camera, offset_m=-0.4)
    grid = CellGrid(W, H, *LaneNetConfig().grid)
    props = proposals(*_perfect_logits(encode(label, grid)), grid, 0.5)
    est = ego_estimate(fit_boundaries(props, grid, DecodeSettings(), camera), camera, -8.0, 3.7,
                       0.8)
    assert est.valid and abs(est.offset_m + 0.4) < 0.02
    np.testing.assert_allclose(est.left, polys[0], atol=0.05)  # vehicle-left = camera-right


def test_ego_estimate_needs_the_pair():
    camera = _camera()
    label, _ = _label(camera, lanes_y=(1.85, 5.55))
    grid = CellGrid(W, H, *LaneNetConfig().grid)
    props = proposals(*_perfect_logits(encode(label, grid)), grid, 0.5)
    est = ego_estimate(fit_boundaries(props, grid, DecodeSettings(), camera), camera, 8.0, 3.7,
                       0.8)
    assert not est.valid and "right missing" in est.reason


def test_ransac_recovers_parabola_with_outliers():
    rng = np.random.default_rng(5)
    x = rng.uniform(5.0, 40.0, 200)
    truth = np.array([0.8, 0.03, 1.5e-3])
    y = truth[0] + truth[1] * x + truth[2] * x * x + rng.normal(0, 0.01, x.size)
    bad = rng.random(x.size) < 0.3
    y[bad] = rng.uniform(-6.0, 6.0, bad.sum())
    basis = np.stack([np.ones_like(x), x, x * x], -1)
    coeffs, inliers = ransac_fit(basis, y, np.full(x.size, 0.01), 4.0, 100,
                                 np.random.default_rng(0))
    np.testing.assert_allclose(coeffs, truth, rtol=0.1, atol=5e-3)
    assert np.mean(inliers[~bad]) > 0.95 and np.mean(inliers[bad]) < 0.05
    xs = np.linspace(5, 40, 50)
    err = (coeffs[0] + coeffs[1] * xs + coeffs[2] * xs ** 2) - (
        truth[0] + truth[1] * xs + truth[2] * xs ** 2)
    assert np.max(np.abs(err)) < 0.03


def _synthetic_frame(camera, rng, offset_m, curvature):
    """Grey road, two painted boundaries (left dashed), and distractors: a car-like box, a
    bright crossing bar, blotches. Returns the frame and its label (ego pair only)."""
    img = np.full((H, W, 3), 70, np.uint8)
    horizon = int(camera.horizon_row())
    img[:horizon] = (150, 170, 200)
    img = np.clip(img.astype(int) + rng.integers(-12, 13, img.shape), 0, 255).astype(np.uint8)
    label, _ = _label(camera, offset_m, curvature, lanes_y=(1.85, -1.85))
    x = np.linspace(4.0, 80.0, 400)
    for y0, dashed in ((1.85, True), (-1.85, False)):
        for x0 in np.arange(4.0, 80.0, 12.0 if dashed else 76.0):
            seg = x[(x >= x0) & (x <= x0 + (3.0 if dashed else 76.0))]
            left = np.stack([seg, y0 - offset_m + curvature * seg ** 2 + 0.075], -1)
            right = np.stack([seg, y0 - offset_m + curvature * seg ** 2 - 0.075], -1)
            uv = np.concatenate([camera.project_ground(left)[0],
                                 camera.project_ground(right)[0][::-1]])
            cv2.fillPoly(img, [np.round(uv * 4).astype(np.int32)], (235, 235, 225), shift=2)
    cx = int(rng.uniform(300, 980))
    cv2.rectangle(img, (cx, horizon + 20), (cx + 120, horizon + 90), (200, 40, 40), -1)
    bar_y = int(rng.uniform(horizon + 120, H - 60))
    cv2.rectangle(img, (0, bar_y), (W, bar_y + 8), (220, 220, 220), -1)
    for _ in range(6):
        c = (int(rng.uniform(0, W)), int(rng.uniform(horizon + 10, H)))
        cv2.circle(img, c, int(rng.uniform(5, 25)), (110, 110, 110), -1)
    return img, label


@pytest.mark.slow
def test_overfit_synthetic_lanes_end_to_end(tmp_path):
    torch.manual_seed(0)
    camera = _camera()
    rng = np.random.default_rng(6)
    config = LaneNetConfig()
    grid = CellGrid(W, H, *config.grid)
    poses = [(-0.5, 0.0), (0.0, 1e-3), (0.4, -1e-3), (0.2, 0.0)]
    frames, labels = zip(*[_synthetic_frame(camera, rng, o, c) for o, c in poses], strict=True)
    x = torch.from_numpy(np.stack([prepare_frame(f, config) for f in frames]))[:, None]
    batch = collate([[encode(lab, grid)] for lab in labels])
    model = LaneNet(config, seed=0)
    opt = torch.optim.Adam(model.parameters(), lr=3e-3)
    with one_torch_thread():  # the end point must not depend on the worker's thread count
        for _ in range(150):  # sub-pixel by ~100 steps; ~0.4 s of CPU a step
            opt.zero_grad()
            loss, parts = lanenet_loss(model(x)[0], batch)
            loss.backward()
            opt.step()
    model.eval()
    with torch.no_grad():
        out, _ = model(x)
    for i, lab in enumerate(labels):
        props = proposals(out.objectness[i, 0].numpy(), out.x_offset[i, 0].numpy(),
                          out.slot[i, 0].numpy(), grid, 0.5)
        bounds = {b.slot: b for b in fit_boundaries(props, grid, DecodeSettings(), camera)}
        assert {0, 1} <= set(bounds), (i, parts)
        for bl in lab.boundaries:
            rows = np.arange(400, H, 10.0)
            ref = _x_of_label(bl, rows)
            got = bounds[bl.slot].x_at_rows(rows, camera)
            ok = np.isfinite(ref) & np.isfinite(got)
            assert ok.sum() >= 10 and np.median(np.abs(got[ok] - ref[ok])) < 3.0, (i, bl.slot)
    # The same weights through the detector wrapper: the ego lane in the vehicle frame.
    save_weights(model, tmp_path / "overfit.pt")
    detector = LaneNetDetector(camera, weights=tmp_path / "overfit.pt")
    for frame, (offset_m, curvature) in zip(frames, poses, strict=True):
        detector.reset()
        est = detector.detect(frame)
        expected = offset_m - curvature * est.x_m ** 2
        assert est.valid and abs(est.offset_m - expected) < 0.05, (est, expected)


def _ground_boundary(camera: CameraModel, slot: int, coeffs: np.ndarray, x: np.ndarray,
                     noise_px: float, rng: np.random.Generator):
    """A fitted-boundary stand-in: ground points on y = coeffs(x) moved across by pixel noise
    (metres per pixel at each distance), with their image points."""
    from lanekeep.detectors.lanenet_decode import Boundary

    dist = np.abs(x - camera.position_m[0])
    y = coeffs[0] + coeffs[1] * x + coeffs[2] * x * x
    y = y + rng.normal(0.0, noise_px, len(x)) * dist / camera.fx
    uv, _ = camera.project_ground(np.stack([x, y], -1))
    return Boundary(slot=slot, coeffs=np.asarray(coeffs, float), frame="ground", points_px=uv,
                    score=0.9, points_xy=np.stack([x, y], -1))


def test_parallel_pair_bends_a_short_side_with_the_long_one():
    from lanekeep.detectors.lanenet_decode import parallel_pair

    camera, rng = _camera(), np.random.default_rng(3)
    true_left, true_right = np.array([1.7, 0.01, 2e-3]), np.array([-2.0, 0.01, 2e-3])
    left = _ground_boundary(camera, 0, true_left, np.linspace(5, 40, 30), 1.0, rng)
    right = _ground_boundary(camera, 1, true_right, np.linspace(5, 9, 6), 1.0, rng)
    own = ransac_fit(np.stack([np.ones(6), right.points_xy[:, 0], right.points_xy[:, 0] ** 2],
                              -1), right.points_xy[:, 1],
                     np.abs(right.points_xy[:, 0] - 1.0) / camera.fx, 6.0, 50, rng)[0]
    c_left, c_right = parallel_pair(left, right, camera, DecodeSettings())
    at = lambda c: c[0] + c[1] * 20.0 + c[2] * 400.0  # noqa: E731
    assert c_left[1:] == pytest.approx(c_right[1:])  # one heading, one bend
    assert abs(at(c_right) - at(true_right)) < 0.1  # within 10 cm at 20 m
    assert abs(at(c_right) - at(true_right)) < abs(at(own) - at(true_right))
    assert abs(at(c_left) - at(true_left)) < 0.1


def test_parallel_pair_needs_three_points_a_side():
    from lanekeep.detectors.lanenet_decode import parallel_pair

    camera, rng = _camera(), np.random.default_rng(0)
    left = _ground_boundary(camera, 0, np.array([1.8, 0, 0]), np.linspace(5, 30, 10), 0.5, rng)
    right = _ground_boundary(camera, 1, np.array([-1.9, 0, 0]), np.array([6.0, 7.0]), 0.5, rng)
    assert parallel_pair(left, right, camera, DecodeSettings()) is None


def test_sides_fitted_alone_must_keep_the_lane_width_where_both_are_seen():
    """Where the pair cannot be fitted (a side with two points), each side's own fit stands,
    and is a lane only if it keeps the width along the stretch both sides are seen."""
    camera, rng = _camera(), np.random.default_rng(0)
    left = _ground_boundary(camera, 0, np.array([1.8, 0, 0]), np.linspace(5, 30, 10), 0.0, rng)
    for slope, valid in ((0.0, True), (-0.08, False)):  # the second drifts 1.6 m off by 20 m
        right = _ground_boundary(camera, 1, np.array([-1.9, slope, 0.0]), np.array([6.0, 20.0]),
                                 0.0, rng)
        est = ego_estimate([left, right], camera, 4.0, 3.7, 0.8, DecodeSettings())
        assert est.valid is valid, est.reason


def test_curvature_prior_holds_a_near_fit_straight_and_leaves_a_long_one():
    camera, rng = _camera(), np.random.default_rng(1)
    settings = DecodeSettings()
    none = DecodeSettings(curvature_prior_per_m=0.0)
    assert none.curvature_prior_row(3).shape == (0, 3)
    row = settings.curvature_prior_row(3)
    assert row.shape == (1, 3) and row[0, 2] == pytest.approx(
        settings.pixel_noise_px / (settings.curvature_prior_per_m / 2))

    def c2(x, curvature, s):
        y = 1.8 + curvature / 2 * x * x + rng.normal(0, 2.0, len(x)) * x / camera.fx
        basis = np.stack([np.ones_like(x), x, x * x], -1)
        return ransac_fit(basis, y, np.maximum(x - 1.0, 1.0) / camera.fx, 6.0, 100,
                          np.random.default_rng(0), s.curvature_prior_row(3))[0][2]

    near = np.linspace(4, 9, 8)  # a straight line seen to 9 m: the prior damps a noisy bend
    bends = [(abs(c2(near, 0.0, settings)), abs(c2(near, 0.0, none))) for _ in range(20)]
    assert np.mean([b[0] for b in bends]) < 0.5 * np.mean([b[1] for b in bends])
    far = np.linspace(4, 45, 40)  # a 100 m radius seen to 45 m: the points win
    assert c2(far, 0.01, settings) == pytest.approx(0.005, rel=0.2)


def test_a_side_inferred_without_paint_leans_on_the_seen_side_and_the_lane_width():
    from dataclasses import replace

    from lanekeep.detectors.lanenet_decode import parallel_pair

    camera, rng = _camera(), np.random.default_rng(5)
    seen = _ground_boundary(camera, 1, np.array([-1.8, 0.0, 0.0]), np.linspace(5, 30, 20),
                            1.0, rng)
    # the left side guessed through an occluder: 0.5 m too far out, and no paint seen there
    guessed = _ground_boundary(camera, 0, np.array([2.4, 0.0, 0.0]), np.linspace(5, 30, 20),
                               1.0, rng)
    guessed = replace(guessed, paint=np.full(20, 0.02))
    seen = replace(seen, paint=np.full(20, 0.95))
    ignore = DecodeSettings(unseen_weight=1.0, width_std_m=0.0)
    c_left, _ = parallel_pair(guessed, seen, camera, ignore, 3.7)
    assert c_left[0] == pytest.approx(2.4, abs=0.05)  # paint ignored: the guess stands
    trust_paint = DecodeSettings(unseen_weight=0.01, width_std_m=0.15)
    c_left, c_right = parallel_pair(guessed, seen, camera, trust_paint, 3.7)
    assert c_right[0] == pytest.approx(-1.8, abs=0.05)  # the seen side stays where it is
    assert abs(c_left[0] - 1.9) < 0.15  # the guessed side follows it at the lane's width
    with pytest.raises(ValueError):
        DecodeSettings(unseen_weight=0.0)


def test_the_ego_pair_weighs_a_point_by_the_networks_confidence_in_it():
    """With `score_power`, points the network is unsure of (low objectness) count less: a side
    whose near half is unsure and drawn 20 cm inward follows its sure far half instead."""
    from dataclasses import replace

    from lanekeep.detectors.lanenet_decode import parallel_pair

    camera, rng = _camera(), np.random.default_rng(2)
    right = _ground_boundary(camera, 1, np.array([-1.85, 0.0, 0.0]), np.linspace(5, 30, 20),
                             0.0, rng)
    x = np.linspace(5, 30, 20)
    left = _ground_boundary(camera, 0, np.array([1.85, 0.0, 0.0]), x, 0.0, rng)
    unsure = x < 12.0
    xy = left.points_xy.copy()
    xy[unsure, 1] -= 0.2
    scores = np.where(unsure, 0.55, 0.98)
    left = replace(left, points_xy=xy, scores=scores)
    right = replace(right, scores=np.full(20, 0.98))
    blind = DecodeSettings(score_power=0.0, width_std_m=0.0)
    weighed = DecodeSettings(score_power=8.0, width_std_m=0.0)
    c_blind, _ = parallel_pair(left, right, camera, blind)
    c_weighed, _ = parallel_pair(left, right, camera, weighed)
    assert abs(c_weighed[0] - 1.85) < 0.5 * abs(c_blind[0] - 1.85)
    assert DecodeSettings().score_power > 0  # the shipped decoding weighs them
    with pytest.raises(ValueError):
        DecodeSettings(score_power=-1.0)


def test_proposals_carry_the_paint_probability():
    grid = CellGrid(W, H, 4, 4)
    obj = np.full((4, 4), -10.0)
    obj[2, 1] = obj[3, 2] = 10.0
    marking = np.zeros((4, 4))
    marking[2, 1], marking[3, 2] = 5.0, -5.0
    props = proposals(obj, np.full((4, 4), 0.5), np.zeros((5, 4, 4)), grid, 0.5, marking)
    assert props.paint.round(2).tolist() == [0.99, 0.01]
    assert proposals(obj, np.full((4, 4), 0.5), np.zeros((5, 4, 4)), grid, 0.5).paint.tolist() \
        == [1.0, 1.0]


def test_ground_points_beyond_the_decoding_range_are_not_fitted():
    from lanekeep.detectors.lanenet_decode import Proposals, _fit_one

    camera = _camera()
    x = np.linspace(5, 60, 30)
    uv, _ = camera.project_ground(np.stack([x, np.full_like(x, 1.85)], -1))
    n = len(x)
    props = Proposals(points_px=uv, boxes_px=np.zeros((n, 4)), scores=np.ones(n),
                      slots=np.zeros(n, int), slot_probs=np.ones(n), paint=np.ones(n))
    rng = np.random.default_rng(0)
    near = DecodeSettings(max_range_m=30.0)
    boundary, _ = _fit_one(props, np.arange(n), 0, near, rng, camera, None)
    assert boundary.points_xy[:, 0].max() < 30.0 + camera.position_m[0]
    boundary, _ = _fit_one(props, np.arange(n), 0, DecodeSettings(), rng, camera, None)
    assert boundary.points_xy[:, 0].max() > 55.0
    with pytest.raises(ValueError):
        DecodeSettings(max_range_m=0.0)


def test_a_cauchy_curvature_prior_damps_a_noisy_bend_and_lets_a_sharp_turn_stand():
    """The ego pair's curvature prior: the Gaussian pulls a 40 m radius turn seen to 15 m
    toward straight (the car then cut the turn); the Cauchy one of the same scale leaves it,
    and still damps the bend that noise puts into a straight pair seen to 9 m."""
    from dataclasses import replace

    from lanekeep.detectors.lanenet_decode import parallel_pair

    camera = _camera()
    gaussian = DecodeSettings(curvature_prior_shape="gaussian", width_std_m=0.0)
    cauchy = replace(gaussian, curvature_prior_shape="cauchy")
    none = replace(gaussian, curvature_prior_per_m=0.0)
    assert DecodeSettings().curvature_prior_shape == "cauchy"
    assert LaneNetSettings(curvature_prior_shape="gaussian").decode().curvature_prior_shape \
        == "gaussian"

    def pair_c2(c2: float, x: np.ndarray, noise_px: float, settings, seed: int) -> float:
        rng = np.random.default_rng(seed)
        left = _ground_boundary(camera, 0, np.array([1.85, 0.0, c2]), x, noise_px, rng)
        right = _ground_boundary(camera, 1, np.array([-1.85, 0.0, c2]), x, noise_px, rng)
        left, right = (replace(b, paint=np.full(len(x), 0.3)) for b in (left, right))
        return parallel_pair(left, right, camera, settings)[0][2]

    turn, x = 0.5 / 40.0, np.linspace(4, 15, 16)
    shrunk, kept = pair_c2(turn, x, 0.5, gaussian, 0), pair_c2(turn, x, 0.5, cauchy, 0)
    assert abs(kept - turn) < 0.05 * turn
    assert abs(shrunk - turn) > 3 * abs(kept - turn)
    near = np.linspace(4, 9, 8)
    bends = np.array([[abs(pair_c2(0.0, near, 2.0, s, seed)) for s in (cauchy, none)]
                      for seed in range(20)])
    assert bends[:, 0].mean() < 0.5 * bends[:, 1].mean()
    with pytest.raises(ValueError):
        DecodeSettings(curvature_prior_shape="laplace")
