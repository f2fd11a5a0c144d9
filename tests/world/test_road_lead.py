"""The road goes on straight before its start and after its end (WorldLayout.lead_m), so the
rear camera at the start pose does not see the asphalt end a few metres behind the car."""

from __future__ import annotations

import numpy as np

from lanekeep.geometry.markings import MarkingStyle
from lanekeep.geometry.road import Road, SegmentSpec
from lanekeep.scenario.schema import load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.world.build import build
from lanekeep.world.parts import WorldLayout


def _road(kind: str) -> Road:
    styles = (MarkingStyle(), MarkingStyle(kind=kind), MarkingStyle())
    return Road([SegmentSpec(kind="straight", length_m=100.0)], n_lanes=2, markings=styles,
                rng_seed=3)


def test_the_lead_adds_paint_before_and_after_and_keeps_the_road_itself():
    for kind in ("solid", "dashed", "double", "worn"):
        road = _road(kind)
        plain = road.marking_pieces()
        led = road.marking_pieces(60.0)
        assert [p for p in led if 0.0 <= p.s_start_m < road.length_m] == plain
        assert min(p.s_start_m for p in led) < -40.0
        assert max(p.s_end_m for p in led) > road.length_m + 40.0
        assert all(p.s_end_m > p.s_start_m for p in led)


def test_dashes_keep_their_period_across_the_start():
    road = _road("dashed")
    starts = sorted(p.s_start_m for p in road.marking_pieces(60.0) if p.boundary == 1)
    steps = np.diff(starts)
    style = road.markings[1]
    np.testing.assert_allclose(steps[: len(steps) - 2], style.dash_m + style.gap_m)


def test_the_rear_camera_at_the_start_sees_paint_to_the_horizon():
    scenario = load_scenario("clear_straight")
    world = build(scenario)  # the car is at its start pose, 10 m into the road
    assert WorldLayout().lead_m >= 40.0
    with CameraRig(world.model, RenderSettings.of(scenario, 640, 360)) as rig:
        seg = rig.render_segmentation(world.data, "rear")
    rows = np.nonzero(world.marking_mask(seg).any(axis=1))[0]
    # Paint reaches the horizon's neighbourhood: row 151 of 360 here; without the lead the
    # lines stop 10 m behind the car, at row 166 (measured with WorldLayout(lead_m=0)).
    assert rows.min() <= 158, rows.min()


def test_a_closed_track_has_no_lead_across_itself():
    """tools/soak's track ends where it starts: a straight lead after its end would lie over
    its first straight (and one before its start across its last curve), two surfaces in one
    place; a closed road is built without them."""
    from pathlib import Path

    from lanekeep.scenario.schema import load_scenario
    from lanekeep.world.build import build_spec

    track = load_scenario(Path(__file__).parents[2] / "tools" / "soak" / "loop_track.toml")
    road = track.build_road()
    assert road.closed and not load_scenario("clear_curve").build_road().closed
    spec, _, _ = build_spec(track, road)
    model = spec.compile()
    ends = [road.segment_bounds()[0][0], road.segment_bounds()[-1][1]]
    assert ends == [0.0, road.length_m]
    assert len([g for g in range(model.ngeom) if model.geom(g).name.startswith("road_")]) \
        == len(road.segment_bounds())
