"""The pavement and what lies on it: asphalt tones, concrete joints, tyre marks, snow cover."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from lanekeep.scenario.pavement import PavementStyle
from lanekeep.scenario.schema import ScenarioError, load_scenario, parse_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.world.build import build
from lanekeep.world.groups import GROUP_WORLD
from lanekeep.world.pavement import LANE_U, SLAB_M, pavement

PERIOD_M = 9.0
ROWS = 512


def _grey(style: PavementStyle, seed: int = 0) -> np.ndarray:
    rgb = pavement(np.random.default_rng(seed), style, 3.7, 1.5, PERIOD_M, ROWS)
    return rgb.astype(float).mean(axis=2)


def _lane(grey: np.ndarray) -> np.ndarray:
    return grey[:, : int(round(LANE_U * grey.shape[1]))]


def test_the_texture_tiles_and_follows_the_seed():
    grey = _grey(PavementStyle())
    inner = np.abs(np.diff(grey, axis=0)).mean()
    wrap = np.abs(grey[0] - grey[-1]).mean()
    assert wrap < 1.3 * inner  # the last row meets the first as any two rows meet
    assert np.array_equal(grey, _grey(PavementStyle()))
    assert not np.array_equal(grey, _grey(PavementStyle(), seed=1))


def test_no_dark_seam_runs_down_the_lane():
    """The old asphalt had two tar seams along the whole tile: dark columns."""
    cols = _lane(_grey(PavementStyle(cracks=0.0, patches=0.0, tyre_marks=0.0))).mean(axis=0)
    local = np.convolve(np.r_[cols[-10:], cols, cols[:10]], np.ones(21) / 21, mode="valid")
    # No column much darker than its neighbourhood: the old texture's seams made -4.9 to -7.3
    # (seeds 0-2); grain alone leaves about -2 at this size.
    assert (cols - local).min() > -3.5


def test_tone_and_surface_set_the_brightness():
    fresh, old = _grey(PavementStyle(asphalt_tone=0.0)), _grey(PavementStyle(asphalt_tone=1.0))
    concrete = _grey(PavementStyle("concrete"))
    assert fresh.mean() + 25 < old.mean() < concrete.mean() - 25


def test_tyre_marks_darken_the_wheel_paths():
    lane = _lane(_grey(PavementStyle(tyre_marks=1.0, cracks=0.0, patches=0.0)))
    cols = lane.mean(axis=0)
    r = (np.arange(lane.shape[1]) + 0.5) / lane.shape[1] * 3.7 - 1.85
    path = cols[np.abs(np.abs(r) - 0.85) < 0.1].mean()
    between = cols[(np.abs(r) > 0.35) & (np.abs(r) < 0.55)].mean()
    assert path < between - 5


def test_concrete_has_joints_across_every_slab_and_under_the_lane_lines():
    grey = _grey(PavementStyle("concrete", cracks=0.0, patches=0.0, tyre_marks=0.0))
    lane = _lane(grey)
    rows = lane.mean(axis=1)
    for s_m in np.arange(0.0, PERIOD_M, SLAB_M):
        row = int(round(s_m / PERIOD_M * ROWS))
        assert rows[row] < np.median(rows) - 15, s_m
    cols = lane.mean(axis=0)
    assert cols[0] < np.median(cols) - 15 and cols[-1] < np.median(cols) - 15


def test_surface_keys_are_read_and_checked():
    base = 'name = "t"\ndescription = ""\n[road]\n{}\n[[road.segments]]\nkind = "straight"\n' \
           'length_m = 50\n'
    road = parse_scenario(base.format('surface = "concrete"\ncracks = 0.5')).road
    assert road.pavement == PavementStyle("concrete", cracks=0.5)
    with pytest.raises(ScenarioError, match="surface"):
        parse_scenario(base.format('surface = "gravel"'))
    with pytest.raises(ScenarioError, match="tyre_marks"):
        parse_scenario(base.format("tyre_marks = 1.5"))


def _paint_pixels(scenario) -> tuple[int, object]:
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, 640, 360)) as rig:
        seg = rig.render_segmentation(world.data, "front")
    return int(world.marking_mask(seg).sum()), world


def test_snow_on_the_road_hides_paint_in_the_image_and_the_mask():
    snowy = load_scenario("snow")
    clear = dataclasses.replace(snowy, conditions=dataclasses.replace(snowy.conditions, snow=0.0))
    covered, world = _paint_pixels(snowy)
    bare, _ = _paint_pixels(clear)
    assert 0.5 * bare < covered < bare  # some paint hidden, most lines still there
    groups = [int(world.model.geom(i).group[0]) for i in range(world.model.ngeom)
              if world.model.geom(i).name.startswith("cond_snow_")]
    assert GROUP_WORLD in groups  # the snow over the lines: shown by the segmentation render
