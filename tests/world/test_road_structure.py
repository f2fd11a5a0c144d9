"""The structure of real roads that a detector may take for a line: tar lines, construction
seams, the oil stripe, sections of another surface along the road, and raised reflective
markers (lanekeep/world/pavement.py, lanekeep/geometry/markings.py, lanekeep/world/build.py)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from lanekeep.geometry.markings import REFLECTOR_M, MarkingStyle, layout
from lanekeep.scenario.pavement import PavementStyle
from lanekeep.scenario.schema import ScenarioError, load_scenario, parse_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.world.build import build
from lanekeep.world.pavement import LANE_U, SEAM_INSET_M, SECTION_M, pavement, sections

PERIOD_M = 9.0
ROWS = 512
LANE_M = 3.7
PLAIN = PavementStyle(cracks=0.0, patches=0.0, tyre_marks=0.0)


def _lane(style: PavementStyle, seed: int = 0) -> np.ndarray:
    grey = pavement(np.random.default_rng(seed), style, LANE_M, 1.5, PERIOD_M, ROWS)
    grey = grey.astype(float).mean(axis=2)
    return grey[:, : int(round(LANE_U * grey.shape[1]))]


def test_the_structure_keys_are_off_by_default_and_leave_the_texture_as_it_was():
    style = PavementStyle()
    assert (style.tar_lines, style.seams, style.oil_stripe, style.surface_changes) == (0,) * 4
    explicit = dataclasses.replace(style, tar_lines=0.0, seams=0.0, oil_stripe=0.0)
    assert np.array_equal(_lane(style), _lane(explicit))


def test_tar_lines_are_dark_bands_mostly_along_the_road():
    plain, tarred = _lane(PLAIN), _lane(dataclasses.replace(PLAIN, tar_lines=1.0))
    base = np.median(plain)
    dark = tarred < base - 40  # sealant: near black on mid-grey asphalt
    assert 0.01 < dark.mean() < 0.15, dark.mean()
    assert dark.mean() > 5.0 * (plain < base - 40).mean()  # (a few dark stones there)
    # lengthwise: a dark pixel's neighbour along the road (rows) is dark more often than its
    # neighbour across it
    along = (dark[1:] & dark[:-1]).sum() / dark.sum()
    across = (dark[:, 1:] & dark[:, :-1]).sum() / dark.sum()
    assert along > across, (along, across)
    assert not np.array_equal(tarred, _lane(dataclasses.replace(PLAIN, tar_lines=1.0), seed=1))


def test_the_seam_is_a_straight_line_a_little_inside_the_left_lane_line():
    cols = _lane(dataclasses.replace(PLAIN, seams=1.0)).mean(axis=0)
    px_per_m = len(cols) / LANE_M
    lo = len(cols) - int(SEAM_INSET_M[1] * px_per_m) - 2
    hi = len(cols) - int(SEAM_INSET_M[0] * px_per_m) + 2
    seam = lo + int(np.argmin(cols[lo:hi]))
    # a whole column darker than the lane beside it: straight down the texture
    assert cols[seam] < np.median(cols) - 6, (cols[seam], np.median(cols))
    assert cols[: len(cols) // 2].min() > np.median(cols) - 4  # nothing like it elsewhere


def test_the_oil_stripe_darkens_the_lane_centre_and_the_wheel_paths_stay_lighter():
    lane = _lane(dataclasses.replace(PLAIN, oil_stripe=1.0))
    cols = lane.mean(axis=0)
    r = (np.arange(len(cols)) + 0.5) / len(cols) * LANE_M - 0.5 * LANE_M
    centre = cols[np.abs(r) < 0.2].mean()
    paths = cols[np.abs(np.abs(r) - 0.85) < 0.15].mean()
    plain = _lane(PLAIN).mean()
    assert centre < plain - 10 and paths > centre + 12, (centre, paths, plain)


def test_sections_cover_about_their_share_in_pieces_of_the_stated_length():
    rng = np.random.default_rng(3)
    parts = sections(rng, 0.0, 20000.0, 0.3)
    lengths = np.array([b - a for a, b in parts])
    assert np.all(lengths[:-1] >= SECTION_M[0] - 1e-9) and np.all(lengths <= SECTION_M[1])
    assert all(b0 < a1 for (_, b0), (a1, _) in zip(parts[:-1], parts[1:], strict=True))
    assert lengths.sum() / 20000.0 == pytest.approx(0.3, abs=0.05)
    assert sections(np.random.default_rng(3), 0.0, 20000.0, 0.3) == parts
    assert sections(rng, 0.0, 500.0, 0.0) == []


def test_structure_keys_are_read_and_checked():
    base = ('name = "t"\ndescription = ""\n[road]\n{}\n[[road.segments]]\nkind = "straight"\n'
            'length_m = 50\n')
    road = parse_scenario(base.format('tar_lines = 0.5\nsurface_changes = 0.3\n'
                                      'section_surface = "concrete"')).road
    assert road.pavement == PavementStyle(tar_lines=0.5, surface_changes=0.3,
                                          section_surface="concrete")
    with pytest.raises(ScenarioError, match="section_surface"):
        parse_scenario(base.format('section_surface = "gravel"'))
    with pytest.raises(ScenarioError, match="seams"):
        parse_scenario(base.format("seams = 2"))


def test_reflectors_sit_in_the_middle_of_every_kth_gap_of_a_dashed_line():
    style = MarkingStyle("dashed", dash_m=3.0, gap_m=9.0, reflector_spacing_m=24.0)
    pieces = layout(style, 1, 0.5, 120.0)
    blocks = [p for p in pieces if p.reflector]
    dashes = [p for p in pieces if not p.reflector]
    assert dashes == layout(dataclasses.replace(style, reflector_spacing_m=0.0), 1, 0.5, 120.0)
    centres = [0.5 * (p.s_start_m + p.s_end_m) for p in blocks]
    np.testing.assert_allclose(centres, 7.5 + 24.0 * np.arange(5))
    assert all(p.dot and p.width_m == REFLECTOR_M and p.r_m == 0.5 for p in blocks)
    assert [p.s_start_m for p in pieces] == sorted(p.s_start_m for p in pieces)
    alone = layout(MarkingStyle("none", reflector_spacing_m=10.0), 0, 0.0, 100.0)
    assert len(alone) == 10 and all(p.reflector for p in alone)
    with pytest.raises(Exception, match="reflector_spacing_m"):
        MarkingStyle(reflector_spacing_m=-1.0)


def _render(scenario, width=640, height=360):
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, width, height)) as rig:
        seg = rig.render_segmentation(world.data, "front")
        rgb = rig.render_rgb(world.data, "front")
    return world, seg, rgb


def _no_traffic(name: str):
    scenario = load_scenario(name)
    return dataclasses.replace(scenario, conditions=dataclasses.replace(
        scenario.conditions, vehicles=()))


def test_road_structure_changes_the_image_but_not_the_marking_masks():
    scenario = _no_traffic("clear_straight")
    road = dataclasses.replace(scenario.road, tar_lines=0.0, seams=0.0, oil_stripe=0.0,
                               surface_changes=0.0)
    plain = dataclasses.replace(scenario, road=road)
    busy = dataclasses.replace(scenario, road=dataclasses.replace(
        road, tar_lines=1.0, seams=1.0, oil_stripe=1.0, surface_changes=0.9))
    w0, seg0, rgb0 = _render(plain)
    w1, seg1, rgb1 = _render(busy)
    assert np.array_equal(w0.marking_mask(seg0), w1.marking_mask(seg1))
    assert np.abs(rgb0.astype(float) - rgb1).mean() > 2.0
    names = [w1.model.geom(i).name for i in range(w1.model.ngeom)]
    assert "road_other" in names and "road_other" not in [
        w0.model.geom(i).name for i in range(w0.model.ngeom)]


def test_reflectors_are_their_boundarys_marking_and_stand_out():
    scenario = _no_traffic("clear_straight")
    styles = list(scenario.road.markings)
    styles[1] = MarkingStyle("none", reflector_spacing_m=4.0)  # markers alone: no paint
    road = dataclasses.replace(scenario.road, markings=tuple(styles))
    world, seg, rgb = _render(dataclasses.replace(scenario, road=road), 1280, 720)
    mask = world.marking_mask(seg, 1)
    assert 10 <= mask.sum() < 1500, mask.sum()
    grey = rgb.astype(float).mean(axis=2)
    beside = np.roll(mask, 8, axis=1) & ~mask
    assert grey[mask].mean() > grey[beside].mean() + 30
    names = [world.model.geom(i).name for i in range(world.model.ngeom)]
    assert names.count("marking_b1_reflectors") == 1  # one geom for the whole road


def test_paint_across_a_concrete_section_is_lighter_than_the_slab():
    """The paint on a section is composed against the section's surface: on light concrete
    slabs it stands out as a light line (it was composed against the asphalt and, a little
    darker than the slab, all but vanished: 7-19 DN above the slab beside it)."""
    scenario = _no_traffic("clear_straight")
    road = dataclasses.replace(scenario.road, surface="asphalt", section_surface="concrete",
                               surface_changes=0.9)
    world, seg, rgb = _render(dataclasses.replace(scenario, road=road))
    names = [world.model.geom(i).name for i in range(world.model.ngeom)]
    assert any(n.startswith("marking_b") and n.endswith("_o_rgb") for n in names)
    grey = rgb.astype(float).mean(axis=2)
    for boundary in range(road.n_lanes + 1):
        mask = world.marking_mask(seg, boundary)
        for shift in (8, -8):
            beside = np.roll(grey, -shift, axis=1)  # the road `shift` px beside each pixel
            on_slab = mask & ~np.roll(mask, -shift, axis=1) & (beside > 140)
            assert on_slab.sum() > 100, (boundary, shift)
            assert np.median(grey[on_slab] - beside[on_slab]) > 25, (boundary, shift)
