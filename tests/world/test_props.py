"""Roadside props (lanekeep/world/props.py): they compile, stand on the ground beyond the gravel
(only overhead parts span the lanes), cast their shadows away from the sun, leave the road
unshaded where no shadow zone is, are drawn from the seed, and put edges above the horizon."""

import dataclasses
import math

import cv2
import mujoco
import numpy as np
import pytest

from lanekeep.core.config_io import InvalidValue
from lanekeep.scenario.roadside import Roadside
from lanekeep.scenario.schema import ScenarioError, load_scenario, parse_scenario
from lanekeep.scenario.traffic import Traffic
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.world import appearance
from lanekeep.world import prop_assets as assets
from lanekeep.world.build import build, build_spec, check_buildable
from lanekeep.world.compiled import COMPILED_WORLDS
from lanekeep.world.lighting import sun_direction
from lanekeep.world.parts import WorldLayout
from lanekeep.world.props import PROP_CELL_M, _add_shadows, prop_kind

CLEARANCE_M = 4.5  # anything lower than this is no overhead part and must stay off the road


def _prop_vertices(spec: mujoco.MjSpec, prefix: str = "props_") -> dict[str, np.ndarray]:
    """Each prop kind's vertices, over all its cells."""
    verts: dict[str, list[np.ndarray]] = {}
    for m in spec.meshes:
        if m.name.startswith(prefix) and not m.name.startswith("props_shadow"):
            verts.setdefault(prop_kind(m.name), []).append(
                np.asarray(m.uservert, float).reshape(-1, 3))
    return {kind: np.concatenate(parts) for kind, parts in verts.items()}


@pytest.fixture(scope="module")
def highway():
    scenario = load_scenario("highway_multilane")
    road = scenario.build_road()
    spec, _, info = build_spec(scenario, road)
    return scenario, road, spec, info


def test_highway_props_compile_into_one_geom_per_material_and_cell(highway):
    scenario, road, spec, _ = highway
    model = spec.compile()
    names = {model.geom(i).name for i in range(model.ngeom)}
    kinds = {prop_kind(n) for n in names if n.startswith("props_")}
    for kind in ("props_steel", "props_concrete", "props_pole", "props_hills", "props_shadow_p0",
                 "props_sign_0", "props_sign_1", "props_trunk"):
        assert kind in kinds
    assert len(kinds) <= 14  # merged per material
    # ... and per cell: each prop lies in the cell of its bounding box's centre, so a cell's
    # trees reach at most a crown's width beyond it (the rails, woods and hills run on).
    for mesh in spec.meshes:
        if prop_kind(mesh.name).startswith(("props_foliage", "props_conifer", "props_trunk")):
            xy = np.asarray(mesh.uservert, float).reshape(-1, 3)[:, :2]
            assert np.ptp(xy, axis=0).max() < PROP_CELL_M + 20.0, mesh.name
    crowns = sum(prop_kind(n).startswith("props_foliage") for n in names)
    assert crowns >= road.length_m / PROP_CELL_M  # the trees line the road: many cells


def test_props_stand_beyond_the_gravel_and_on_the_ground(highway):
    _, road, spec, _ = highway
    layout = WorldLayout()
    right, left = (assets.verge_r(road, side, layout) for side in ("right", "left"))
    for name, verts in _prop_vertices(spec).items():
        if name == "props_hills":
            continue
        low = verts[verts[:, 2] < CLEARANCE_M]
        s, r = road.local_coordinates(low[:, :2])
        beside = (s < 0.0) | (s > road.length_m) | (r <= right + 1e-6) | (r >= left - 1e-6)
        assert beside.all(), f"{name}: {np.sum(~beside)} low vertices over the road or gravel"
        if not name.startswith(("props_foliage", "props_conifer", "props_sign")):  # held up
            assert verts[:, 2].min() == pytest.approx(0.0, abs=1e-6), f"{name} floats"


def test_overhead_parts_leave_clearance_over_the_lanes(highway):
    _, road, spec, _ = highway
    over = []
    for name, verts in _prop_vertices(spec).items():
        if name == "props_hills":  # far beyond the road's ends, where its line runs on
            continue
        s, r = road.local_coordinates(verts[:, :2])
        inside = (r > road.boundary_r(0)) & (r < road.boundary_r(road.n_lanes))
        inside &= (s >= 0.0) & (s <= road.length_m)
        over.append(verts[inside, 2])
    over = np.concatenate(over)
    assert len(over) > 0  # the gantry, its signs and the overpass deck span the lanes
    assert over.min() >= 5.0


def test_a_pole_casts_its_shadow_away_from_the_sun():
    spec = mujoco.MjSpec()
    info = type("Info", (), {"shadow_polygons": []})()
    props = assets.Props()
    height = 10.0
    props.add("prop_pole", assets.prism(np.zeros(3), height, 0.1))
    for az_deg, el_deg in ((30.0, 40.0), (200.0, 60.0)):
        az, el = math.radians(az_deg), math.radians(el_deg)
        to_sun = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        info.shadow_polygons = []
        _add_shadows(spec, props, to_sun, info, transmission=0.3)
        (poly,) = info.shadow_polygons
        tip = poly[np.argmax(np.hypot(poly[:, 0], poly[:, 1]))]
        assert np.hypot(*tip) == pytest.approx(height / math.tan(el), rel=0.05)
        assert tip @ to_sun[:2] < 0.0  # on the side away from the sun
        spec = mujoco.MjSpec()


def test_the_overpass_shades_the_road_where_the_sun_puts_its_deck(highway):
    scenario, road, _, info = highway
    assert scenario.roadside.overpasses_m
    to_sun = sun_direction(scenario.conditions, road)
    shift = -to_sun[:2] / to_sun[2] * 6.4  # the deck's mid height
    lanes = np.linspace(road.boundary_r(0) + 0.5, road.boundary_r(road.n_lanes) - 0.5, 9)
    for s_bridge in scenario.roadside.overpasses_m:  # every bridge
        t = np.array([math.cos(road.heading_at(s_bridge)), math.sin(road.heading_at(s_bridge))])
        s_shade = s_bridge + float(shift @ t)
        assert info.shaded(road.position(np.full(9, s_shade), lanes)).all(), s_bridge
        assert not info.shaded(road.position(np.full(9, s_shade - 25.0), lanes)).any(), s_bridge


def test_scenery_shadows_stay_off_the_road():
    """case 1's shade is its shadow zone's, in the first quarter: the town's other buildings,
    its trees and poles throw none on the road."""
    scenario = load_scenario("case1_building_shadows")
    assert scenario.roadside.buildings_per_100m > 0 and scenario.roadside.trees_per_100m > 0
    road = scenario.build_road()
    _, _, info = build_spec(scenario, road)
    s, r = np.meshgrid(np.arange(120.0, road.length_m, 0.5),
                       np.linspace(road.boundary_r(0), road.boundary_r(road.n_lanes), 9))
    assert not info.shaded(road.position(s.ravel(), r.ravel())).any()


def test_props_are_drawn_from_the_seed():
    scenario = load_scenario("clear_curve")
    road = scenario.build_road()
    first = _prop_vertices(build_spec(scenario, road)[0])
    again = _prop_vertices(build_spec(scenario, road)[0])
    assert first.keys() == again.keys()
    for name in first:
        assert np.array_equal(first[name], again[name])
    other = dataclasses.replace(scenario, seed=scenario.seed + 1)
    moved = _prop_vertices(build_spec(other, other.build_road())[0])
    assert not np.array_equal(first["props_trunk"], moved["props_trunk"])


def test_roadside_keys_are_checked():
    with pytest.raises(InvalidValue):
        Roadside(guard_rail_sides=("middle",))
    with pytest.raises(InvalidValue):
        Roadside(guard_rail_sides=("left",), barrier_sides=("left",))
    with pytest.raises(InvalidValue):
        Roadside(skyline="mountains")
    text = ('name = "t"\ndescription = "t"\n[road]\n[[road.segments]]\nkind = "straight"\n'
            'length_m = 100\n[roadside]\n')
    with pytest.raises(ScenarioError, match="roadside.poles"):
        parse_scenario(text + "poles = 3\n")
    with pytest.raises(ScenarioError, match="overpasses_m"):
        check_buildable(parse_scenario(text + "overpasses_m = [150.0]\n"))


def _edges_above_horizon(scenario) -> float:
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, 320, 180)) as rig:
        rgb = rig.render_rgb(world.data, "front")
    edges = cv2.Canny(cv2.GaussianBlur(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY), (5, 5), 1.0),
                      50, 150)
    return float((edges[:90] > 0).mean())  # the horizon lies near the middle row


def test_props_put_edges_above_the_horizon(monkeypatch):
    # props only: no traffic and a cloudless sky (clouds are edges above the horizon too)
    monkeypatch.setattr(appearance, "CLEAR_SKY_CLOUDS", 0.0)
    scenario = dataclasses.replace(load_scenario("clear_straight"), traffic=Traffic())  # props only
    bare = dataclasses.replace(scenario, roadside=Roadside())
    with COMPILED_WORLDS.disabled():  # the patched sky is no world for later builds to reuse
        assert _edges_above_horizon(scenario) > 2.0 * _edges_above_horizon(bare) + 0.002
