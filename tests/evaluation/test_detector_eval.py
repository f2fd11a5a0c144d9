"""lanekeep/evaluation/detector_eval.py (`lanekeep eval` as a library): the plan is checked
before anything is rendered, the table shows "-" where nothing was scored, and the JSON
document names what made the results. The scoring loop itself runs in
tests/evaluation/test_lane_eval.py through the command."""

from __future__ import annotations

import math

import pytest

from lanekeep.evaluation.detector_eval import (
    TABLE_COLUMNS,
    BadInput,
    EvalPlan,
    eval_document,
    plan_eval,
    table,
)
from lanekeep.evaluation.eval_sets import CONDITIONS, EvalRecipe


def test_the_plan_keeps_the_names_in_order_once_each():
    plan = plan_eval("hough, sliding_window,hough", "night,clear", None)
    assert plan == EvalPlan(["hough", "sliding_window"], ["night", "clear"], None)
    assert plan_eval("hough", "all", None).conditions == list(CONDITIONS)


@pytest.mark.parametrize(("detectors", "conditions", "message"), [
    ("hough,nope", "all", "unknown detector 'nope'; known:"),
    (" , ", "all", "no detector given"),
    ("hough", "sunny", "unknown condition 'sunny'"),
])
def test_a_bad_name_is_refused_by_name(detectors, conditions, message):
    with pytest.raises(BadInput, match=message):
        plan_eval(detectors, conditions, None)


def test_outputs_that_cannot_be_written_are_refused_before_anything_runs(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(BadInput, match="--json .*: exists and is a folder"):
        plan_eval("hough", "clear", None, json_path=str(tmp_path))
    with pytest.raises(BadInput, match="--cache .*: exists and is not a folder"):
        plan_eval("hough", "clear", None, cache=str(blocker))
    with pytest.raises(BadInput, match="cannot write there"):
        plan_eval("hough", "clear", None, json_path=str(blocker / "out.json"))
    assert list(tmp_path.iterdir()) == [blocker]  # checking created nothing


def test_bad_weights_stop_the_plan_and_none_are_read_without_lanenet(tmp_path):
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not weights")
    with pytest.raises(BadInput, match="bad.pt"):
        plan_eval("lanenet", "clear", str(bad))
    assert plan_eval("hough", "clear", None).weights is None


def test_the_table_shows_a_dash_where_nothing_was_scored():
    scored = {key: 0.5 for key, _, _ in TABLE_COLUMNS}
    results = {"night": {"detectors": {"hough": scored,
                                       "lanenet": {**scored, "ade_cm": None, "ms": math.nan}}}}
    lines = table(results).splitlines()
    assert lines[0].split()[:5] == ["condition", "detector", "AP", "APego", "IoU"]
    assert lines[2].split()[:3] == ["night", "hough", "0.500"]
    lanenet = lines[3].split()
    assert lanenet[0] == "lanenet" and lanenet.count("-") == 2
    assert lines[-1].startswith("AP: proposals vs marking boxes")


def test_the_document_names_what_made_the_results():
    plan = EvalPlan(["hough"], ["clear"], None)
    doc = eval_document(plan, EvalRecipe.quick(), True, {"clear": {}})
    assert doc["command"] == "eval" and doc["quick"] is True
    assert doc["detectors"] == ["hough"] and doc["conditions"] == {"clear": {}}
    assert doc["recipe"]["worlds"] == EvalRecipe.quick().worlds
