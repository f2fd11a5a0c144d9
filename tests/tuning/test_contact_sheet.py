"""tools/contact_sheet.py and lanekeep/tuning/contact_sheet.py: the layout on stub images, the
tiles against `lanekeep render`'s frames (one tiny render), and one-line errors with exit 2."""

import dataclasses
import importlib.util
from pathlib import Path

import cv2
import numpy as np
import pytest
from helpers import small_scenario

from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.snapshot import render_snapshot
from lanekeep.tuning import contact_sheet as cs

ROOT = Path(__file__).resolve().parents[2]
TILE = (64, 36)


def _tool():
    spec = importlib.util.spec_from_file_location("contact_sheet_tool",
                                                  ROOT / "tools" / "contact_sheet.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _solid(rgb, h=72, w=128) -> np.ndarray:
    return np.full((h, w, 3), rgb, np.uint8)


def test_layout_places_each_tile_in_its_row_and_column_with_its_label():
    colours = [[(200, 0, 0), (0, 200, 0), (0, 0, 200)], [(200, 200, 0)]]
    rows = [[cs.Tile(_solid(c), f"r{i}c{j}") for j, c in enumerate(row)]
            for i, row in enumerate(colours)]
    sheet = cs.layout(rows, TILE)
    w, h, gap = *TILE, cs.GAP_PX
    assert sheet.shape == (2 * (h + gap) + gap, 3 * (w + gap) + gap, 3)
    for i, row in enumerate(colours):
        for j, colour in enumerate(row):
            top, left = gap + i * (h + gap), gap + j * (w + gap)
            np.testing.assert_array_equal(sheet[top + h - 2, left + w // 2], colour)
            band = sheet[top:top + 8, left:left + w]
            assert (band.min(axis=2) > 240).any()  # white label text
            assert (band.max(axis=2) < max(colour)).any()  # on a darkened band
    empty = sheet[gap + h + gap:, gap + 1 * (w + gap):]  # row 2 has one tile only
    assert (empty == cs.BACKGROUND).all()
    with pytest.raises(ValueError):
        cs.layout([], TILE)


def test_fit_letterboxes_another_aspect():
    square = cs.fit(_solid((255, 255, 255), 100, 100), TILE)
    assert square.shape == (36, 64, 3)
    assert (square[:, :10] == cs.BACKGROUND).all() and (square[:, 20:44] == 255).all()


def test_mid_drive_is_half_the_episode_at_target_speed_clipped_to_the_road():
    scenario = load_scenario("clear_straight")
    start, duration, speed = (scenario.start.s_m, scenario.duration_s,
                              scenario.target_speed_mps)
    assert cs.mid_drive_s(scenario) == pytest.approx(start + 0.5 * duration * speed)
    long = dataclasses.replace(scenario, duration_s=10 * scenario.road.length_m / speed)
    assert cs.mid_drive_s(long) == pytest.approx(scenario.road.length_m)


def test_tiles_are_the_frames_lanekeep_render_writes(tmp_path):
    """The mid-drive tiles (the second pose rendered) are `render_snapshot --at mid`'s front.png
    and rear.png bit for bit: same pose, same effects stream."""
    # clear_straight: its camera model draws read noise
    scenario = small_scenario("clear_straight", camera={"width": 96, "height": 54})
    tiles = dict(zip(cs.VIEWS, cs.scenario_tiles(scenario), strict=True))
    assert tiles["front", "mid"].label.startswith("clear_straight | front mid s=")
    render_snapshot(scenario, tmp_path, at_s=cs.mid_drive_s(scenario))
    for cam in ("front", "rear"):
        written = cv2.cvtColor(cv2.imread(str(tmp_path / f"{cam}.png")), cv2.COLOR_BGR2RGB)
        np.testing.assert_array_equal(tiles[cam, "mid"].image, written)
    assert not np.array_equal(tiles["front", "start"].image, tiles["front", "mid"].image)


@pytest.mark.parametrize("args, says", [
    (["nope"], "unknown scenario 'nope'"),
    (["--tile", "8x8"], "--tile 8x8"),
    (["--quality", "5"], "--quality 5"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, args, says):
    assert _tool().main([*args, "--out", str(tmp_path / "sheet.jpg")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("contact_sheet: error:") and says in err[0]


def test_real_frames_never_go_into_a_repository(tmp_path, capsys):
    real = tmp_path / "real"
    real.mkdir()
    cv2.imwrite(str(real / "a.png"), _solid((0, 0, 0)))
    assert _tool().main(["--real", str(real), "--out", str(ROOT / "docs" / "x.jpg")]) == 2
    assert "outside the repository" in capsys.readouterr().err
    assert not (ROOT / "docs" / "x.jpg").exists()
    assert [t.label for t in cs.real_row(real)] == ["real | real/a.png"]
