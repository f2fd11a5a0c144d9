"""Botts' dots joined along the road (detectors/image_stage.py `join_along_road`): a row of
dots becomes one stroke, a line and a dash stay as they were, pieces further apart than the
setting stay apart; both classical models join only when asked; the setting is checked."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from lanekeep.core.config_io import InvalidValue
from lanekeep.detectors.config import Preprocess, load_config
from lanekeep.detectors.image_stage import join_along_road, join_dot_rows
from lanekeep.detectors.registry import make_detector
from lanekeep.sensing.cameras import CameraRig

M_PER_ROW, M_PER_COL = 0.1, 0.05  # the shipped bird's-eye view's pixel


def _pieces(bev: np.ndarray) -> int:
    return cv2.connectedComponents(bev, connectivity=8)[0] - 1


def _dots(bev: np.ndarray, col: int, first_row: int, spacing_m: float, n: int,
          drift_px: int = 0) -> None:
    """`n` dots 10 cm across, `spacing_m` apart down the view, each `drift_px` columns
    beside the one before (a leaning line)."""
    for k in range(n):
        r, c = first_row + int(round(k * spacing_m / M_PER_ROW)), col + k * drift_px
        bev[r:r + 2, c:c + 2] = 255


def test_a_row_of_dots_becomes_one_stroke_and_lines_stay() -> None:
    bev = np.zeros((160, 240), np.uint8)
    _dots(bev, 40, 10, 1.0, 4)  # a row of dots 1 m apart, straight
    _dots(bev, 120, 10, 1.2, 4, drift_px=1)  # 1.2 m apart, leaning a pixel per dot
    bev[:, 200:203] = 255  # a solid line
    bev[60:90, 170:173] = 255  # a 3 m dash
    joined = join_along_road(bev, M_PER_ROW, 1.4)
    assert _pieces(bev) == 10 and _pieces(joined) == 4
    assert joined[10:42, 40:42].any(axis=1).all()  # no row of the dots' span left empty
    assert np.array_equal(joined[:, 160:], bev[:, 160:])  # the line and the dash unchanged
    assert (joined >= bev).all() and set(np.unique(joined)) <= {0, 255}


def test_pieces_further_apart_than_the_setting_stay_apart() -> None:
    bev = np.zeros((160, 120), np.uint8)
    _dots(bev, 40, 10, 2.0, 4)  # 2 m apart: a dashed line's gap, or noise, not a row of dots
    assert _pieces(join_along_road(bev, M_PER_ROW, 1.4)) == 4
    assert join_along_road(bev, M_PER_ROW, 0.0) is bev
    assert join_along_road(bev, M_PER_ROW, 0.1) is bev  # under two rows: nothing to join


def test_only_rows_of_dots_are_joined_when_asked_for_dots() -> None:
    """join_min_dots: four dots in a row join; two dots, a lone speck beside a dash, a wide
    blotch in a row with dots and the dash itself stay as they were."""
    bev = np.zeros((160, 240), np.uint8)
    _dots(bev, 40, 10, 1.0, 4)  # a row of four dots
    _dots(bev, 80, 10, 1.0, 2)  # two: not a row
    bev[60:90, 170:173] = 255  # a 3 m dash ...
    bev[92:94, 171:173] = 255  # ... and a speck 20 cm beyond its end (whole view: joined)
    bev[10:12, 120:122] = bev[30:32, 120:122] = 255  # two dots around ...
    bev[20:22, 120:130] = 255  # ... a blotch 0.5 m wide: not a dot
    joined = join_dot_rows(bev, M_PER_ROW, M_PER_COL, 1.4, 3)
    assert joined[10:42, 40:42].any(axis=1).all()  # the row of four: one stroke
    assert _pieces(joined[:, :60]) == 1
    assert np.array_equal(joined[:, 60:], bev[:, 60:])  # everything else as it was
    assert not np.array_equal(join_along_road(bev, M_PER_ROW, 1.4)[:, 160:], bev[:, 160:])
    assert (joined >= bev).all() and set(np.unique(joined)) <= {0, 255}
    assert _pieces(join_dot_rows(bev, M_PER_ROW, M_PER_COL, 1.4, 2)[:, 60:100]) == 1
    assert join_dot_rows(bev, M_PER_ROW, M_PER_COL, 0.0, 3) is bev


def test_a_field_of_specks_is_not_made_a_band() -> None:
    """Gravel beside a curve's edge line reached sliding_window's view as a field of specks,
    which a join of every row of dots closed into a band 0.5 m wide that the model took for the
    boundary (tests/detectors/test_detectors.py, clear_curve, 1.2 m off). A joined row must be
    no wider than a dot; a row beside the field still joins."""
    rng = np.random.default_rng(7)
    bev = np.zeros((160, 240), np.uint8)
    for r, c in zip(rng.integers(40, 100, 60), rng.integers(100, 112, 60), strict=True):
        bev[r:r + 2, c:c + 2] = 255  # specks over 6 m x 0.6 m
    _dots(bev, 40, 10, 1.0, 4)
    joined = join_dot_rows(bev, M_PER_ROW, M_PER_COL, 1.5, 2)
    assert np.array_equal(joined[:, 90:], bev[:, 90:])
    assert joined[10:42, 40:42].any(axis=1).all()


@pytest.mark.parametrize("bad", [1, -1])
def test_a_bad_dot_count_is_refused_by_name(bad: int) -> None:
    with pytest.raises(InvalidValue, match="join_min_dots"):
        Preprocess(join_min_dots=bad)


@pytest.mark.parametrize("bad", [-0.5, float("nan"), float("inf")])
def test_a_bad_join_length_is_refused_by_name(bad: float) -> None:
    with pytest.raises(InvalidValue, match="join_along_m"):
        Preprocess(join_along_m=bad)


@pytest.mark.parametrize("name", ["hough", "sliding_window"])
def test_the_models_join_dots_only_when_asked(straight_world, searched_view, name):
    with CameraRig(straight_world.model) as rig:
        camera = dict(rig.cameras)["front"]
    shipped = load_config()
    assert shipped.preprocess.join_along_m == 0.0
    on = replace(shipped, preprocess=replace(shipped.preprocess, join_along_m=1.4))
    dots_only = replace(on, preprocess=replace(on.preprocess, join_min_dots=3))
    for config, joins in ((shipped, False), (on, True), (dots_only, True)):
        detector = make_detector(name, camera, config)
        assert detector.view.window.m_per_row == M_PER_ROW
        bev = np.zeros((detector.view.rows, detector.view.cols), np.uint8)
        _dots(bev, 100, 20, 1.0, 5)
        assert _pieces(searched_view(detector, bev)) == (1 if joins else 5)


@pytest.mark.parametrize(("name", "min_dots"), [("join_dots", 0), ("join_dot_rows", 2)])
def test_the_measured_settings_in_docs_load(name: str, min_dots: int) -> None:
    """docs/data/join_dots.toml and join_dot_rows.toml, the settings docs/experiments.md
    measured, are valid files that change the join and nothing else."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "docs" / "data" / f"{name}.toml"
    config = load_config(str(path))
    assert config.preprocess.join_along_m == 1.5
    assert config.preprocess.join_min_dots == min_dots
    assert replace(config.preprocess, join_along_m=0.0,
                   join_min_dots=0) == load_config().preprocess
