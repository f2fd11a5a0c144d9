"""The realism report's shade/sun and paint-edge statistics on synthetic frames whose answer
is known by construction."""

import numpy as np
import pytest

from lanekeep.tuning.realism import paint_edge_width, shade_sun_ratio

H, W, HORIZON = 360, 640, 100


def test_shade_sun_is_the_ratio_of_the_two_road_levels():
    rgb = np.full((H, W, 3), 120, np.uint8)
    rgb[:, : W // 2] = 36  # the left half of the road in shade: 0.3 of the sun
    assert shade_sun_ratio(rgb, HORIZON) == pytest.approx(0.3, abs=0.01)


def test_shade_sun_is_undefined_when_the_dark_class_is_small():
    rgb = np.full((H, W, 3), 120, np.uint8)
    rgb[300:305, 300:340] = 30  # a small dark patch: < 10% of the road area
    assert np.isnan(shade_sun_ratio(rgb, HORIZON))


@pytest.mark.parametrize("ramp_px", [2, 4, 8])
def test_paint_edge_width_is_the_ramps_10_to_90_percent_width(ramp_px):
    """A vertical line 16 px wide, 60 DN over the road, with linear ramps `ramp_px` wide: the
    10-90% rise is 0.8 of the ramp."""
    x = np.arange(W, dtype=float)
    lo, hi = 300.0, 316.0
    up = np.clip((x - lo) / ramp_px + 0.5, 0.0, 1.0)
    down = np.clip((hi - x) / ramp_px + 0.5, 0.0, 1.0)
    row = 80.0 + 60.0 * np.minimum(up, down)
    rgb = np.repeat(np.repeat(row[None, :, None], H, 0), 3, 2).round().astype(np.uint8)
    paint = np.zeros((H, W), bool)
    paint[:, int(lo):int(hi)] = True
    assert paint_edge_width(rgb, paint, HORIZON) == pytest.approx(0.8 * ramp_px, abs=0.3)
