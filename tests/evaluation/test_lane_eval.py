"""`lanekeep eval`: the metrics on synthetic frames with known answers, the occluders, the test
sets' seeds and forced conditions, and the command (strict JSON, bad input -> exit 2)."""

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from lanekeep.cli.main import main
from lanekeep.detectors.base import LaneEstimate
from lanekeep.evaluation.dataset import LABEL_ROWS, DatasetRecipe, world_seed
from lanekeep.evaluation.eval_sets import (
    CONDITIONS,
    OVERSHOOT,
    EvalRecipe,
    condition_scenario,
    condition_seed,
    occlude,
    occlusion_share,
    readable,
)
from lanekeep.evaluation.lane_metrics import (
    FramePrediction,
    Tally,
    average_precision,
    cell_boxes,
    estimate_prediction,
    eval_grid,
    gt_boxes,
    lane_iou_matrix,
    match_boxes,
    match_lanes,
    x_at_rows,
)
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.scoring.metrics import ADE_POINTS_M

W, H = 1280, 720
LANES_Y = (1.8, -1.8, 5.4, -5.4)  # ego-left, ego-right, next-left, next-right (m)


def _camera() -> CameraModel:
    f = (W / 2.0) / math.tan(math.radians(45.0))
    k = np.array([[f, 0, (W - 1) / 2.0], [0, f, (H - 1) / 2.0], [0, 0, 1]])
    return CameraModel.from_mounting("front", k, W, H, 1.5, math.radians(-6.0), 1.0)


def _truth(camera: CameraModel):
    """Labels of straight boundaries at LANES_Y, as the dataset stores them."""
    xs = np.full((6, len(LABEL_ROWS)), np.nan, np.float32)
    ground_y = np.full((6, len(ADE_POINTS_M)), np.nan, np.float32)
    slots = np.full(6, -1, np.int8)
    for b, y in enumerate(LANES_Y):
        xs[b] = x_at_rows(np.array([y, 0.0, 0.0]), camera, LABEL_ROWS, (4.0, 80.0))
        ground_y[b] = y
        slots[b] = b
    return xs, slots, ground_y


def _estimate(shift_m: float = 0.0, valid: bool = True) -> LaneEstimate:
    if not valid:
        return LaneEstimate.invalid("nothing")
    left, right = LANES_Y[0] + shift_m, LANES_Y[1] + shift_m
    return LaneEstimate(valid=True, offset_m=-(left + right) / 2.0, x_m=8.0,
                        left=np.array([left, 0.0, 0.0]), right=np.array([right, 0.0, 0.0]),
                        confidence=0.9)


def _perfect(xs, slots, shift_m: float = 0.0) -> FramePrediction:
    boxes = gt_boxes(xs, slots, eval_grid())
    lanes = [x for x, s in zip(xs, slots, strict=True) if s >= 0]
    return FramePrediction(boxes, np.ones(len(boxes)), lanes, _estimate(shift_m))


def test_perfect_prediction_scores_ap_1_iou_1_ade_0():
    cam = _camera()
    xs, slots, gy = _truth(cam)
    tally = Tally()
    for _ in range(3):
        tally.add(_perfect(xs, slots), xs, slots, gy, ms=1.0)
    s = tally.summary()
    assert s["gt_boxes"] > 60 and s["gt_lanes"] == 12
    assert s["ap"] == pytest.approx(1.0)
    assert s["iou"] == pytest.approx(1.0) and s["iou_ego"] == pytest.approx(1.0)
    # every lane proposed: the other lanes' boxes are false positives against the ego ones
    assert 0.0 < s["ego_box_share"] < 1.0 and s["ap_ego"] < 1.0
    assert s["f1"] == pytest.approx(1.0)
    assert s["ade_cm"] == pytest.approx(0.0, abs=1e-4)
    assert s["fde_cm"] == pytest.approx(0.0, abs=1e-4)
    assert s["offset_err_cm"] == pytest.approx(0.0, abs=1e-4)
    assert s["valid"] == 1.0 and s["ms"] == 1.0


def test_an_ego_only_model_is_bounded_by_the_ego_share_and_whole_on_ap_ego():
    """A perfect model of the ego lane alone: AP at most the ego boundaries' share of all
    boxes (it cannot recall the others), AP-ego 1."""
    cam = _camera()
    xs, slots, gy = _truth(cam)
    ego = np.isin(slots, (0, 1))
    pred = _perfect(xs[ego], slots[ego])
    tally = Tally()
    tally.add(FramePrediction(pred.boxes, pred.scores, pred.lanes, _estimate()), xs, slots, gy,
              ms=1.0)
    s = tally.summary()
    assert s["ap_ego"] == pytest.approx(1.0)
    assert s["ap"] == pytest.approx(s["ego_box_share"]) and s["ego_box_share"] < 1.0


def test_shifted_estimate_has_the_known_ade_and_offset_error():
    cam = _camera()
    xs, slots, gy = _truth(cam)
    tally = Tally()
    pred = _perfect(xs, slots)
    tally.add(FramePrediction(pred.boxes, pred.scores, pred.lanes, _estimate(0.25)), xs, slots,
              gy, ms=2.0)
    s = tally.summary()
    assert s["ade_cm"] == pytest.approx(25.0, abs=1e-3)
    assert s["fde_cm"] == pytest.approx(25.0, abs=1e-3)
    assert s["offset_err_cm"] == pytest.approx(25.0, abs=1e-3)


def test_no_prediction_scores_zero_and_no_ade():
    cam = _camera()
    xs, slots, gy = _truth(cam)
    tally = Tally()
    tally.add(FramePrediction(np.zeros((0, 4)), np.zeros(0), [], _estimate(valid=False)),
              xs, slots, gy, ms=1.0)
    s = tally.summary()
    assert s["ap"] == 0.0 and s["iou"] == 0.0 and s["f1"] == 0.0 and s["valid"] == 0.0
    assert math.isnan(s["ade_cm"]) and math.isnan(s["offset_err_cm"])


def test_average_precision_of_a_hand_worked_ranking():
    # Ranked: TP, FP, TP over 2 ground-truth boxes: precision 1, 1/2, 2/3 at recall 1/2, 1/2, 1.
    ap = average_precision(np.array([0.9, 0.8, 0.7]), np.array([True, False, True]), 2)
    assert ap == pytest.approx(0.5 * 1.0 + 0.5 * 2.0 / 3.0)
    assert average_precision(np.zeros(0), np.zeros(0, bool), 3) == 0.0
    assert math.isnan(average_precision(np.array([0.5]), np.array([False]), 0))


def test_a_box_is_matched_once_and_only_at_iou_half():
    grid = eval_grid()
    gt = cell_boxes(np.array([100.0]), np.array([50.0]), grid)
    near = cell_boxes(np.array([100.0 + grid.cell_w / 4, 100.0]), np.array([50.0, 50.0]), grid)
    tp = match_boxes(near, np.array([0.6, 0.9]), gt)
    assert tp.tolist() == [False, True]  # the higher score takes it; the other is a duplicate
    far = cell_boxes(np.array([100.0 + grid.cell_w / 2]), np.array([50.0]), grid)  # IoU 1/3
    assert not match_boxes(far, np.array([0.9]), gt).any()


def test_lane_iou_of_shifted_lanes_and_hungarian_pairing():
    rows = LABEL_ROWS
    a, b = np.full(len(rows), 400.0), np.full(len(rows), 800.0)
    iou = lane_iou_matrix([a + 15.0, a], [a])
    assert iou[0, 1] == pytest.approx(1.0)
    assert iou[0, 0] == pytest.approx(15.0 / 45.0, abs=0.03)  # 30 px wide, 15 px apart
    per_gt = match_lanes(lane_iou_matrix([b, a], [a, b]))  # order of predictions is irrelevant
    assert per_gt == pytest.approx([1.0, 1.0])


def test_classical_estimate_becomes_the_labels_boxes_within_its_range():
    cam = _camera()
    xs, slots, gy = _truth(cam)
    pred = estimate_prediction(_estimate(), cam, (4.0, 80.0), eval_grid())
    assert len(pred.lanes) == 2 and np.all(pred.scores == 0.9)
    ok = np.isfinite(pred.lanes[0]) & np.isfinite(xs[0])
    assert ok.sum() > 20 and np.abs(pred.lanes[0][ok] - xs[0][ok]).max() < 0.5
    tp = match_boxes(pred.boxes, pred.scores, gt_boxes(xs, slots, eval_grid()))
    # Every band but, at most, the last one of each boundary (labels stop at a 5 px row).
    assert len(tp) > 30 and tp.sum() >= len(tp) - 2


def test_the_other_lanes_lines_of_a_classical_estimate_are_scored_too():
    """A classical estimate that reports the neighbouring lanes' lines (`others`) is scored on
    them: every labelled boundary recalled, AP 1 where its ego pair alone is bounded by the
    ego boundaries' share of the boxes."""
    cam = _camera()
    xs, slots, gy = _truth(cam)
    ego_only = _estimate()
    every = dataclasses.replace(ego_only, others=tuple(np.array([y, 0.0, 0.0])
                                                       for y in LANES_Y[2:]))
    scores = {}
    for name, est in (("ego", ego_only), ("every", every)):
        tally = Tally()
        tally.add(estimate_prediction(est, cam, (4.0, 80.0), eval_grid()), xs, slots, gy, 1.0)
        scores[name] = tally.summary()
    assert scores["every"]["ap"] > 0.97 and scores["every"]["iou"] > 0.9
    assert scores["ego"]["ap"] < scores["ego"]["ego_box_share"] + 0.01
    assert scores["every"]["ade_cm"] == scores["ego"]["ade_cm"]  # the ego pair is unchanged


def _paint(t: int = 3) -> np.ndarray:
    """Two slanted painted lines over the lower half of a 176x320 frame, moving down a bit."""
    paint = np.zeros((t, 176, 320), np.uint8)
    for k in range(t):
        for v in range(90, 176):
            d = v - 80
            paint[k, v, max(0, 160 - 2 * d - 3 + k):160 - 2 * d + 3 + k] = 1
            paint[k, v, 160 + 2 * d - 3:min(320, 160 + 2 * d + 3)] = 2
    return paint


@pytest.mark.parametrize("share", [0.4, 0.6])
def test_occluders_cover_the_asked_share_of_paint(share):
    paint = _paint()
    frames = np.full(paint.shape + (3,), 90, np.uint8)
    out, reached = occlude(frames, paint, 80.0, 1.5, share, np.random.default_rng(1))
    assert np.all(reached >= share) and reached[0] <= share + OVERSHOOT + 0.01
    changed = np.any(out != frames, axis=-1)
    covered_paint = (changed & (paint > 0)).sum(axis=(1, 2)) / (paint > 0).sum(axis=(1, 2))
    assert covered_paint == pytest.approx(reached, abs=0.02)  # what is reported is drawn
    again, _ = occlude(frames, paint, 80.0, 1.5, share, np.random.default_rng(1))
    assert np.array_equal(out, again)


def test_eval_seeds_are_not_dataset_seeds():
    ours = {condition_seed(c, i) for c in CONDITIONS for i in range(8)}
    assert len(ours) == len(CONDITIONS) * 8
    theirs = {world_seed(DatasetRecipe(), split, i) for split in ("train", "val", "test")
              for i in range(3000)}
    assert not ours & theirs
    tuning = {condition_seed(c, i, namespace=EvalRecipe(split="tuning").namespace)
              for c in CONDITIONS for i in range(8)}
    assert len(tuning) == len(CONDITIONS) * 8
    assert not tuning & ours and not tuning & theirs  # tuning worlds are never scored ones


def test_tuning_split_draws_other_worlds_of_the_same_conditions():
    from lanekeep.evaluation.eval_sets import set_key

    test, tuning = EvalRecipe.quick(), EvalRecipe(worlds=1, sequences=1, split="tuning")
    assert test.namespace != tuning.namespace
    assert set_key("clear", test) != set_key("clear", tuning)
    night = condition_scenario("night", 0, tuning.namespace)
    assert night.conditions.time_of_day == "night"
    assert night.seed != condition_scenario("night", 0).seed
    with pytest.raises(ValueError, match="split"):
        EvalRecipe(split="train")
    assert occlusion_share("occlusion_40") == 0.4 and occlusion_share("clear") == 0.0


def test_conditions_are_forced_on_the_worlds():
    curve = condition_scenario("curve", 0)
    arcs = [s for s in curve.road.segments if s.kind == "arc"]
    assert arcs and 150.0 <= 1.0 / abs(arcs[0].curvature_1pm) <= 300.0
    worn = condition_scenario("worn", 0).road.markings
    assert all(m.kind == "worn" for m in worn[1:-1])
    dots = condition_scenario("dots", 0).road.markings
    assert len(dots) > 2 and all(m.kind == "dots" for m in dots[1:-1])
    assert {dots[0].kind, dots[-1].kind} <= {"solid", "dashed", "double"}
    shade = condition_scenario("half_shade", 0).conditions.shadows
    assert len(shade) == 1 and 0.45 <= shade[0].reach <= 0.55 and shade[0].coverage == 1.0
    assert condition_scenario("clear", 0).conditions.shadows == ()
    assert condition_scenario("night", 0).conditions.time_of_day == "night"


def test_eval_worlds_have_readable_paint_unless_worn_is_the_condition():
    """Worn, dotted and missing lines are the `worn` condition's subject, not a draw's: the
    first clear world (the `--quick` one) was drawn with both ego boundaries worn."""
    from lanekeep.evaluation.dataset_world import random_scenario
    from lanekeep.geometry.markings import MARKING_KINDS, MarkingStyle

    lines = {"solid", "dashed", "double"}
    drawn = random_scenario(condition_seed("clear", 0), "clear").road.markings
    assert {m.kind for m in drawn} - lines  # the draw had worn paint
    assert {m.kind for m in condition_scenario("clear", 0).road.markings} <= lines
    assert readable(MarkingStyle(kind="worn", pattern="dashed")).kind == "dashed"
    assert all(readable(MarkingStyle(kind=k)).kind in lines for k in MARKING_KINDS)


def test_eval_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["eval", "--detectors", "hough,nope", "--cache", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown detector 'nope'" in err[0]
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not a torch file")
    assert main(["eval", "--detectors", "lanenet", "--weights", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"lanekeep eval: error: {bad}")
    assert main(["eval", "--conditions", "sunny", "--detectors", "hough"]) == 2
    capsys.readouterr()
    typo = tmp_path / "typo.toml"
    typo.write_text("[hough]\nbinarisaton = \"ridge\"\n")
    for config, named in ((typo, "hough.binarisaton: unknown key"),
                          (tmp_path / "missing.toml", "missing.toml")):
        assert main(["eval", "--detectors", "hough", "--detectors-config", str(config)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--detectors-config" in err[0] and named in err[0]


def _strict(path: Path) -> dict:
    def refuse(token):
        raise ValueError(f"non-strict JSON token {token}")

    return json.loads(path.read_text(), parse_constant=refuse)


def test_eval_quick_writes_strict_json_and_reuses_its_cache(tmp_path, capsys):
    out, cache = tmp_path / "eval.json", tmp_path / "cache"
    argv = ["eval", "--quick", "--detectors", "hough", "--conditions", "clear,occlusion_60",
            "--cache", str(cache), "--json", str(out)]
    assert main(argv) == 0
    doc = _strict(out)
    assert doc["recipe"] == {**doc["recipe"], "worlds": 1, "sequences": 1}
    occ = doc["conditions"]["occlusion_60"]
    assert occ["frames"] == EvalRecipe.quick().frames and occ["coverage_mean"] >= 0.6
    for entry in doc["conditions"].values():
        s = entry["detectors"]["hough"]
        assert s["gt_boxes"] > 0 and s["ms"] > 0 and (s["ap"] is None or 0 <= s["ap"] <= 1)
    assert "occlusion_60" in capsys.readouterr().out
    files = sorted(p.name for p in cache.iterdir())
    assert len(files) == 2
    assert main(argv) == 0  # from the cache: the same sets, the same scores
    assert sorted(p.name for p in cache.iterdir()) == files
    assert _untimed(_strict(out)["conditions"]) == _untimed(doc["conditions"])
    assert doc["detectors_config"] is None  # the shipped settings
    # Other settings, from a file: the same sets, the file's settings recorded in full.
    settings = tmp_path / "ridge.toml"
    settings.write_text("[hough]\nbinarisation = \"ridge\"\n")
    assert main([*argv, "--detectors-config", str(settings)]) == 0
    assert sorted(p.name for p in cache.iterdir()) == files
    record = _strict(out)["detectors_config"]
    assert record["path"] == str(settings)
    assert record["settings"]["hough"]["binarisation"] == "ridge"
    assert record["settings"]["lane"]["lane_width_m"] > 0  # every setting, not only the file's


def _untimed(conditions: dict) -> dict:
    return {k: {**v, "detectors": {n: {m: x for m, x in d.items() if m != "ms"}
                                   for n, d in v["detectors"].items()}}
            for k, v in conditions.items()}


@pytest.mark.slow
def test_eval_quick_every_condition_with_hough(tmp_path):
    out = tmp_path / "eval.json"
    assert main(["eval", "--quick", "--detectors", "hough", "--cache", str(tmp_path / "c"),
                 "--json", str(out)]) == 0
    assert list(_strict(out)["conditions"]) == list(CONDITIONS)


@pytest.mark.slow
def test_eval_runs_lanenet_from_a_weights_file(tmp_path):
    torch = pytest.importorskip("torch")
    from lanekeep.detectors.lanenet import save_weights
    from lanekeep.detectors.lanenet_model import LaneNet, LaneNetConfig

    torch.manual_seed(0)
    weights = tmp_path / "lanenet.pt"  # untrained but valid: the plumbing, not the accuracy
    save_weights(LaneNet(LaneNetConfig()).eval(), weights)
    out = tmp_path / "eval.json"
    assert main(["eval", "--quick", "--detectors", "lanenet,hough", "--conditions", "clear",
                 "--weights", str(weights), "--cache", str(tmp_path / "c"),
                 "--json", str(out)]) == 0
    doc = _strict(out)
    assert doc["weights"] == str(weights)
    s = doc["conditions"]["clear"]["detectors"]["lanenet"]
    assert s["frames"] == 3 and s["ms"] > 0 and s["gt_boxes"] > 0
    assert s["ap"] is not None and 0.0 <= s["ap"] <= 1.0


def test_the_eval_cache_key_covers_the_code_that_renders_a_set():
    """A cached test set is rendered again after any edit of the world, camera or scenario
    code, not only of lanekeep/evaluation (the key once hashed that folder alone)."""
    from lanekeep.evaluation.eval_sets import fingerprinted_files

    names = {name for name, _ in fingerprinted_files()}
    for needed in ("world/build.py", "sensing/cameras.py", "sensing/camera_sensor.py",
                   "scenario/schema.py", "evaluation/eval_sets.py", "evaluation/dataset.py",
                   "evaluation/dataset_world.py", "world/camera_mount.py", "mjcf/car.xml",
                   "__init__.py", "world/__init__.py"):
        assert needed in names, needed
    # Code that scores or drives, not draws, leaves the cached sets valid (documents scored
    # by two checkouts that differ only there pair up): the key is the renderer's imports.
    for scoring in ("evaluation/lane_metrics.py", "evaluation/detector_eval.py",
                    "evaluation/eval_compare.py", "cli/main.py", "detectors/hough.py",
                    "driver/driver.py"):
        assert scoring not in names, scoring


def test_a_settings_files_lanenet_table_reaches_lanenet(tmp_path):
    """`--detectors-config` reaches every detector it has a table for, LaneNet's decoding
    too: before 2026-12-01 eval built LaneNet with the shipped settings and recorded the
    file's, so a [lanenet] table changed the JSON's record and not one figure."""
    scores = {}
    for name, text in (("shipped", None), ("strict", "[lanenet]\nmin_points = 1000\n")):
        out = tmp_path / f"{name}.json"
        argv = ["eval", "--quick", "--detectors", "lanenet", "--conditions", "clear",
                "--cache", str(tmp_path / "c"), "--json", str(out)]
        if text is not None:
            settings = tmp_path / f"{name}.toml"
            settings.write_text(text)
            argv += ["--detectors-config", str(settings)]
        assert main(argv) == 0
        doc = _strict(out)
        scores[name] = doc["conditions"]["clear"]["detectors"]["lanenet"]
    assert doc["detectors_config"]["settings"]["lanenet"]["min_points"] == 1000
    assert scores["shipped"]["valid"] > 0.5
    assert scores["strict"]["valid"] == 0.0  # no boundary has 1000 points: no lane


def test_stateless_eval_resets_lanenet_before_every_frame(tmp_path):
    """`--stateless`: the same frames without LaneNet's recurrent state (the frame-only
    ablation) score otherwise than with it, and the document says which it was."""
    docs = {}
    for flag in ([], ["--stateless"]):
        out = tmp_path / f"eval{len(flag)}.json"
        assert main(["eval", "--quick", "--detectors", "lanenet", "--conditions", "clear",
                     "--frames", "4", "--cache", str(tmp_path / "c"), "--json", str(out),
                     *flag]) == 0
        docs[bool(flag)] = _strict(out)
    assert [docs[k]["stateless"] for k in (False, True)] == [False, True]
    assert docs[False]["recipe"]["frames"] == 4
    with_state, without = (docs[k]["conditions"]["clear"]["detectors"]["lanenet"]
                           for k in (False, True))
    assert with_state["frames"] == without["frames"] == 4
    keys = ("ap", "ade_cm", "offset_err_cm")
    assert [with_state[k] for k in keys] != [without[k] for k in keys]
