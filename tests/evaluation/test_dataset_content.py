"""What a dataset's worlds contain (lanekeep/evaluation/dataset_content.py): the paint's
contrast as measured on frames, which worlds a leave-content-out run drops, and a training
split restricted to chosen worlds."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from lanekeep.evaluation.dataset import load_split, shard_path
from lanekeep.evaluation.dataset_content import (
    WorldContent,
    held_out,
    label_contrast,
    paint_contrast,
)


def _frame(road: int, paint: int, width: int = 4) -> tuple[np.ndarray, np.ndarray]:
    rgb = np.full((60, 80, 3), road, np.uint8)
    ids = np.zeros((60, 80), np.uint8)
    rgb[:, 30:30 + width] = paint
    ids[:, 30:30 + width] = 1
    return rgb, ids


def test_paint_contrast_is_paint_minus_the_road_beside_it():
    a, b = _frame(80, 130), _frame(60, 70)
    frames, paint = np.stack([a[0], b[0], a[0]]), np.stack([a[1], b[1], a[1]])
    assert paint_contrast(frames, paint) == pytest.approx(50.0, abs=1.0)  # median of 50, 10, 50


def test_a_world_without_visible_paint_has_no_contrast():
    rgb, ids = _frame(80, 130)
    assert math.isnan(paint_contrast(rgb[None], np.zeros_like(ids)[None]))


def test_label_contrast_reads_dashed_paint_at_its_labels():
    """A dashed line labelled through its gaps (as TuSimple labels lanes): the read is the
    paint's contrast, not the gaps'; the far rows and a line off the frame are not read."""
    rgb = np.full((176, 320, 3), 70, np.uint8)
    for top in range(106, 176, 20):  # dashes of 6 rows every 20 in the near rows
        rgb[top:top + 6, 159:162] = 130
    rows = np.arange(0, 720, 5, dtype=float)
    line = np.stack([np.full_like(rows, 160 * 4.0), rows], 1)
    assert label_contrast(rgb, [line]) == pytest.approx(60.0)
    rgb[:, 159:162] = 70  # no paint: the read is the road's own
    assert label_contrast(rgb, [line]) == pytest.approx(0.0)
    assert math.isnan(label_contrast(rgb, [line[:20]]))  # only far rows labelled


def _worlds() -> list[WorldContent]:
    base = WorldContent(index=0, world_seed=0, tag="clear", paint_contrast_dn=20.0,
                        label_contrast_dn=20.0, vehicles_per_lane_km=5.0, shade_share=0.0,
                        dashcam=False,
                        horizon_row=350.0, camera_height_m=1.4)
    return [
        dataclasses.replace(base, index=0, paint_contrast_dn=4.0, vehicles_per_lane_km=1.0),
        dataclasses.replace(base, index=1, paint_contrast_dn=math.nan, shade_share=0.5),
        dataclasses.replace(base, index=2, vehicles_per_lane_km=15.0, dashcam=True),
        dataclasses.replace(base, index=3, paint_contrast_dn=40.0, shade_share=0.2),
        dataclasses.replace(base, index=4, paint_contrast_dn=9.0, vehicles_per_lane_km=9.0),
    ]


def test_leave_out_drops_the_worlds_with_the_most_of_a_factor():
    worlds = _worlds()
    assert held_out(worlds, "paint_contrast", 2) == [0, 4]  # the faintest; NaN is not faint
    assert held_out(worlds, "traffic", 2) == [2, 4]
    assert held_out(worlds, "shade", 2) == [1, 3]
    assert held_out(worlds, "dashcam", 1) == [2]
    control = held_out(worlds, "random", 2, seed=3)
    assert len(set(control)) == 2 and control == held_out(worlds, "random", 2, seed=3)


@pytest.mark.parametrize(("factor", "count", "message"), [
    ("weather", 2, "factor must be one of"), ("traffic", 0, "count must be between"),
    ("traffic", 5, "count must be between"),
])
def test_bad_leave_out_is_named(factor, count, message):
    with pytest.raises(ValueError, match=message):
        held_out(_worlds(), factor, count)


def test_a_split_restricted_to_chosen_worlds(tmp_path):
    for i in range(3):
        path = shard_path(tmp_path, "train", i)
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = {k: np.full((2, 1), i) for k in ("frames", "paint", "xs", "slots", "ground_y",
                                                    "camera", "is_rear")}
        np.savez(path, tag=np.array("clear"), **arrays)
    assert load_split(tmp_path, "train")["frames"].ravel().tolist() == [0, 0, 1, 1, 2, 2]
    assert load_split(tmp_path, "train", [2, 0])["frames"].ravel().tolist() == [0, 0, 2, 2]
    with pytest.raises(FileNotFoundError, match="world_00007"):
        load_split(tmp_path, "train", [0, 7])
