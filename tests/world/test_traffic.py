"""Other vehicles look like vehicles: cars, vans and trucks stand on wheels that touch the road
(no Euler-angle posts, no floating bodies), have windows, cast their shadows away from the sun
and show paint and dark tyres to the camera behind them."""

import dataclasses

import mujoco
import numpy as np
import pytest

from lanekeep.scenario.schema import VehicleSpec, load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.world.build import build
from lanekeep.world.groups import GROUP_SHADOW
from lanekeep.world.paint import FAR_DEPTH_M
from lanekeep.world.parts import OVERLAY_Z_M
from lanekeep.world.traffic import update_dynamic
from lanekeep.world.traffic_flow import traffic_vehicles
from lanekeep.world.vehicle_assets import kind_of, vehicle_parts

MESH = int(mujoco.mjtGeom.mjGEOM_MESH)


@pytest.fixture(scope="module")
def occlusion():
    scenario = load_scenario("occlusion")
    world = build(scenario)
    update_dynamic(world, 0.0)
    mujoco.mj_forward(world.model, world.data)
    return scenario, world


def _geoms(model: mujoco.MjModel, body: str) -> dict[int, str]:
    """Geom id -> name suffix (after the body's name) of one body's geoms."""
    bid = model.body(body).id
    return {g: model.geom(g).name[len(body) + 1:] for g in range(model.ngeom)
            if model.geom_bodyid[g] == bid}


def _lowest_z(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> float:
    """Lowest corner of a geom's bounding box (its local frame), world z."""
    centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
    signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)])
    corners = data.geom_xpos[g] + (centre + signs * half) @ data.geom_xmat[g].reshape(3, 3).T
    return float(corners[:, 2].min())


def _mesh_points(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> np.ndarray:
    """World points of a mesh geom, without the buried triangle that orders an overlay's
    drawing (lanekeep/world/paint.py)."""
    mesh = model.geom_dataid[g]
    adr, n = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    local = model.mesh_vert[adr:adr + n]
    points = data.geom_xpos[g] + local @ data.geom_xmat[g].reshape(3, 3).T
    return points[points[:, 2] > -FAR_DEPTH_M / 2]


def _wheels(model, data, body):
    """(geom id, centre height, radius) of a vehicle's tyres, checking each is a round prism
    (a mesh) standing upright along the vehicle's heading, its axis level and across it."""
    frame = data.body(body).xmat.reshape(3, 3)
    out = []
    for g, name in _geoms(model, body).items():
        if not name.startswith("wheel_"):
            continue
        assert model.geom_type[g] == MESH, name
        local = (_mesh_points(model, data, g) - data.body(body).xpos) @ frame  # body frame
        along, across, up = np.ptp(local, axis=0)
        assert abs(along - up) < 0.02 * up and across < 0.8 * up, (body, name)
        out.append((g, float(local[:, 2].min() + 0.5 * up), float(0.5 * up)))
    return out


@pytest.mark.parametrize("t_s", [0.0, 12.0])  # on the straight, and in the bend
def test_every_vehicle_stands_on_four_or_more_wheels_touching_the_road(occlusion, t_s):
    scenario, world = occlusion
    update_dynamic(world, t_s)
    mujoco.mj_forward(world.model, world.data)
    specs = scenario.conditions.vehicles + traffic_vehicles(scenario, world.road)
    for track, spec in zip(world.conditions.vehicles, specs, strict=True):
        wheels = _wheels(world.model, world.data, track.name)
        assert len(wheels) >= (6 if kind_of(spec) == "truck" else 4), track.name
        for _, centre, radius in wheels:
            assert abs(centre - radius) < 0.01  # the tyre's bottom on z = 0
            assert centre + radius < 1.2  # a wheel, not a post through the cabin
            assert 0.3 <= radius <= 0.55
        assert abs(world.data.body(track.name).xpos[2]) < 1e-12  # mocap origin on the ground
    update_dynamic(world, 0.0)
    mujoco.mj_forward(world.model, world.data)


def test_bodies_ride_on_their_wheels_and_have_windows(occlusion):
    _, world = occlusion
    model, data = world.model, world.data
    for track in world.conditions.vehicles:
        geoms = _geoms(model, track.name)
        centre = min(c for _, c, _ in _wheels(model, data, track.name))
        body = [g for g, n in geoms.items() if not n.startswith(("wheel_", "hub_"))
                and model.geom_group[g] != GROUP_SHADOW]
        lowest = min(_lowest_z(model, data, g) for g in body)
        assert centre - 0.2 < lowest < 0.6, (track.name, lowest)
        windows = [n for n in geoms.values() if n.startswith("window")]
        assert {"window_front", "window_sides"} <= set(windows), (track.name, windows)
        top = max(data.geom_xpos[g, 2] for g in body)
        assert top < 4.0


def test_kinds_follow_the_dimensions():
    assert kind_of(VehicleSpec()) == "car"
    assert kind_of(VehicleSpec(length_m=5.2, width_m=2.0, height_m=2.4)) == "van"
    assert kind_of(VehicleSpec(length_m=12.0, width_m=2.5, height_m=3.6)) == "truck"
    long = [p for p in vehicle_parts(VehicleSpec(length_m=16.0, height_m=4.0))
            if p.name.startswith("wheel_")]
    assert len(long) == 8  # front axle and a tri-axle group


@pytest.mark.parametrize("dims", [(0.5, 0.5, 0.5), (3.0, 1.6, 1.4), (5.5, 2.0, 2.6),
                                  (7.5, 2.3, 2.2), (20.0, 2.55, 4.2), (20.0, 20.0, 20.0)])
def test_any_allowed_size_builds_sound_parts(dims):
    length, width, height = dims
    parts = vehicle_parts(VehicleSpec(length_m=length, width_m=width, height_m=height))
    for p in parts:
        assert p.shape == "hull" or min(p.size[:2]) > 0.0, p
        assert p.corners()[:, 2].min() > -1e-9, p  # nothing below the road
    for w in (p for p in parts if p.name.startswith("wheel_")):
        assert abs(w.corners()[:, 2].min()) < 1e-9  # on the road


def test_shadows_fall_away_from_the_sun_and_move_with_the_vehicle(occlusion):
    _, world = occlusion
    model, data = world.model, world.data
    light = model.light("sun")
    to_sun = -np.asarray(model.light_dir[light.id])
    for track in world.conditions.vehicles:
        geoms = {n: g for g, n in _geoms(model, track.name).items()}
        for name in ("shadow", "contact_shadow"):
            g = geoms[name]
            assert model.geom_group[g] == GROUP_SHADOW  # hidden from the segmentation render
            assert model.geom_bodyid[g] == model.body(track.name).id
        cast = _mesh_points(model, data, geoms["shadow"])
        np.testing.assert_allclose(cast[:, 2], OVERLAY_Z_M, atol=1e-6)
        azimuth = to_sun[:2] / np.linalg.norm(to_sun[:2])
        away = (cast[:, :2].mean(0) - data.body(track.name).xpos[:2]) @ azimuth
        assert away < -0.2, track.name  # metres, away from the sun
        contact = _mesh_points(model, data, geoms["contact_shadow"])
        assert contact[:, 2].min() > OVERLAY_Z_M


def test_at_night_vehicles_keep_only_their_contact_shadow_and_light_up():
    scenario = load_scenario("occlusion")
    night = dataclasses.replace(
        scenario, conditions=dataclasses.replace(scenario.conditions, time_of_day="night"))
    model = build(night).model
    names = {model.geom(g).name for g in range(model.ngeom)}
    assert "cond_vehicle_0_contact_shadow" in names and "cond_vehicle_0_shadow" not in names
    assert model.mat_emission[model.mat("cond_vehicle_taillight").id] >= 0.9


def test_the_camera_behind_a_car_sees_its_paint_and_dark_tyres(occlusion):
    scenario, world = occlusion
    spec = scenario.conditions.vehicles[0]
    road = world.road
    s = spec.s_m - 15.0
    x, y = road.position(s, road.lane_center_r(spec.lane))
    world.car.place(float(x), float(y), float(road.heading_at(s)))
    update_dynamic(world, 0.0)
    with CameraRig(world.model, RenderSettings.of(scenario, 640, 360)) as rig:
        rgb = rig.render_rgb(world.data, "front").astype(int)
        seg = rig.render_segmentation(world.data, "front")
    model = world.model
    geoms = _geoms(model, world.conditions.vehicles[0].name)
    paint = np.isin(seg, [g for g in geoms if model.mat(model.geom_matid[g]).name.endswith(
        "_paint")])
    tyres = np.isin(seg, [g for g, n in geoms.items() if n.startswith("wheel_")])
    vehicle = np.isin(seg, list(geoms))
    rows = np.nonzero(vehicle)[0]
    assert paint.sum() > 100 and tyres.sum() >= 8
    red = rgb[paint]
    assert np.median(red[:, 0]) > 120 and np.median(red[:, 0] - red[:, 1]) > 80  # red paint
    assert np.median(rgb[tyres].max(1)) < 40  # dark rubber
    tyre_rows = np.nonzero(tyres)[0]
    assert tyre_rows.min() > rows.min() + 0.7 * (rows.max() - rows.min())  # at the road
