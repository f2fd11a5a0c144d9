"""LaneNet's faster inference path against the plain one, bit for bit: the faster area resize
gives OpenCV's pixels exactly, every torch computation of a frame runs on one thread, the
detector gives the proposals of the plain computation (OpenCV's resize, one call of the
network on the frame and its mirror) exactly, and `detect_many` (one batch for detectors that
share weights) gives what `detect` gives one at a time. Speed is not asserted here; what is
asserted is that it changes nothing else."""

from dataclasses import fields

import cv2
import numpy as np
import pytest
import torch
from torch.overrides import TorchFunctionMode

from lanekeep.core.reproducibility import portable_torch
from lanekeep.detectors import lanenet
from lanekeep.detectors.lanenet import LaneNetDetector, LaneNetSettings, save_weights
from lanekeep.detectors.lanenet_decode import Proposals
from lanekeep.detectors.lanenet_model import LaneNet, LaneNetConfig, _area_resize, prepare_frame
from lanekeep.detectors.lanenet_targets import CellGrid
from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build

SMALL = LaneNetConfig(width=160, height=88, channels=(8, 16, 16), hidden=8, head=16)


@pytest.mark.parametrize("size", [(1280, 720), (640, 360), (2560, 1440), (1920, 1080),
                                  (1000, 700), (1280, 704), (320, 176), (1280, 100), (1280, 176)])
@pytest.mark.parametrize("config", [LaneNetConfig(), SMALL])
def test_area_resize_is_opencvs_pixel_for_pixel(size, config):
    """The two-pass resize where the width shrinks by a power of two, the plain call
    elsewhere: equal to cv2.resize(INTER_AREA) in every pixel, on noise (every rounding tie
    OpenCV can meet) and on a smooth ramp."""
    rng = np.random.default_rng(size[0] + size[1])
    w, h = size
    noise = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    ramp = np.broadcast_to((np.arange(w) * 255 // max(w - 1, 1)).astype(np.uint8)[None, :, None],
                           (h, w, 3)).copy()
    for frame in (noise, ramp, noise[:, :, :1].copy()):
        expected = cv2.resize(frame, (config.width, config.height), interpolation=cv2.INTER_AREA)
        got = _area_resize(frame, config.width, config.height)
        assert got.dtype == np.uint8 and got.shape == expected.shape
        assert np.array_equal(got, expected)
    prepared = prepare_frame(noise, config)
    assert prepared.shape == (3, config.height, config.width) and prepared.flags.c_contiguous


@pytest.fixture(scope="module")
def road_frames():
    """Three front frames of clear_curve along the road (1280x720) and the front camera; the
    rear frames and camera as the third and fourth items."""
    scenario = load_scenario("clear_curve")
    world = build(scenario)
    front, rear = [], []
    with CameraRig(world.model, RenderSettings(1280, 720)) as rig:
        for s in (90.0, 91.5, 93.0):
            place_on_road(world, s, -0.25)
            front.append(rig.render_rgb(world.data, "front"))
            rear.append(rig.render_rgb(world.data, "rear"))
        return front, rig.cameras["front"], rear, rig.cameras["rear"]


def _plain_candidates(model, frames: list[np.ndarray], mirror: bool) -> list[Proposals]:
    """The frames' candidates the plain way: OpenCV's resize, the batch built and the network
    run at one thread, state carried."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    out, state = [], None
    try:
        for frame in frames:
            image = cv2.resize(frame, (model.config.width, model.config.height),
                               interpolation=cv2.INTER_AREA)
            batch = torch.from_numpy(np.ascontiguousarray(image.transpose(2, 0, 1)))[None, None]
            if mirror:
                batch = torch.cat([batch, batch.flip(-1)])
            with torch.inference_mode(), portable_torch():  # the detector's kernel path
                heads, state = model(batch, state)
            rows, cols = model.config.grid
            grid = CellGrid(frame.shape[1], frame.shape[0], rows, cols)
            out.append(lanenet._proposals_of(heads, 0, grid, lanenet.CANDIDATE_SCORE))
    finally:
        torch.set_num_threads(threads)
    return out


@pytest.mark.parametrize("mirror", [True, False])
def test_detector_gives_the_plain_computations_proposals_exactly(road_frames, mirror):
    frames, camera = road_frames[:2]
    detector = LaneNetDetector(camera, settings=LaneNetSettings(mirror=mirror))
    expected = _plain_candidates(detector.model, frames, mirror)
    for frame, plain in zip(frames, expected, strict=True):
        assert detector.detect(frame).valid
        got = detector.last.candidates
        assert len(got.scores) > 10
        for f in fields(Proposals):
            assert np.array_equal(getattr(got, f.name), getattr(plain, f.name)), f.name


class _ThreadsSeen(TorchFunctionMode):
    """Records torch's intra-op thread count at every torch call made from Python."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: list[tuple[str, int]] = []

    def __torch_function__(self, func, types, args=(), kwargs=None):
        self.seen.append((getattr(func, "__name__", str(func)), torch.get_num_threads()))
        return func(*args, **(kwargs or {}))


def test_every_torch_computation_of_a_frame_runs_on_one_thread(road_frames):
    """In a process allowed two threads (a single loop), a torch call outside the one-thread
    scope would run on both and wait for the second when the other core is busy."""
    frames, camera = road_frames[:2]
    detector = LaneNetDetector(camera)
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        with _ThreadsSeen() as mode:
            detector.detect(frames[0])
        assert torch.get_num_threads() == 2  # left as found
    finally:
        torch.set_num_threads(before)
    calls = [name for name, _ in mode.seen]
    assert "cat" in calls and "flip" in calls and "conv2d" in calls
    # reading the outputs after the scope (a view, then numpy's view of it) runs no kernel
    outside = {name for name, threads in mode.seen if threads != 1}
    assert outside <= {"__getitem__", "numpy"}, outside


def _same_decoding(a: LaneNetDetector, b: LaneNetDetector) -> bool:
    pa, pb = a.last.proposals, b.last.proposals
    return (all(np.array_equal(getattr(pa, f.name), getattr(pb, f.name))
                for f in fields(Proposals))
            and torch.equal(a._state.hidden, b._state.hidden)
            and torch.equal(a._state.features, b._state.features)
            and a.last.scene_change == b.last.scene_change)


def _same_estimate(x, y) -> bool:
    if x.valid != y.valid or x.reason != y.reason:
        return False
    return not x.valid or (x.offset_m == y.offset_m and np.array_equal(x.left, y.left)
                           and np.array_equal(x.right, y.right))


def test_detect_many_is_detect_one_at_a_time_bit_for_bit(road_frames, tmp_path):
    """Front and rear (two cameras, one weights file) as one batch of four give what each
    gives alone, state carried; so does a step where only one starts a new scene (two calls),
    and a third detector with other weights (its own call)."""
    front, front_cam, rear, rear_cam = road_frames
    other = tmp_path / "other.pt"
    save_weights(LaneNet(SMALL, seed=1), other)
    alone = [LaneNetDetector(front_cam), LaneNetDetector(rear_cam),
             LaneNetDetector(front_cam, weights=other)]
    together = [LaneNetDetector(front_cam), LaneNetDetector(rear_cam),
                LaneNetDetector(front_cam, weights=other)]
    dark = (front[1] // 6).astype(np.uint8)  # a new scene for the front camera only
    changes = []
    for f, r in ((front[0], rear[0]), (front[1], rear[1]), (dark, rear[2]), (front[2], rear[2])):
        step = [f, r, f]
        expected = [d.detect(x) for d, x in zip(alone, step, strict=True)]
        got = LaneNetDetector.detect_many(together, step)
        assert all(_same_estimate(x, y) for x, y in zip(expected, got, strict=True))
        assert all(_same_decoding(a, b) for a, b in zip(alone, together, strict=True))
        changes.append((together[0].last.scene_change, together[1].last.scene_change))
    # the last two steps had a fresh front state beside a carried rear one
    assert changes == [(False, False), (False, False), (True, False), (True, False)]
    assert expected[0].valid and expected[1].valid


def test_detect_many_leaves_every_detector_as_it_was_when_it_fails(road_frames):
    """The loop runs the detectors one at a time after a failed batch: that must start from
    the state they had, not from a half-done step."""
    front, front_cam, rear, rear_cam = road_frames
    detectors = [LaneNetDetector(front_cam), LaneNetDetector(rear_cam)]
    LaneNetDetector.detect_many(detectors, [front[0], rear[0]])
    before = [(d._state, d._thumb, d._frame_size, d.last) for d in detectors]
    with pytest.raises(Exception):  # noqa: B017 - whatever OpenCV or torch raise
        LaneNetDetector.detect_many(detectors, [front[1], np.zeros((720, 1280), np.uint8)])
    for d, (state, thumb, size, last) in zip(detectors, before, strict=True):
        assert d._state is state and d._thumb is thumb and d._frame_size == size
        assert d.last is last
    with pytest.raises(ValueError, match="2 detectors for 1 frames"):
        LaneNetDetector.detect_many(detectors, [front[1]])
    with pytest.raises(ValueError, match="listed twice"):
        LaneNetDetector.detect_many([detectors[0], detectors[0]], [front[1], front[2]])
    assert detectors[0]._state is before[0][0]


def test_area_resize_takes_the_two_pass_path_for_the_cameras_size(monkeypatch):
    """The loop's 1280x720 frames do go the faster way (the test above would pass if they
    never did)."""
    import lanekeep.detectors.lanenet_model as model_module

    seen = []
    real = cv2.resize

    def spy(src, *args, **kwargs):
        seen.append(src.dtype)
        return real(src, *args, **kwargs)

    monkeypatch.setattr(model_module.cv2, "resize", spy)
    _area_resize(np.zeros((720, 1280, 3), np.uint8), 320, 176)
    assert seen == [np.float32, np.float32]
