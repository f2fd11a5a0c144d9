"""Two eval documents paired over conditions (lanekeep/evaluation/eval_compare.py)."""

import json

import pytest

from lanekeep.evaluation.eval_compare import EvalMismatch, compare_evals, main

CONDITIONS = ("clear", "night", "fog", "snow", "rain")


def _doc(ap_shift=0.0, offset_scale=1.0, sets="s"):
    return {"conditions": {c: {"set_sha256": f"{sets}{c}", "detectors": {"lanenet": {
        "ap": 0.5 + 0.08 * i + ap_shift, "f1": 0.6, "iou_ego": 0.7, "ade_cm": 4.0 + i,
        "offset_err_cm": (2.0 + 0.5 * i) * offset_scale, "valid": 0.95}}}
        for i, c in enumerate(CONDITIONS)}}


def test_a_higher_ap_everywhere_is_better_and_the_same_scores_are_equivalent():
    common, _, _, diffs = compare_evals(_doc(ap_shift=0.1, offset_scale=0.5), _doc())
    assert common == list(CONDITIONS)
    assert diffs["ap"].verdict == "better" and diffs["ap"].diff == pytest.approx(0.1)
    assert diffs["offset_err_cm"].verdict == "better"
    assert diffs["f1"].verdict == "equivalent" and diffs["f1"].n == len(CONDITIONS)


def test_documents_of_other_sets_are_refused(tmp_path, capsys):
    with pytest.raises(EvalMismatch, match="sets differ"):
        compare_evals(_doc(), _doc(sets="other"))
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    a.write_text(json.dumps(_doc()))
    b.write_text(json.dumps(_doc(sets="other")))
    assert main([str(a), str(b)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("eval_compare: error: the sets differ")
