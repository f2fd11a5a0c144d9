"""LaneNet from the command line: the registry makes it (lazily, from a given weights file),
`--weights` reaches every command that takes a detector, a bad file is one error line and exit 2
before any output, and `detect` reports every boundary (TuSimple lanes, JSON, overlays).

Weights here are untrained networks saved to tmp_path: these tests prove the plumbing, not the
detection quality (tests/detectors/test_lanenet.py and `lanekeep eval` measure that).
"""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys

import cv2
import numpy as np
import pytest
import torch
from cli.error_lines import one_error_line  # tests/ is on sys.path

from lanekeep.cli.main import main
from lanekeep.detectors.lanenet import LaneNetDetector, WeightsError, save_weights
from lanekeep.detectors.lanenet_decode import Boundary
from lanekeep.detectors.lanenet_model import LaneNet, LaneNetConfig
from lanekeep.detectors.registry import (
    check_detectors_weights,
    detector_weights,
    known_detectors,
    make_detector,
)
from lanekeep.detectors.tusimple import ABSENT, boundary_lanes, h_samples_for
from lanekeep.geometry.camera_model import CameraModel

W, H = 1280, 720
SMALL = LaneNetConfig(width=160, height=88, channels=(8, 16, 16), hidden=8, head=16)
OTHER = dataclasses.replace(SMALL, channels=(8, 16, 24))  # same format, other shapes


def _camera(pitch_deg: float = -2.0) -> CameraModel:
    f = (H / 2.0) / math.tan(math.radians(50.0) / 2.0)
    K = np.array([[f, 0, (W - 1) / 2.0], [0, f, (H - 1) / 2.0], [0, 0, 1]])  # noqa: N806
    return CameraModel.from_mounting("front", K, W, H, 1.4, math.radians(pitch_deg), 1.0)


@pytest.fixture(scope="module")
def weights(tmp_path_factory) -> str:
    """An untrained small LaneNet (seeded) whose objectness bias makes every cell a proposal,
    so that the decoding fits boundaries whatever the random initialisation gives."""
    torch.manual_seed(0)
    model = LaneNet(SMALL)
    per_row = 3 + SMALL.n_slots  # head channels per sub-row: objectness first
    with torch.no_grad():
        for j in range(SMALL.rows_per_cell):
            model.head[-1].bias[j * per_row] = 20.0
    path = tmp_path_factory.mktemp("weights") / "small.pt"
    save_weights(model, path)
    return str(path)


def _bad_weights(tmp_path, case: str) -> str:
    path = tmp_path / f"{case.replace(' ', '_')}.pt"
    if case == "empty":
        path.write_bytes(b"")
    elif case == "garbage":
        path.write_bytes(bytes(range(256)) * 8)
    elif case == "other architecture":  # the config says SMALL, the tensors are OTHER's
        blob = {"format": "lanekeep-lanenet/1", "config": SMALL.to_dict(),
                "state_dict": LaneNet(OTHER).state_dict(), "meta": {}}
        torch.save(blob, str(path))
    elif case == "not lanenet":  # a readable torch file of something else
        torch.save({"w": torch.zeros(3)}, str(path))
    return str(path)  # "missing": never written


BAD = ["missing", "empty", "garbage", "other architecture", "not lanenet"]


# --- The registry ---------------------------------------------------------------------------


def test_importing_the_registry_does_not_import_torch():
    """LaneNet is registered lazily: classical-only commands must not pay torch's ~1 s."""
    code = ("import sys, detectors.registry as r; "
            "assert 'lanenet' in r.known_detectors(); "
            "assert 'torch' not in sys.modules, 'torch imported'")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr


def test_registry_makes_lanenet_from_a_weights_file(weights):
    assert "lanenet" in known_detectors()
    detector = make_detector("lanenet", _camera(), weights=weights)
    assert isinstance(detector, LaneNetDetector)
    assert detector.weights_path == weights and detector.model.config == SMALL
    estimate = detector.detect(np.zeros((H, W, 3), np.uint8))
    assert estimate.x_m == detector.x_ref
    with detector_weights(weights):  # the scope an episode is built in
        assert make_detector("lanenet", _camera()).weights_path == weights
    # Classical detectors take no weights: the same call is theirs unchanged.
    assert make_detector("hough", _camera(), weights=weights).name == "hough"


def test_without_weights_lanenet_loads_its_configured_file_or_names_it(tmp_path):
    from lanekeep.detectors.config import load_config

    missing = tmp_path / "nowhere" / "lanenet.pt"
    config_file = tmp_path / "detectors.toml"
    config_file.write_text(f"[lanenet]\nweights = {json.dumps(str(missing))}\n")
    config = load_config(config_file)
    with pytest.raises(WeightsError, match="no such weights file") as caught:
        make_detector("lanenet", _camera(), config)
    assert str(caught.value).startswith(f"{missing}: ")
    with pytest.raises(WeightsError, match=str(missing)):
        check_detectors_weights(["hough", "lanenet"], config)
    assert check_detectors_weights(["hough", "sliding_window"], config) == []


@pytest.mark.parametrize("case", BAD)
def test_a_bad_file_is_one_weights_error_naming_it(tmp_path, case):
    path = _bad_weights(tmp_path, case)
    with pytest.raises(WeightsError) as caught:
        check_detectors_weights(["hough"], None, path)  # given: checked even if unused
    assert str(caught.value).startswith(f"{path}: ")


# --- Every boundary as TuSimple lanes -------------------------------------------------------


def _image_boundary(slot: int, slope: float, horizon: float) -> Boundary:
    """A straight boundary through the vanishing point (W/2, horizon): u = cx + slope * d,
    seen only between rows 500 and 600."""
    v = np.arange(500.0, 601.0, 10.0)
    pts = np.stack([(W - 1) / 2.0 + slope * (v - horizon), v], -1)
    return Boundary(slot=slot, coeffs=np.array([(W - 1) / 2.0, slope, 0.0]), frame="image",
                    points_px=pts, score=0.9, horizon_row=horizon)


def test_boundary_lanes_extends_orders_and_clips():
    horizon = 360.0
    rows = h_samples_for(H)
    found = [_image_boundary(1, 1.2, horizon), _image_boundary(0, -1.2, horizon),
             _image_boundary(2, -3.0, horizon)]  # next-left leaves through the left side
    lanes = boundary_lanes(found, None, rows, (W, H), horizon)
    assert [lane.name for lane in lanes] == ["next-left", "ego-left", "ego-right"]
    ego_left = dict(zip(rows, lanes[1].xs, strict=True))
    assert ego_left[710] == round(639.5 - 1.2 * 350)  # extended below the points (500-600)
    assert ego_left[390] == round(639.5 - 1.2 * 30)  # and up to near the horizon ...
    assert ego_left[380] == ABSENT and ego_left[160] == ABSENT  # ... not to it or above
    next_left = dict(zip(rows, lanes[0].xs, strict=True))
    assert next_left[710] == ABSENT  # off the image on the left
    assert next_left[500] == round(639.5 - 3.0 * 140)
    assert all(len(lane.xs) == len(rows) for lane in lanes)


def test_a_ground_boundary_is_drawn_where_the_camera_sees_it():
    camera = _camera()
    x = np.linspace(8.0, 20.0, 12)
    xy = np.stack([x, np.full_like(x, 1.85)], -1)
    uv, ok = camera.project_ground(xy)
    b = Boundary(slot=0, coeffs=np.array([1.85, 0.0, 0.0]), frame="ground", points_px=uv[ok],
                 score=0.8, points_xy=xy[ok])
    horizon = camera.cy + camera.fy * math.tan(math.radians(2.0))
    (lane,) = boundary_lanes([b], camera, h_samples_for(H), (W, H), horizon)
    drawn = [(u, v) for u, v in zip(lane.xs, h_samples_for(H), strict=True) if u != ABSENT]
    assert max(v for _, v in drawn) == 710  # extended to the bottom (points from 8 m only)
    ground, ok = camera.pixels_to_ground(np.array(drawn, dtype=float))
    assert ok.all()
    np.testing.assert_allclose(ground[:, 1], 1.85, atol=0.05)  # every point on y = 1.85 m


# --- `lanekeep detect` ----------------------------------------------------------------------


def _road_png(tmp_path) -> str:
    """A flat road seen by the default dashcam (as tests/realcam/test_detect_cli.py draws it)."""
    image = np.full((H, W, 3), (95, 95, 95), np.uint8)
    image[:360] = (200, 170, 120)
    f = 640.0 / np.tan(np.radians(30.0))
    for y_lane in (5.55, 1.85, -1.85, -5.55):
        for x in np.arange(5.0, 80.0, 0.05):
            v, u = 359.5 + f * 1.5 / x, 639.5 - f * y_lane / x
            if 0 <= u < W and v < H:
                cv2.circle(image, (int(u), int(v)), max(1, int(f * 0.075 / x)), (240,) * 3, -1)
    path = tmp_path / "road.png"
    cv2.imwrite(str(path), image)
    return str(path)


def test_detect_lanenet_tusimple_and_json_report_every_boundary(tmp_path, capsys, weights):
    png = _road_png(tmp_path)
    code = main(["detect", "--detector", "lanenet", "--weights", weights, png, png,
                 "--format", "tusimple"])
    out, err = capsys.readouterr()
    assert code == 0, err
    records = [json.loads(line) for line in out.strip().splitlines()]
    assert len(records) == 2 and records[0]["raw_file"] == png
    assert records[0]["h_samples"] == list(range(160, 720, 10))
    assert records[0]["lanes"]
    for lane in records[0]["lanes"]:
        assert len(lane) == len(records[0]["h_samples"])
        assert all(x == ABSENT or 0 <= x < W for x in lane)
        assert any(x != ABSENT for x in lane)
    assert records[0]["lanes"] == records[1]["lanes"]  # a fresh detector per photo
    code = main(["detect", "--detector", "lanenet", "--weights", weights, png])
    (doc,) = [json.loads(line) for line in capsys.readouterr().out.strip().splitlines()]
    assert code == 0
    assert [b["xs"] for b in doc["boundaries"]] == records[0]["lanes"]
    assert all(b["slot"] in ("ego-left", "ego-right", "next-left", "next-right", "other")
               for b in doc["boundaries"])


def test_overlay_draws_each_boundary_in_its_colour():
    from lanekeep.cli.detect import SLOT_COLOURS, _overlay
    from lanekeep.detectors.base import LaneEstimate

    rows = h_samples_for(H)
    lanes = [("ego-left", [300] * len(rows)), ("ego-right", [900] * len(rows)),
             ("other", [1100] * len(rows))]
    out = _overlay(np.zeros((H, W, 3), np.uint8), LaneEstimate.invalid("test", x_m=5.0), lanes,
                   rows, 300.0)
    assert tuple(out[400, 300]) == SLOT_COLOURS["ego-left"]
    assert tuple(out[400, 900]) == SLOT_COLOURS["ego-right"]
    other = tuple(out[400, 1100])
    assert other not in SLOT_COLOURS.values() and other != (0, 0, 0)


@pytest.mark.parametrize("case", BAD)
def test_detect_rejects_a_bad_weights_file_before_any_output(tmp_path, capsys, case):
    png = _road_png(tmp_path)
    path = _bad_weights(tmp_path, case)
    code = main(["detect", "--detector", "lanenet", "--weights", path, png,
                 "--overlay", str(tmp_path / "ov")])
    one_error_line(capsys, code, start=f"lanekeep detect: error: {path}: ")
    assert not (tmp_path / "ov").exists()


# --- `lanekeep run`, `bench`, `perf` --------------------------------------------------------


@pytest.mark.parametrize("case", BAD)
def test_run_rejects_a_bad_weights_file_before_any_output(tmp_path, capsys, case):
    path = _bad_weights(tmp_path, case)
    out = tmp_path / "out.json"
    code = main(["run", "clear_straight", "--seconds", "1", "--weights", path,
                 "--json", str(out), "--record", str(tmp_path / "out.rrd")])
    one_error_line(capsys, code, start=f"lanekeep run: error: {path}: ")
    assert not out.exists() and not (tmp_path / "out.rrd").exists()


def test_run_checks_the_weights_a_detectors_table_names_before_any_output(tmp_path, capsys):
    """`--detectors-config` with `[lanenet] weights = "..."`: the up-front check loads that
    file, not the shipped one (until 2026-11-29 it checked the shipped file, and a missing
    configured one failed only when the episode built its detectors)."""
    missing = tmp_path / "nowhere" / "lanenet.pt"
    config_file = tmp_path / "detectors.toml"
    config_file.write_text(f"[lanenet]\nweights = {json.dumps(str(missing))}\n")
    out = tmp_path / "out.json"
    code = main(["run", "clear_straight", "--seconds", "1", "--detectors-config",
                 str(config_file), "--json", str(out)])
    one_error_line(capsys, code, start=f"lanekeep run: error: {missing}: no such weights file")
    assert not out.exists()


def test_bench_and_perf_reject_a_bad_weights_file(tmp_path, capsys):
    path = _bad_weights(tmp_path, "garbage")
    code = main(["bench", "clear_straight", "--seconds", "1", "--workers", "1",
                 "--weights", path, "--json", str(tmp_path / "bench.json")])
    one_error_line(capsys, code, start=f"lanekeep bench: error: {path}: ")
    code = main(["perf", "--weights", path, "--json", str(tmp_path / "perf.json")])
    one_error_line(capsys, code, start=f"lanekeep perf: error: {path}: ")
    assert not list(tmp_path.glob("*.json"))


def test_the_episode_builds_lanenet_from_the_scoped_weights(weights):
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario

    scenario = load_scenario("clear_straight")
    scenario = dataclasses.replace(scenario, estimation=dataclasses.replace(
        scenario.estimation, front_detectors=("hough", "lanenet")))
    with detector_weights(weights), Episode(scenario, render_size=(320, 180)) as episode:
        assert episode.driver.front["lanenet"].weights_path == weights
        result = episode.step()
    assert "lanenet" in result.estimates


def test_perf_lanenet_timing_or_why_not(tmp_path, weights):
    from lanekeep.loop.perf import format_lanenet, lanenet_inference
    from lanekeep.scenario.schema import load_scenario

    scenario = load_scenario("clear_straight")
    missing = str(tmp_path / "absent.pt")
    gone = lanenet_inference(scenario, missing, frames=3)
    assert gone["ms_median"] is None and gone["unavailable"].startswith(f"{missing}: ")
    assert format_lanenet(gone) == [f"LaneNet inference: unavailable ({gone['unavailable']})"]
    timed = lanenet_inference(scenario, weights, frames=3, size=(640, 360))
    assert timed["unavailable"] is None and timed["weights"] == weights
    assert 0.0 < timed["ms_median"] <= timed["ms_p90"]
    assert "ms median" in format_lanenet(timed)[0]
