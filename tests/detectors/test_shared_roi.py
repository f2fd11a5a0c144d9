"""The region of interest the classical models share (detectors/image_stage.py `RoiMemo`).

Both models crop, scale, destreak and find the vehicles in the same front frame each step; a
memo lets the second take the first's. These tests hold that sharing changes nothing: a shared
region equals one computed afresh, models that share give the estimates of models that do not
(on one thread or two at once), and a frame changed in place, another frame or another image
stage never gets a stale region.
"""

import math
import threading
import weakref
from dataclasses import fields, replace

import mujoco
import numpy as np
import pytest

import lanekeep  # noqa: F401 - MUJOCO_GL before mujoco
from lanekeep.detectors import image_stage
from lanekeep.detectors.image_stage import RoiMemo, region_of_interest
from lanekeep.detectors.registry import make_detector
from lanekeep.detectors.vehicle_mask import VehicleFilter
from lanekeep.sensing.cameras import CameraRig

MODELS = ("hough", "sliding_window")


@pytest.fixture(scope="module")
def scene(curve_world):
    """Front and rear frames at a few poses on the curve, each also with a vehicle-dark band
    (the underside of a vehicle ahead) painted into its region of interest, and the cameras."""
    road, lane = curve_world.road, curve_world.scenario.road.ego_lane
    frames = []
    with CameraRig(curve_world.model) as rig:
        for s_m, off, hd in ((150.0, 0.0, 0.0), (155.0, 0.4, 2.0), (160.0, -0.4, -2.0)):
            x, y = road.position(s_m, road.lane_center_r(lane) + off)
            yaw = float(road.heading_at(s_m)) + math.radians(hd)
            curve_world.car.place(float(x), float(y), yaw, 0.0)
            mujoco.mj_forward(curve_world.model, curve_world.data)
            frames.append({c: rig.render_rgb(curve_world.data, c).copy()
                           for c in ("front", "rear")})
        cameras = dict(rig.cameras)
    curve_world.reset()
    banded = []
    for images in frames:
        out = {}
        for cam, image in images.items():
            det = make_detector("hough", cameras[cam])
            out[cam] = _with_dark_band(image, det)
        banded.append(out)
    return frames + banded, cameras


def _with_dark_band(image: np.ndarray, detector) -> np.ndarray:
    """The image with a 2 m wide, vehicle-dark band across the middle of the ROI's rows."""
    view, scale = detector.view, detector.config.preprocess.scale
    px_per_m = detector.vehicles.px_per_m
    row = int(0.6 * len(px_per_m))
    half_cols = int(1.0 * px_per_m[row] / scale)
    centre_row = view.crop_top + int(row / scale)
    centre_col = image.shape[1] // 2
    out = image.copy()
    out[centre_row - 6 : centre_row + 6, centre_col - half_cols : centre_col + half_cols] = 4
    return out


def _same_region(a, b) -> bool:
    same = np.array_equal(a.rgb, b.rgb) and np.array_equal(a.grey, b.grey)
    if a.covered is None or b.covered is None:
        return same and a.covered is None and b.covered is None
    return same and np.array_equal(a.covered, b.covered)


def _same_estimate(a, b) -> bool:
    for f in fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if f.name == "image_points":
            if set(x) != set(y) or not all(np.array_equal(x[k], y[k]) for k in x):
                return False
        elif f.name == "others":
            if len(x) != len(y) or not all(np.array_equal(u, v) for u, v in zip(x, y, strict=True)):
                return False
        elif isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            if x is None or y is None or not np.array_equal(x, y):
                return False
        elif x != y:
            return False
    return True


def _detectors(cameras, memo):
    """hough and sliding_window on both cameras, all sharing `memo` (None: none shares)."""
    out = {}
    for cam in ("front", "rear"):
        for name in MODELS:
            det = make_detector(name, cameras[cam])
            det.rois = memo
            out[name, cam] = det
    return out


def _count_regions(monkeypatch) -> list:
    """The frames `region_of_interest` is computed for from now on (it still computes)."""
    calls = []
    fresh = image_stage.region_of_interest

    def counted(*args, **kwargs):
        calls.append(args[0])
        return fresh(*args, **kwargs)

    monkeypatch.setattr(image_stage, "region_of_interest", counted)
    return calls


def test_the_band_gives_the_vehicle_cue_something_to_hide(scene):
    """The banded frames exercise the shared vehicle mask (else the tests below hold less)."""
    frames, cameras = scene
    det = make_detector("hough", cameras["front"])
    plain = region_of_interest(frames[0]["front"], det.view, det.config.preprocess, det.vehicles)
    banded = region_of_interest(frames[3]["front"], det.view, det.config.preprocess,
                                det.vehicles)
    assert banded.covered.sum() > plain.covered.sum() + 1000


def test_a_remembered_region_equals_a_fresh_one_and_is_computed_once(scene, monkeypatch):
    frames, cameras = scene
    fresh = image_stage.region_of_interest
    calls = _count_regions(monkeypatch)
    memo = RoiMemo()
    for images in frames:
        for cam, frame in images.items():
            det = make_detector("sliding_window", cameras[cam])
            view, pre, veh = det.view, det.config.preprocess, det.vehicles
            first = memo.get(frame, view, pre, veh)
            assert memo.get(frame, view, pre, veh) is first  # the second model's call
            assert _same_region(first, fresh(frame, view, pre, veh))
            for array in (first.rgb, first.grey, first.covered):
                assert not array.flags.writeable  # shared: no model may write into it
    assert len(calls) == 2 * len(frames)  # once per frame and camera


def test_models_that_share_give_the_estimates_of_models_that_do_not(scene):
    """Both models on both cameras, frame after frame (the sliding window keeps its fit
    between frames): sharing one memo changes no estimate."""
    frames, cameras = scene
    alone, shared = _detectors(cameras, None), _detectors(cameras, RoiMemo())
    valid = 0
    for images in frames * 2:
        images = {cam: frame.copy() for cam, frame in images.items()}  # new objects per step
        for key, det in alone.items():
            a = det.detect(images[key[1]])
            b = shared[key].detect(images[key[1]])
            assert _same_estimate(a, b), key
            valid += a.valid
    assert valid > len(frames) * 2  # the comparison is of real lanes, not of failures


def test_a_frame_changed_in_place_is_computed_afresh(scene):
    frames, cameras = scene
    det = make_detector("hough", cameras["front"])
    view, pre, veh = det.view, det.config.preprocess, det.vehicles
    memo = RoiMemo()
    frame = frames[0]["front"].copy()
    before = memo.get(frame, view, pre, veh)
    frame[: view.crop_top] = 255  # rows the region does not read: it still holds
    assert memo.get(frame, view, pre, veh) is before
    frame[...] = frames[3]["front"]  # the same object, now with a vehicle in its ROI
    after = memo.get(frame, view, pre, veh)
    assert _same_region(after, region_of_interest(frame, view, pre, veh))
    assert not _same_region(after, before)
    frame[-1, -1] ^= 1  # one pixel of one channel
    last = memo.get(frame, view, pre, veh)
    assert last is not after
    assert _same_region(last, region_of_interest(frame, view, pre, veh))


def test_another_frame_or_image_stage_gets_its_own_region(scene):
    frames, cameras = scene
    memo = RoiMemo()
    det = make_detector("hough", cameras["front"])
    view, pre, veh = det.view, det.config.preprocess, det.vehicles
    frame = frames[1]["front"]
    copy = frame.copy()
    assert memo.get(copy, view, pre, veh) is not memo.get(frame, view, pre, veh)
    darker = replace(pre, vehicle_dark_ratio=0.5)
    others = [
        (replace(view, crop_top=view.crop_top + 10), pre, veh),  # another crop
        (view, replace(pre, destreak_width_px=0.0), veh),  # no destreaking
        (view, darker, VehicleFilter.of(view, darker)),  # another vehicle cue
        (view, pre, None),  # no vehicle cue
    ]
    for other_view, other_pre, other_veh in others:
        got = memo.get(frame, other_view, other_pre, other_veh)
        assert _same_region(got, region_of_interest(frame, other_view, other_pre, other_veh))
        assert not _same_region(got, memo.get(frame, view, pre, veh))


def test_two_models_at_once_on_two_threads(scene, monkeypatch):
    """hough and sliding_window started together on each frame (as the loop's two threads may
    run them): their estimates are those of one thread without sharing, and each frame's
    region is computed once."""
    frames, cameras = scene
    calls = _count_regions(monkeypatch)
    alone, shared = _detectors(cameras, None), _detectors(cameras, RoiMemo())
    steps = [{cam: f.copy() for cam, f in images.items()} for images in frames * 3]
    expected = [{name: alone[name, "front"].detect(images["front"]) for name in MODELS}
                for images in steps]
    calls.clear()
    got = [{} for _ in steps]
    start = threading.Barrier(2)
    errors = []

    def run(name):
        try:
            for i, images in enumerate(steps):
                start.wait()
                got[i][name] = shared[name, "front"].detect(images["front"])
        except Exception as err:  # noqa: BLE001 - reported below
            errors.append(err)
            start.abort()

    threads = [threading.Thread(target=run, args=(name,)) for name in MODELS]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for want, have in zip(expected, got, strict=True):
        for name in MODELS:
            assert _same_estimate(want[name], have[name]), name
    assert len(calls) == len(steps)  # one region per frame, whichever thread made it


def test_the_memo_keeps_only_its_latest_frames(scene):
    frames, cameras = scene
    det = make_detector("hough", cameras["front"])
    memo = RoiMemo(slots=2)
    frame = frames[0]["front"].copy()
    gone = weakref.ref(frame)
    memo.get(frame, det.view, det.config.preprocess, det.vehicles)
    del frame
    assert gone() is not None  # remembered: its identity cannot pass to another frame
    for images in frames[1:3]:
        memo.get(images["front"], det.view, det.config.preprocess, det.vehicles)
    assert gone() is None  # two newer frames pushed it out
