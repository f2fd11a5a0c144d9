"""#59's realism statistics (lanekeep/tuning/realism_gaps.py) on synthetic frames whose answer
is known by construction; no rendering, no real photos."""

import math

import numpy as np
import pytest

from lanekeep.tuning import realism_gaps as gaps
from lanekeep.tuning.realism_report import GAP_ROWS, gap_summary, gap_table

H, W, HORIZON = 360, 640, 120
SKY_BLUE, GREEN, DRY_GRASS = (120, 160, 225), (60, 140, 50), (170, 150, 80)


def flat(value, h: int = H, w: int = W) -> np.ndarray:
    return np.full((h, w, 3), value, np.uint8)


# -- tone --------------------------------------------------------------------------------------
def test_dark_share_and_darkest_percentile():
    img = flat(100)
    img[: H // 4] = 20  # a quarter of the frame at 20 DN
    stats = gaps.dark_stats(img)
    assert stats["dark_share"] == pytest.approx(0.25)
    assert stats["dark_p1"] == pytest.approx(20.0, abs=0.5)
    assert gaps.dark_stats(flat(45))["dark_share"] == 0.0  # 40 DN is the line


# -- vegetation --------------------------------------------------------------------------------
def test_green_share_brightness_and_texture():
    img = flat(110)
    img[200:, :W // 2] = GREEN  # flat, 160 of 360 rows, half the width
    stats = gaps.green_stats(img)
    assert stats["green_share"] == pytest.approx(160 / 360 / 2, abs=0.01)
    assert stats["green_v"] == pytest.approx(140, abs=1)
    assert stats["green_texture"] < 0.5
    leafy = img.copy()
    y, x = np.mgrid[200:H, 0:W // 2]
    leafy[200:, :W // 2][((x // 4 + y // 4) % 2) == 1] = (40, 95, 33)  # same hue, clumps
    assert gaps.green_stats(leafy)["green_texture"] > 5.0


def test_grey_and_dry_grass_are_not_green():
    img = flat(110)
    img[200:] = DRY_GRASS
    stats = gaps.green_stats(img)
    assert stats["green_share"] == 0.0 and math.isnan(stats["green_v"])


# -- open sky ----------------------------------------------------------------------------------
def sky_scene() -> np.ndarray:
    """Blue sky above the horizon, dark ground below."""
    img = flat(70)
    img[:HORIZON] = SKY_BLUE
    return img


def test_open_sky_fills_the_area_above_the_horizon():
    assert gaps.open_sky_share(sky_scene(), HORIZON) == pytest.approx(1.0)
    assert math.isnan(gaps.open_sky_share(sky_scene(), 0))


def test_a_cloud_with_a_rough_rim_and_a_wire_are_sky():
    img = sky_scene()
    img[30:70, 200:320] = 235  # a white cloud ...
    img[28:32, 198:322:2] = 150  # ... whose top rim is not smooth
    img[90:92] = 30  # a dark wire across the frame
    assert gaps.open_sky_share(img, HORIZON) == pytest.approx(1.0, abs=0.01)


def test_sky_coloured_patches_cut_off_from_the_top_are_not_sky():
    img = sky_scene()
    img[:40] = 60  # a dark overpass across the top ...
    img[:40, (np.arange(W) // 3) % 2 == 1] = 90  # ... with texture
    share = gaps.open_sky_share(img, HORIZON)
    assert share == 0.0
    assert gaps.open_sky_share(flat(40), HORIZON) == 0.0  # a night sky is dark: not counted


def test_trees_against_the_sky_are_not_sky():
    img = sky_scene()
    img[60:HORIZON, :W // 4] = GREEN
    img[60:HORIZON, :W // 4][::3] = (30, 70, 25)  # foliage texture
    assert gaps.open_sky_share(img, HORIZON) == pytest.approx(1 - 60 * 160 / (HORIZON * W),
                                                               abs=0.02)


# -- road structure ----------------------------------------------------------------------------
def road_with_paint() -> tuple[np.ndarray, np.ndarray]:
    """Flat grey road below the horizon, a bright vertical line at the centre as paint."""
    img = sky_scene()
    img[HORIZON:] = 90
    img[HORIZON:, 316:324] = 200
    paint = np.zeros((H, W), bool)
    paint[HORIZON:, 316:324] = True
    return img, paint


def test_paint_is_not_road_structure_but_a_seam_is():
    img, paint = road_with_paint()
    assert gaps.road_structure_edges(img, paint, HORIZON) == 0.0
    img[HORIZON:, 360:362] = 60  # a dark tar seam beside the paint
    assert gaps.road_structure_edges(img, paint, HORIZON) > 0.005
    assert math.isnan(gaps.road_structure_edges(img, None, HORIZON))


def test_paint_margin_grows_below_the_horizon():
    paint = np.zeros((H, W), bool)
    paint[:, 320] = True
    margin = gaps.paint_margin_mask(paint, HORIZON)
    near, far = margin[HORIZON].sum(), margin[H - 1].sum()
    assert near == pytest.approx(2 * 3 + 1, abs=1)
    assert far == pytest.approx(2 * (3 + 0.06 * (H - 1 - HORIZON)) + 1, abs=2)


def test_guessed_paint_is_a_narrow_ridge_not_a_light_patch():
    img, paint = road_with_paint()
    img[250:, 450:] = 150  # a wide light patch of concrete
    guess = gaps.guess_paint(img, HORIZON)
    assert guess[250:, 318:322].all()
    assert not guess[250:, 400:].any()
    assert not guess[:HORIZON].any()


# -- the side-by-side table --------------------------------------------------------------------
def test_gap_table_has_ours_range_and_na_for_unlabelled_sets():
    keys = [key for key, *_ in GAP_ROWS]
    sim = [dict.fromkeys(keys, v) for v in (0.1, 0.2, 0.4)]
    real = {"Udacity": [{**dict.fromkeys(keys, 0.5), "road_edges": math.nan}]}
    summary = gap_summary(sim, real)
    assert summary["dark_share"]["ours"] == {"median": 0.2, "min": 0.1, "max": 0.4, "n": 3}
    table = gap_table(summary, ["Udacity"])
    assert "| dark share (luma < 40 DN), % of frame | 20.0 | 10.0-40.0 | 50.0 |" in table
    assert "| road-structure edges, % (paint: mask/labels) | 20.00 | 10.00-40.00 | n/a |" in table
