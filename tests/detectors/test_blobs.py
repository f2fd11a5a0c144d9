"""The bird's-eye blob test (detectors/image_stage.py `drop_blobs`): sun flecks go, lines,
dashes, sharply curving lines and fragments of worn lines stay; both classical models apply
it when asked and not by default; the settings are checked (paper mode's in
tests/estimators/test_paper_deviations.py)."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from lanekeep.core.config_io import InvalidValue
from lanekeep.detectors.config import Preprocess, load_config
from lanekeep.detectors.image_stage import drop_blobs
from lanekeep.detectors.registry import make_detector
from lanekeep.sensing.cameras import CameraRig

M_PER_ROW, M_PER_COL = 0.05, 0.02  # a bird's-eye view 10 m x 4 m at 200 x 200 cells


def _view() -> tuple[np.ndarray, dict[str, tuple[int, int]]]:
    """A view with a solid line, a 3 m dash, a curved line, a 50 cm worn fragment, and three
    flecks (a 10 cm dot, a 20 x 16 cm blob, a 45 x 50 cm cluster); each shape's centre."""
    bev = np.zeros((200, 200), np.uint8)
    cv2.rectangle(bev, (20, 0), (26, 199), 255, -1)  # solid line, 12 cm wide, 10 m long
    cv2.rectangle(bev, (100, 40), (106, 99), 255, -1)  # dash, 3 m
    rows = np.arange(200)
    cv2.polylines(bev, [np.stack([170 + (rows / 40.0) ** 2, rows], 1).astype(np.int32)],
                  False, 255, 5)  # curving line
    cv2.rectangle(bev, (60, 150), (66, 159), 255, -1)  # worn fragment: 50 cm x 14 cm
    cv2.circle(bev, (140, 20), 2, 255, -1)  # dot, 10 cm
    cv2.rectangle(bev, (130, 120), (137, 123), 255, -1)  # blob 20 x 16 cm
    cv2.rectangle(bev, (30, 170), (54, 178), 255, -1)  # cluster 45 x 50 cm
    centres = {"line": (100, 23), "dash": (70, 103), "curve": (150, 170 + int((150 / 40) ** 2)),
               "fragment": (155, 63), "dot": (20, 140), "blob": (121, 133), "cluster": (174, 42)}
    return bev, centres


def test_flecks_go_and_lines_dashes_curves_and_fragments_stay() -> None:
    bev, at = _view()
    kept = drop_blobs(bev, M_PER_ROW, M_PER_COL, min_length_m=1.0, min_elongation=3.0)
    for name in ("line", "dash", "curve", "fragment"):
        assert kept[at[name]] == 255, name
    for name in ("dot", "blob", "cluster"):
        assert bev[at[name]] == 255 and kept[at[name]] == 0, name
    assert set(np.unique(kept)) <= {0, 255} and kept.dtype == np.uint8


def test_off_or_nothing_to_drop_returns_the_view_itself() -> None:
    bev, _ = _view()
    assert drop_blobs(bev, M_PER_ROW, M_PER_COL, 0.0, 3.0) is bev
    line_only = np.zeros_like(bev)
    line_only[:, 20:27] = 255
    assert drop_blobs(line_only, M_PER_ROW, M_PER_COL, 1.0, 3.0) is line_only
    empty = np.zeros_like(bev)
    assert drop_blobs(empty, M_PER_ROW, M_PER_COL, 1.0, 3.0) is empty


@pytest.mark.parametrize(("field", "bad"), [("min_blob_length_m", -0.5),
                                            ("min_blob_length_m", float("nan")),
                                            ("min_blob_elongation", 0.0),
                                            ("min_blob_elongation", float("inf"))])
def test_bad_blob_settings_are_refused_by_name(field: str, bad: float) -> None:
    with pytest.raises(InvalidValue, match=field):
        Preprocess(**{field: bad})


@pytest.mark.parametrize("name", ["hough", "sliding_window"])
def test_the_models_look_for_lines_in_the_view_without_its_blobs_only_when_asked(
        straight_world, searched_view, name):
    with CameraRig(straight_world.model) as rig:
        camera = dict(rig.cameras)["front"]
    shipped = load_config()
    on = replace(shipped, preprocess=replace(shipped.preprocess, min_blob_length_m=1.0))
    for config, drops in ((shipped, False), (on, True)):
        detector = make_detector(name, camera, config)
        window = detector.view.window
        bev = np.zeros((detector.view.rows, detector.view.cols), np.uint8)
        bev[:, 40:43] = 255  # a line along the whole view
        bev[50:52, 100:102] = 255  # a fleck: 20 x 10 cm
        assert window.m_per_row * 2 < 1.0
        seen = searched_view(detector, bev)
        assert seen[:, 40:43].all()
        assert seen[50, 100] == (0 if drops else 255)
