"""The rerun recording: it verifies, reads back with rerun's own reader, lines up with the images,
stores its blueprint and scenario, survives Ctrl-C, and costs nothing when off."""

import dataclasses
import math
import os
import signal
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

import lanekeep  # noqa: F401 - EGL before mujoco
from lanekeep.core.signals import VehicleSignals
from lanekeep.detectors.base import LaneEstimate
from lanekeep.report.blueprint import blueprint, has_other_vehicles
from lanekeep.report.record import TTC_PLOT_MAX_S, EpisodeInfo, RerunRecorder
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring.metrics import ADE_POINTS_M
from lanekeep.scoring.safety import Footprint, StepSafety
from lanekeep.scoring.step_truth import step_truth
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.world.build import build

BIN = Path(sys.executable).parent
MODELS = ("hough", "sliding_window")


# -- reading a recording back -------------------------------------------------------------------
def verify(path: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(BIN / "rerun"), "rrd", "verify", str(path)],
                          capture_output=True, text=True, timeout=120)


def read_back(path: Path) -> dict[str, dict[str, list]]:
    """entity -> column -> [(step, value)] for every row, or [(None, value)] when static."""
    import rerun as rr

    out: dict[str, dict[str, list]] = defaultdict(lambda: defaultdict(list))
    for chunk in rr.chunk.RrdReader(path).stream():
        batch = chunk.to_record_batch()
        names = batch.schema.names
        steps = (batch.column("step").to_pylist() if "step" in names
                 else [None] * batch.num_rows)
        for name in names:
            if ":" in name or chunk.entity_path.startswith("/__properties/"):
                for step, value in zip(steps, batch.column(name).to_pylist(), strict=True):
                    if value is not None:
                        out[chunk.entity_path][name].append((step, value))
    return out


def steps_of(data, entity: str, column: str) -> list:
    return sorted(step for step, _ in data[entity][column])


def value_at(data, entity: str, column: str, step):
    (value,) = [v for s, v in data[entity][column] if s == step]
    return value


def texts(data) -> list[str]:
    return [v[0] for _, v in data["/events"]["TextLog:text"]]


def marking_distance_px(mask: np.ndarray, strips: list) -> float:
    """Median distance (px) from the strips' points inside the image to the nearest marking."""
    distance = cv2.distanceTransform((~mask).astype(np.uint8), cv2.DIST_L2, 3)
    points = np.concatenate([np.asarray(s, dtype=float) for s in strips if len(s)])
    h, w = mask.shape
    inside = ((points[:, 0] >= 0) & (points[:, 0] < w) & (points[:, 1] >= 0)
              & (points[:, 1] < h))
    uv = points[inside].astype(int)
    assert len(uv) > 10
    return float(np.median(distance[uv[:, 1], uv[:, 0]]))


# -- a small fake episode that feeds the recorder synthetic steps --------------------------------
@pytest.fixture(scope="module")
def fake():
    scenario = load_scenario("clear_curve")
    world = build(scenario)
    rig = CameraRig(world.model, RenderSettings(320, 180))
    frames = {n: rig.render_rgb(world.data, n) for n in rig.CAMERA_NAMES}
    marking = world.marking_mask(rig.render_segmentation(world.data, "front"))
    geometry = world.car.geometry
    info = EpisodeInfo(world.road, dict(rig.cameras), list(MODELS), 0.1,
                       (geometry.length_m, geometry.width_m))
    yield SimpleNamespace(scenario=scenario, info=info, world=world, frames=frames,
                          marking=marking)
    rig.close()


def make_step(fake, index: int, **changes) -> SimpleNamespace:
    half = fake.scenario.road.lane_width_m / 2
    pose = fake.scenario.start_pose(fake.world.road)
    estimate = LaneEstimate(True, 0.05, 6.0, np.array([half, 0.0, 0.0]),
                            np.array([-half, 0.0, 0.0]), 0.9,
                            {"left": np.array([[100.0, 170.0], [140.0, 120.0]])})
    step = dict(
        index=index, time_s=0.1 * (index + 1), frames=fake.frames,
        estimates={"hough": estimate, "sliding_window": estimate, "reference": estimate},
        tracked={m: np.zeros(3) for m in MODELS}, probabilities=np.array([0.7, 0.3]),
        track_offsets_m={m: 0.05 for m in MODELS},
        selected=0, output_offset_m=0.05, output_x_m=4.0, output_centre=np.zeros(3),
        reference_m=0.04, reference_x_m=6.0, mmae_residuals_m=np.array([-0.01, np.nan]),
        reference_repaired=False, steer=0.01, throttle=0.2,
        truth=step_truth(fake.world.road, fake.scenario.road.ego_lane, pose, pose, [6.0, 4.0],
                         np.asarray(ADE_POINTS_M), drawn_lookaheads_m=(0.0, 4.0)),
        pose=fake.scenario.start_pose(fake.world.road),
        sensed_pose=fake.scenario.start_pose(fake.world.road), speed_mps=15.0,
        signals=VehicleSignals(15.0, 0.0, 0.0, 0.0, 0.0),
        events=[], tracker_status=dict.fromkeys(MODELS, "updated"),
    )
    step.update(changes)
    return SimpleNamespace(**step)


def record(fake, path: Path, steps: list, **kwargs) -> Path:
    with RerunRecorder(path, fake.scenario, **kwargs) as recorder:
        recorder.start(fake.info)
        for step in steps:
            recorder.log_step(step)
    return path


def test_recording_verifies_and_holds_one_image_per_camera_per_recorded_step(fake, tmp_path):
    path = record(fake, tmp_path / "x.rrd", [make_step(fake, i) for i in range(7)], every=3)
    result = verify(path)
    assert result.returncode == 0, result.stderr
    data = read_back(path)
    for cam in ("front", "rear"):
        assert steps_of(data, f"/cameras/{cam}/image", "EncodedImage:blob") == [0, 3, 6]
        assert value_at(data, f"/cameras/{cam}/image", "EncodedImage:media_type",
                        3) == ["image/jpeg"]
        assert steps_of(data, f"/cameras/{cam}/lanes/truth", "LineStrips2D:strips") == [0, 3, 6]
    for model in MODELS:
        assert len(data[f"/cameras/front/lanes/{model}/boundaries"]["LineStrips2D:strips"]) == 3
        assert steps_of(data, f"/plots/probability/{model}", "Scalars:scalars") == list(range(7))
    # the MMAE's residuals: a model it did not compare (NaN) has none
    assert steps_of(data, "/plots/residual/hough", "Scalars:scalars") == list(range(7))
    # plotted in cm: the step's residual was -0.01 m
    assert value_at(data, "/plots/residual/hough", "Scalars:scalars", 3) == [pytest.approx(-1.0)]
    assert not steps_of(data, "/plots/residual/sliding_window", "Scalars:scalars")
    assert len(data["/cameras/front/lanes/hough/points"]["Points2D:positions"]) == 3
    assert len(data["/cameras/rear/lanes/reference/boundaries"]["LineStrips2D:strips"]) == 3
    for entity in ("/plots/offset/truth", "/plots/offset/fused", "/plots/error/hough",
                   "/plots/speed/speed_mps"):
        assert steps_of(data, entity, "Scalars:scalars") == list(range(7))
    assert steps_of(data, "/world/car", "Transform3D:translation") == [0, 3, 6]
    assert len(value_at(data, "/world/path", "LineStrips3D:strips", 6)[0]) == 7
    road = value_at(data, "/world/road/boundaries", "LineStrips3D:strips", None)
    assert len(road) == fake.scenario.road.n_lanes + 1
    assert not data["/cameras/front/segmentation"]  # an optional layer, off by default
    # a model's offset error is the estimate minus the true offset at its look-ahead
    (offset,) = value_at(data, "/plots/offset/hough", "Scalars:scalars", 0)
    (error,) = value_at(data, "/plots/error/hough", "Scalars:scalars", 0)
    (truth,) = value_at(data, "/plots/offset/truth", "Scalars:scalars", 0)
    assert offset == pytest.approx(5.0) and error == pytest.approx(offset - truth)  # cm
    # steer and throttle in % of [-1, 1]; the colour key names every source once
    assert value_at(data, "/plots/steer/steer_pct", "Scalars:scalars", 0) == [pytest.approx(1.0)]
    assert value_at(data, "/plots/throttle/throttle_pct", "Scalars:scalars",
                    0) == [pytest.approx(20.0)]
    labels = value_at(data, "/key", "Points2D:labels", None)
    assert sorted(labels) == sorted(["truth", "fused", "reference", *MODELS])


def test_ground_truth_overlay_lies_on_the_rendered_markings(fake, tmp_path):
    """Truth is drawn from the pose the frames were taken from (`sensed_pose`). Step 1 claims
    its frames came from a pose 1.5 m off, so its truth, drawn on the same start-pose frame,
    must miss the markings: the check can tell right from wrong."""
    x, y, yaw = fake.scenario.start_pose(fake.world.road)
    moved = (x - 1.5 * np.sin(yaw), y + 1.5 * np.cos(yaw), yaw + 0.03)
    steps = [make_step(fake, 0, pose=moved), make_step(fake, 1, pose=moved, sensed_pose=moved)]
    data = read_back(record(fake, tmp_path / "x.rrd", steps))
    strips = {s: value_at(data, "/cameras/front/lanes/truth", "LineStrips2D:strips", s)
              for s in (0, 1)}
    assert marking_distance_px(fake.marking, strips[0]) < 1.5
    assert marking_distance_px(fake.marking, strips[1]) > 4.0


def test_blueprint_is_stored_with_the_recording(fake, tmp_path):
    import rerun as rr

    reader = rr.chunk.RrdReader(record(fake, tmp_path / "x.rrd", [make_step(fake, 0)]))
    (blueprint,) = reader.blueprints()
    assert blueprint.application_id == reader.recordings()[0].application_id == "lanekeep"
    views = {}
    for chunk in reader.stream(store=blueprint):
        batch = chunk.to_record_batch()
        if "ViewBlueprint:display_name" in batch.schema.names:
            row = {n: batch.column(n).to_pylist()[0][0] for n in batch.schema.names
                   if n.startswith("ViewBlueprint:")}
            views[row["ViewBlueprint:display_name"]] = (row["ViewBlueprint:class_identifier"],
                                                        row["ViewBlueprint:space_origin"])
    assert views["front camera"] == ("2D", "cameras/front")
    assert views["rear camera"] == ("2D", "cameras/rear")
    assert views["offsets (cm, + = car left)"] == ("TimeSeries", "plots/offset")
    assert views["errors (cm, estimate - truth)"] == ("TimeSeries", "plots/error")
    assert views["MMAE probabilities"] == ("TimeSeries", "plots/probability")
    assert views["MMAE residuals (cm, reference - model)"] == ("TimeSeries", "plots/residual")
    assert views["follow view (3D)"] == ("3D", "world")
    assert views["road map (north up)"] == ("2D", "map")
    assert views["colour key"] == ("2D", "key")
    # one unit per plot: the car's offset, steer, throttle and speed each in their own
    assert views["car: offset from the lane centre (cm)"] == ("TimeSeries", "plots/car")
    assert views["steer (% of full lock, + = left)"] == ("TimeSeries", "plots/steer")
    assert views["throttle (%, - = brake)"] == ("TimeSeries", "plots/throttle")
    assert views["speed (m/s)"] == ("TimeSeries", "plots/speed")
    assert views["events"] == ("TextLog", "events")


def test_scenario_and_events_are_logged(fake, tmp_path):
    gone = LaneEstimate.invalid("no paint")
    base = make_step(fake, 0).estimates
    steps = [
        make_step(fake, 0),
        make_step(fake, 1, tracker_status={"hough": "gated", "sliding_window": "updated"}),
        make_step(fake, 2, selected=1, probabilities=np.array([0.2, 0.8]),
                  estimates={**base, "sliding_window": gone},
                  events=["lane departure: a wheel crossed a lane boundary"]),
    ]
    data = read_back(record(fake, tmp_path / "x.rrd", steps))
    logged = texts(data)
    assert "tracker hough: measurement gated" in logged
    assert "model switch: hough -> sliding_window (p = 0.80)" in logged
    assert "detector sliding_window: lane lost (no paint)" in logged
    assert "lane departure: a wheel crossed a lane boundary" in logged
    assert len(logged) == 4
    # a lost lane clears its overlay instead of leaving the last one on screen
    assert data["/cameras/front/lanes/sliding_window"]["Clear:is_recursive"] == [(2, [True])]
    (document,) = [v for _, v in data["/scenario"]["TextDocument:text"]]
    toml = Path(fake.scenario.source).read_text(encoding="utf-8")
    assert toml in document[0] and f"--seed {fake.scenario.seed}" in document[0]
    # and machine-readable, as a recording property
    assert data["/__properties/scenario"]["seed"] == [(None, [fake.scenario.seed])]
    assert data["/__properties/scenario"]["name"] == [(None, ["clear_curve"])]


def test_writer_failure_reaches_the_episode_and_the_file_still_closes(fake, tmp_path):
    recorder = RerunRecorder(tmp_path / "x.rrd", fake.scenario)
    recorder.start(fake.info)
    recorder.log_step(make_step(fake, 0, sensed_pose=None))  # the writer fails on it
    with pytest.raises(RuntimeError, match="recording to .* failed"):
        recorder.close()
    assert verify(tmp_path / "x.rrd").returncode == 0
    recorder.close()  # a second close is a no-op


def test_a_step_before_start_or_a_second_start_is_an_error(fake, tmp_path):
    with RerunRecorder(tmp_path / "x.rrd", fake.scenario) as recorder:
        with pytest.raises(RuntimeError, match="start"):
            recorder.log_step(make_step(fake, 0))
        recorder.start(fake.info)
        with pytest.raises(RuntimeError, match="start"):
            recorder.start(fake.info)


@pytest.mark.parametrize("kwargs", [{"every": 0}, {"jpeg_quality": 0}, {"jpeg_quality": 101}])
def test_bad_settings_raise(fake, tmp_path, kwargs):
    with pytest.raises(ValueError):
        RerunRecorder(tmp_path / "x.rrd", fake.scenario, **kwargs)


# -- real episodes ------------------------------------------------------------------------------
def test_recorded_episode_reads_back_and_lines_up_with_its_segmentation(tmp_path):
    """A real closed-loop episode on a curve, with the optional segmentation layer: the truth
    overlay of each recorded step lies on the marking pixels of that step's own render."""
    from lanekeep.loop.episode import Episode

    scenario = load_scenario("clear_curve")
    path = tmp_path / "curve.rrd"
    recorder = RerunRecorder(path, scenario, every=2, jpeg_quality=60, segmentation=True)
    with Episode(scenario, recorder=recorder, render_size=(640, 360)) as episode:
        report = episode.run(seconds=2.0)
    assert report.completed
    assert verify(path).returncode == 0
    data = read_back(path)
    recorded = list(range(0, 20, 2))
    for cam in ("front", "rear"):
        assert steps_of(data, f"/cameras/{cam}/image", "EncodedImage:blob") == recorded
    assert steps_of(data, "/plots/offset/truth", "Scalars:scalars") == list(range(20))
    for name in (*episode.driver.front, "reference"):
        assert f"/plots/offset/{name}" in data
    # One ground truth: the plotted errors are the ones the report scores.
    errors_cm = [v[0] for _, v in data["/plots/error/fused"]["Scalars:scalars"]]
    rms_cm = float(np.sqrt(np.mean(np.square(errors_cm))))
    assert rms_cm == pytest.approx(report.sources["fused"].rmse_cm, rel=1e-9)
    for step in recorded[1:]:
        mask = np.asarray(value_at(data, "/cameras/front/segmentation",
                                   "SegmentationImage:buffer", step), dtype=np.uint8)
        mask = mask.reshape(360, 640) > 0
        strips = value_at(data, "/cameras/front/lanes/truth", "LineStrips2D:strips", step)
        assert marking_distance_px(mask, strips) < 1.5, step


def test_sigint_leaves_a_verified_recording_and_a_partial_report(tmp_path):
    path = tmp_path / "interrupted.rrd"
    proc = subprocess.Popen(
        [str(BIN / "lanekeep"), "run", "clear_straight", "--seconds", "20", "--record",
         str(path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "MUJOCO_GL": "egl"})
    try:
        deadline = time.monotonic() + 180
        while not (path.exists() and path.stat().st_size > 500_000):  # a few steps written
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.2)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "scenario clear_straight" in out and "RMSE" in out
    assert "interrupted" in err
    result = verify(path)
    assert result.returncode == 0, result.stderr
    images = steps_of(read_back(path), "/cameras/front/image", "EncodedImage:blob")
    assert 1 <= len(images) < 200 and images == list(range(len(images)))


def test_recording_off_does_no_work():
    """With the NullRecorder an episode never imports rerun and never touches its arguments."""
    program = """
import sys
import lanekeep
from lanekeep.loop.episode import Episode
from lanekeep.report.record import NullRecorder
from lanekeep.scenario.schema import load_scenario

class Untouchable:
    def __getattr__(self, name):
        raise AssertionError(f"NullRecorder read .{name}")

NullRecorder().start(Untouchable())
NullRecorder().log_step(Untouchable())
with Episode(load_scenario("clear_straight"), render_size=(320, 180)) as episode:
    assert isinstance(episode.recorder, NullRecorder)
    episode.step()
    episode.step()
assert "rerun" not in sys.modules, "rerun was imported"
print("ok")
"""
    result = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok"


def test_overlays_are_clipped_to_the_image():
    from lanekeep.report.overlay import clip_polyline

    line = np.array([[-50.0, 50.0], [50.0, 50.0], [150.0, 50.0], [150.0, 300.0]])
    (run,) = clip_polyline(line, 100.0, 100.0)
    assert run.min() >= 0.0 and run[:, 0].max() <= 100.0 and run[:, 1].max() <= 100.0
    assert run[0] == pytest.approx([0.0, 50.0]) and run[-1] == pytest.approx([100.0, 50.0])
    assert clip_polyline(np.array([[-5.0, -5.0], [-1.0, 200.0]]), 100.0, 100.0) == []
    # out, in, out, in: two separate runs, none bridging the gap outside
    zigzag = np.array([[-10.0, 10.0], [10.0, 10.0], [10.0, 200.0], [20.0, 20.0]])
    assert len(clip_polyline(zigzag, 100.0, 100.0)) == 2


def test_colours_are_readable_on_light_and_dark_themes():
    """No series may be near-white or near-black (invisible on one of the viewer's themes)."""
    from lanekeep.report.palette import COLOURS, FUSED, SPARE_COLOURS

    for rgb in [*COLOURS.values(), *SPARE_COLOURS]:
        luma = 0.299 * rgb[0] + 0.587 * rgb[1] + 0.114 * rgb[2]
        assert 40 < luma < 200, rgb
    assert len({COLOURS[name] for name in ("hough", "sliding_window", "lanenet", FUSED,
                                           "reference", "truth")}) == 6


def test_map_shows_the_road_the_lane_the_car_and_its_path(fake, tmp_path):
    steps = [make_step(fake, i) for i in range(4)]
    data = read_back(record(fake, tmp_path / "x.rrd", steps, every=3))
    road = value_at(data, "/map/road", "LineStrips2D:strips", None)
    assert len(road) == fake.scenario.road.n_lanes + 1
    assert len(value_at(data, "/map/lane", "LineStrips2D:strips", None)) == 2
    (outline,) = value_at(data, "/map/car", "LineStrips2D:strips", 3)
    assert len(outline) == 5 and np.allclose(outline[0], outline[-1])
    (path,) = value_at(data, "/map/path", "LineStrips2D:strips", 3)
    assert len(path) == 4
    x, y, _ = steps[3].sensed_pose
    assert np.asarray(outline)[:4].mean(axis=0) == pytest.approx([x, -y], abs=1e-3)


def test_gap_ttc_and_the_other_vehicles_are_recorded(fake, tmp_path):
    """Among other vehicles: the gap and TTC to the vehicle ahead each step (a TTC that is not
    closing drawn at the plot's top), the car's acceleration, the vehicles' footprints on the
    map and as boxes, a collision as an error in the events."""
    x, y, yaw = fake.scenario.start_pose(fake.world.road)
    ahead = Footprint("vehicle_1", x + 20.0 * np.cos(yaw), y + 20.0 * np.sin(yaw), yaw, 4.6,
                      1.85)
    safety = [StepSafety(-1.0, "vehicle_1", 15.4, 5.0, 3.08, vehicles=(ahead,)),
              StepSafety(-4.5, "vehicle_1", 15.0, -1.0, math.inf, vehicles=(ahead,)),
              StepSafety(0.0), StepSafety(0.0, collided_with="vehicle_1", vehicles=(ahead,))]
    steps = [make_step(fake, i, safety=s) for i, s in enumerate(safety)]
    steps[3].events.append("collision with vehicle_1 at t = 0.4 s")
    data = read_back(record(fake, tmp_path / "x.rrd", steps))
    assert [v for _, v in sorted(data["/plots/gap/gap_m"]["Scalars:scalars"])] == [[15.4],
                                                                                    [15.0]]
    assert [v for _, v in sorted(data["/plots/ttc/ttc_s"]["Scalars:scalars"])] == [
        pytest.approx([3.08]), [TTC_PLOT_MAX_S]]
    assert steps_of(data, "/plots/accel/accel_mps2", "Scalars:scalars") == [0, 1, 2, 3]
    (outline,) = value_at(data, "/map/vehicles", "LineStrips2D:strips", 0)
    assert np.asarray(outline)[:4].mean(axis=0) == pytest.approx(
        [ahead.x_m, -ahead.y_m], abs=1e-3)
    assert value_at(data, "/map/vehicles", "LineStrips2D:labels", 0) == ["vehicle_1"]
    assert steps_of(data, "/world/vehicles", "Boxes3D:half_sizes") == [0, 1, 3]
    assert "collision with vehicle_1 at t = 0.4 s" in texts(data)


def test_the_layout_shows_the_safety_plots_only_with_other_vehicles():
    def origins(item) -> list[str]:
        if hasattr(item, "origin"):  # a view
            return [str(item.origin)]
        return [o for child in getattr(item, "contents", ()) for o in origins(child)]

    scenario = load_scenario("clear_curve")
    busy = dataclasses.replace(scenario, traffic=dataclasses.replace(scenario.traffic,
                                                                     vehicles_per_km=10.0))
    quiet = dataclasses.replace(
        scenario, traffic=dataclasses.replace(scenario.traffic, vehicles_per_km=0.0),
        conditions=dataclasses.replace(scenario.conditions, vehicles=()))
    assert has_other_vehicles(busy) and not has_other_vehicles(quiet)
    shown = origins(blueprint(busy).root_container)
    assert {"plots/gap", "plots/ttc", "plots/accel", "plots/speed"} <= set(shown)
    assert not {"plots/gap", "plots/ttc"} & set(origins(blueprint(quiet).root_container))


@pytest.mark.parametrize("content", [None, b"", b"not a recording"])
def test_view_rejects_a_missing_or_garbage_file_in_one_line(tmp_path, capsys, content):
    from lanekeep.cli.main import main

    path = tmp_path / "x.rrd"
    if content is not None:
        path.write_bytes(content)
    assert main(["view", str(path), "--web"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "Traceback" not in err[0]


def test_view_url_is_bound_to_localhost_and_asks_for_webgl():
    from lanekeep.cli.view import web_url

    # WebGL: the default WebGPU renderer crashed in a browser with software GL.
    assert web_url(9090, 9876) == ("http://127.0.0.1:9090/?url=rerun%2Bhttp%3A%2F%2F"
                                   "127.0.0.1%3A9876%2Fproxy&renderer=webgl")


def test_the_other_lanes_lines_a_detector_reports_are_drawn_and_cleared(fake, tmp_path):
    """A detector's `others` (the neighbouring lanes' lines) go to `.../others`, drawn on the
    steps that have them and cleared on a step without them."""
    half = fake.scenario.road.lane_width_m / 2
    plain = make_step(fake, 0).estimates["hough"]
    with_others = dataclasses.replace(plain, others=(np.array([3 * half, 0.0, 0.0]),
                                                     np.array([-3 * half, 0.0, 0.0])))
    steps = [make_step(fake, i, estimates={**make_step(fake, i).estimates, "hough": e})
             for i, e in enumerate((with_others, plain, with_others))]
    data = read_back(record(fake, tmp_path / "o.rrd", steps))
    entity = "/cameras/front/lanes/hough/others"
    assert steps_of(data, entity, "LineStrips2D:strips") == [0, 2]
    assert len(value_at(data, entity, "LineStrips2D:strips", 0)) >= 2
    cleared = [c for c in data[entity] if c.startswith("Clear")]
    assert cleared and [s for c in cleared for s, _ in data[entity][c]] == [1]
    assert not data["/cameras/front/lanes/sliding_window/others"]  # it reported none
