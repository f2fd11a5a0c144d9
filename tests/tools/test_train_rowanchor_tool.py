"""tools/train_rowanchor.py's `lean_into_lane`: a point read off its line by a known amount is
counted on the right side (into or out of the lane) and in the right kind of row (on paint or
in a dash gap), from a synthetic frame's labels, paint ids and logits; `--seen-only` targets
drop exactly the gap rows."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
import torch

ROOT = Path(__file__).resolve().parents[2]
SPEC = importlib.util.spec_from_file_location("train_rowanchor_tool",
                                              ROOT / "tools/train_rowanchor.py")
tool = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(tool)

BINS, ANCHORS = 80, 22


def _frame(gap_rows: slice, hfov_deg: float) -> tuple[dict, torch.Tensor]:
    """Ego-left line at x = 400 px, ego-right at x = 880 px (1280x720 labels); the ego-right
    line's paint missing in `gap_rows` of the stored 176-row map; the network reads ego-left
    in bin 27 and ego-right in bin 56, both to the right (+x) of their lines."""
    rows_px = tool.LABEL_ROWS
    xs = np.full((6, len(rows_px)), np.nan, np.float32)
    xs[0], xs[1] = 400.0, 880.0
    slots = np.array([0, 1, -1, -1, -1, -1], np.int8)
    paint = np.zeros((176, 320), np.uint8)
    paint[:, 99:102] = 1  # boundary 0 around x = 400 / 4
    paint[:, 219:222] = 2  # boundary 1 around x = 880 / 4
    paint[gap_rows, 219:222] = 0
    logits = torch.full((1, 4, ANCHORS, BINS + 1), -30.0)
    logits[0, 0, :, 27] = 30.0
    logits[0, 1, :, 56] = 30.0
    fx = 640.0 / math.tan(math.radians(hfov_deg / 2))
    camera = np.zeros((1, 16))
    camera[0, 0] = fx
    data = {"paint": paint[None], "xs": xs[None], "slots": slots[None], "camera": camera}
    return data, logits


def test_a_lean_is_signed_into_the_lane_and_split_by_paint_and_gap():
    data, logits = _frame(slice(120, 176), hfov_deg=150.0)
    lean = tool.dash_gap_lean(logits, data, BINS)
    into = float(tool.bin_to_x(27.5, 1280, BINS)) - 400.0  # ego-left: + x is into the lane
    out_of = -(float(tool.bin_to_x(56.5, 1280, BINS)) - 880.0)  # ego-right: + x is out of it
    assert into > 0 > out_of
    lower_half = 11  # of the 22 anchors, per line
    gap = lean["all_gap"]  # only the ego-right line has gap rows, the lowest ones
    assert gap["mean_px"] == round(out_of, 2) and 0 < gap["points"] < lower_half
    dash = lean["all_dash"]
    right_on_paint = lower_half - gap["points"]
    assert dash["points"] == lower_half + right_on_paint
    expected = (lower_half * into + right_on_paint * out_of) / dash["points"]
    assert dash["mean_px"] == round(expected, 2)
    assert lean["wide_gap"] == gap  # a 150 deg camera is a wide one
    narrow, logits = _frame(slice(120, 176), hfov_deg=100.0)
    assert "wide_gap" not in tool.dash_gap_lean(logits, narrow, BINS)


def test_seen_only_targets_call_a_line_absent_in_its_gaps_and_nowhere_else():
    """`--seen-only`: the ego-right line's gap rows become "absent" targets, its painted rows
    and the solid ego-left line keep their columns; without the option every row keeps them."""
    data, _ = _frame(slice(120, 176), hfov_deg=150.0)
    config = tool.RowAnchorConfig()
    cls, pos = tool.targets_of(data, config)
    seen_cls, seen_pos = tool.targets_of(data, config, seen_only=True)
    painted = tool.on_paint(data, config.lanes, config.anchors)[0]
    assert painted[0].all() and 0 < painted[1].sum() < config.anchors
    assert np.isfinite(pos[0, :2]).all()  # the labels cover every anchor of both lines
    gap = ~painted[1]
    assert (seen_cls[0, 1, gap] == config.bins).all() and np.isnan(seen_pos[0, 1, gap]).all()
    assert (seen_cls[0, 1, ~gap] == cls[0, 1, ~gap]).all()
    assert (seen_cls[0, 0] == cls[0, 0]).all() and np.array_equal(seen_pos[0, 0], pos[0, 0])
    rows = tool.anchor_rows(176, config.anchors)  # the anchors' rows in the stored paint map
    assert np.array_equal(gap, rows > 120)  # the gap drawn: stored rows 120 down


def test_a_missing_weights_file_is_one_line_and_exit_2(tmp_path, capsys):
    missing = tmp_path / "none.pt"
    with pytest.raises(SystemExit) as stop:
        tool.main(["--data", str(tmp_path), "--evaluate", "val", "--out", str(missing)])
    err = capsys.readouterr().err.strip().splitlines()
    assert stop.value.code == 2 and len(err) == 1
    assert err[0].startswith("train_rowanchor: error: ") and str(missing) in err[0]
