"""Marking styles as on real highways: Botts' dots, yellow paint, worn paint that breaks up."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from lanekeep.core.config_io import InvalidValue
from lanekeep.geometry.markings import MarkingStyle, layout
from lanekeep.scenario.schema import load_scenario, parse_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.world.build import build

DOTS = MarkingStyle("dots", dash_m=2.8, gap_m=4.52)


def test_botts_dots_come_in_rows_of_four_every_period():
    pieces = layout(DOTS, 1, 0.0, 73.2)
    assert pieces and all(p.dot for p in pieces)
    assert all(p.width_m == pytest.approx(0.10) for p in pieces)
    starts = np.array([p.s_start_m for p in pieces])
    assert len(starts) == 4 * 10  # 10 periods of 7.32 m, 4 dots (0, 0.9, 1.8, 2.7 m) each
    np.testing.assert_allclose(starts[:5], [0.0, 0.9, 1.8, 2.7, 7.32])


def test_a_worn_dashed_line_keeps_its_dashes_and_loses_paint_with_wear():
    fresh = layout(MarkingStyle("dashed"), 1, 0.0, 600.0)

    def worn(wear: float, seed: int = 1):
        return layout(MarkingStyle("worn", pattern="dashed", wear=wear), 1, 0.0, 600.0,
                      rng_seed=seed)

    light, heavy = worn(0.2), worn(0.6)
    for chip in light + heavy:  # chips lie within the dashes that wore
        assert any(d.s_start_m - 1e-9 <= chip.s_start_m and chip.s_end_m <= d.s_end_m + 1e-9
                   for d in fresh)
        assert chip.width_m <= 0.15 + 1e-12
        assert abs(chip.r_m) <= 0.5 * (0.15 - chip.width_m) + 1e-12  # inside the line
    painted = {w: sum(p.s_end_m - p.s_start_m for p in worn(w)) for w in (0.2, 0.6)}
    total = sum(d.s_end_m - d.s_start_m for d in fresh)
    assert 0.65 * total < painted[0.2] < 0.95 * total
    assert 0.2 * total < painted[0.6] < 0.6 * total
    assert np.mean([p.brightness for p in heavy]) < np.mean([p.brightness for p in light])
    lengths = np.array([p.s_end_m - p.s_start_m for p in heavy])
    assert lengths.min() < 0.2 and lengths.max() > 0.8  # holes and chips of every size
    assert worn(0.6) == worn(0.6) and worn(0.6) != worn(0.6, seed=2)


def test_pattern_is_validated():
    with pytest.raises(InvalidValue, match="pattern"):
        MarkingStyle("worn", pattern="zigzag")
    with pytest.raises(InvalidValue, match="dot_spacing_m"):
        MarkingStyle("dots", dot_spacing_m=0.0)


def test_shipped_highway_has_dots_between_the_left_lanes_and_a_yellow_left_edge():
    road = load_scenario("highway_multilane").road
    assert [m.kind for m in road.markings] == ["solid", "dashed", "dashed", "dots", "solid"]
    r, g, b = road.markings[-1].colour
    assert r > b + 0.5 and g > b + 0.3  # yellow


def test_dots_are_their_boundarys_marking_in_the_segmentation_render():
    scenario = load_scenario("highway_multilane")
    scenario = dataclasses.replace(scenario, conditions=dataclasses.replace(
        scenario.conditions, vehicles=()), camera=dataclasses.replace(  # the paper camera the
        scenario.camera, preset="paper"))  # count was set for (the file's dashcam since #59)
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, 640, 360)) as rig:
        seg = rig.render_segmentation(world.data, "front")
        rgb = rig.render_rgb(world.data, "front")
    mask = world.marking_mask(seg, 3)  # the dotted line between the two left lanes
    assert 20 <= mask.sum() < 2000, mask.sum()
    # a dot is brighter than the concrete right beside it
    assert rgb[mask].mean() > rgb[np.roll(mask, 6, axis=1) & ~mask].mean() + 10


def test_yellow_paint_renders_yellow():
    text = load_scenario("s_bend").source
    scenario = parse_scenario(open(text, encoding="utf-8").read())
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, 640, 360)) as rig:
        seg = rig.render_segmentation(world.data, "front")
        rgb = rig.render_rgb(world.data, "front").astype(float)
    centre = rgb[world.marking_mask(seg, 1)].mean(axis=0)
    edge = rgb[world.marking_mask(seg, 0)].mean(axis=0)
    assert centre[0] - centre[2] > 60  # yellow: red well above blue
    assert abs(edge[0] - edge[2]) < 25  # white
