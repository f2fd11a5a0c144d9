"""The LaneNet dataset: re-mounted cameras render what their models project, labels are exact,
and a recipe reproduces its data bit for bit."""

import dataclasses
import json

import numpy as np
import pytest

from lanekeep.core.config_io import InvalidValue
from lanekeep.evaluation.dataset import (
    LABEL_ROWS,
    DatasetRecipe,
    camera_from_vector,
    frame_label,
    make_shard,
    read_recipe,
    world_seed,
    write_recipe,
)
from lanekeep.evaluation.dataset_world import CONDITION_TAGS, near_rear_mount, random_scenario
from lanekeep.scenario.schema import CameraConfig, load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build
from lanekeep.world.camera_mount import camera_from_model

SMALL = DatasetRecipe(sequences_per_world=1, frames=2, render_width=320, render_height=180)


def _paint_at(world, rig, cam, uv) -> int:
    seg = rig.render_segmentation(world.data, cam)
    u, v = np.round(uv).astype(int)
    patch = np.append(world.marking_boundary, -1)[seg[v - 1:v + 2, u - 1:u + 2]]
    return int(patch.max())


@pytest.mark.parametrize("mount", [
    dict(mount_height_m=1.25, pitch_offset_deg=-12.0, fov_scale=0.4),
    dict(mount_height_m=1.85, pitch_offset_deg=-6.0, roll_deg=2.0, yaw_offset_deg=-3.0),
])
def test_remounted_camera_renders_what_its_model_projects(mount):
    """A point of the right edge line 12 m ahead, projected by the camera model read from the
    re-mounted model, lands on that line's paint in the segmentation render."""
    base = load_scenario("clear_straight")  # the mounts move the paper camera (the file's
    base = dataclasses.replace(base, camera=dataclasses.replace(base.camera, preset="paper"))
    scenario = dataclasses.replace(base, camera=dataclasses.replace(  # is the dashcam, #59)
        base.camera, width=640, height=360, show_hood=False, **mount))
    world = build(scenario)
    x, y, yaw = place_on_road(world, 40.0)
    road = world.road
    camera = camera_from_model(world.model, "front", 640, 360)
    nominal = camera_from_model(build(base).model, "front", 640, 360)
    assert camera.height_m == pytest.approx(mount["mount_height_m"], abs=1e-6)
    assert camera.fy != pytest.approx(nominal.fy) or "fov_scale" not in mount
    line_y = road.boundary_r(0) - road.lane_center_r(scenario.road.ego_lane)
    uv, ok = camera.project_ground(np.array([12.0, line_y]))
    assert ok and 0 < uv[0] < 640 and 0 < uv[1] < 360
    with CameraRig(world.model, RenderSettings(640, 360)) as rig:
        assert _paint_at(world, rig, "front", uv) == 0  # boundary 0: the right edge


@pytest.mark.parametrize("seed", [3, 8])  # drawn rows 259 and 447
def test_a_drawn_horizon_is_where_the_camera_sees_it(seed):
    """A dataset camera drawn for horizon row h (at 720 rows) sees the ground far ahead at row
    h, not at 720 - h: until 2026-11-29 the pitch had the opposite sign to the mount's (+ =
    up), and the worlds' horizons spanned rows 270-519 instead of 200-450."""
    from lanekeep.evaluation.dataset_world import _camera

    rng = np.random.default_rng(seed)
    rng.uniform(62.0, 120.0)  # the lens, then the horizon: _camera's first two draws
    drawn = float(rng.uniform(200.0, 450.0))
    mount = _camera(np.random.default_rng(seed))
    base = load_scenario("clear_straight")
    scenario = dataclasses.replace(base, camera=dataclasses.replace(
        mount, preset="paper", roll_deg=0.0, yaw_offset_deg=0.0))
    camera = camera_from_model(build(scenario).model, "front", 1280, 720)
    uv, _ = camera.project(np.array([[1.0e4, 0.0, 0.0]]))
    assert abs(drawn - 359.5) > 40.0  # a seed whose mirror image is far from it
    assert uv[0, 1] == pytest.approx(drawn, abs=3.0)


@pytest.mark.parametrize("key, value", [("mount_height_m", 0.3), ("fov_scale", 2.0),
                                        ("roll_deg", 45.0), ("pitch_offset_deg", -40.0)])
def test_camera_mount_out_of_range_is_named(key, value):
    with pytest.raises(InvalidValue, match=key):
        CameraConfig(**{key: value})


def test_five_lanes_build():
    base = load_scenario("highway_multilane")
    road = dataclasses.replace(base.road, n_lanes=5, markings=())
    world = build(dataclasses.replace(base, road=road))
    assert world.road.n_lanes == 5 and (world.marking_boundary >= 0).any()


def test_random_worlds_vary_and_repeat():
    a, b = random_scenario(11), random_scenario(11)
    assert a == b  # a pure function of the seed
    worlds = [random_scenario(s) for s in range(12)]
    assert len({w.road.n_lanes for w in worlds}) >= 3
    assert len({w.camera.fov_scale for w in worlds}) == 12
    assert {random_scenario(3, tag).name.rsplit("_", 1)[1] for tag in CONDITION_TAGS} == set(
        CONDITION_TAGS)


def test_random_worlds_carry_road_structure_and_reflectors_from_their_own_stream():
    """#59's road structure (tar lines, seams, oil stripe, sections of another surface) and
    raised reflectors appear in some worlds and not in others, on the inner lines only; they
    are drawn from a stream of their own, so a world's other draws do not depend on them."""
    worlds = [random_scenario(s) for s in range(40)]
    for key in ("tar_lines", "seams", "oil_stripe", "surface_changes"):
        values = [getattr(w.road, key) for w in worlds]
        assert any(v > 0.0 for v in values) and any(v == 0.0 for v in values), key
    with_dots = [w for w in worlds if any(m.reflector_spacing_m > 0 for m in w.road.markings)]
    assert 0 < len(with_dots) < len(worlds)
    for w in with_dots:  # the edges never carry them
        assert w.road.markings[0].reflector_spacing_m == 0.0
        assert w.road.markings[-1].reflector_spacing_m == 0.0
    # Seeds 0-2 as drawn before the structure came (36c6a89): lanes, width, cracks, segments.
    before = {0: (4, 3.4760567709680883, 0.38731228686003427, 7),
              1: (4, 3.6083897342378752, 0.33668121959371194, 8),
              2: (4, 3.512140688694329, 0.6810763665917838, 7)}
    for seed, drawn in before.items():
        road = worlds[seed].road
        assert (road.n_lanes, road.lane_width_m, road.cracks, len(road.segments)) == drawn


def test_splits_never_share_a_world_seed():
    seeds = {split: {world_seed(SMALL, split, i) for i in range(200)}
             for split in ("train", "val", "test")}
    assert not seeds["train"] & seeds["val"] and not seeds["train"] & seeds["test"]
    assert not seeds["val"] & seeds["test"]


@pytest.fixture(scope="module")
def shard():
    return make_shard(SMALL, "test", 0)


def test_recipe_reproduces_a_sample_bit_for_bit(shard):
    again = make_shard(SMALL, "test", 0)
    assert set(again) == set(shard)
    for key, value in shard.items():
        assert np.array_equal(value, again[key], equal_nan=value.dtype.kind == "f"), key


def test_labels_lie_on_the_paint(shard):
    """Where the segmentation has paint of a boundary, the boundary's label is within 2 stored
    pixels (8 px at 1280) across: the label is the paint's centre line, through dash gaps."""
    checked = 0
    for i in range(len(shard["frames"])):
        for k in range(shard["frames"].shape[1]):
            paint, xs = shard["paint"][i, k], shard["xs"][i, k]
            h, w = paint.shape
            for b in range(xs.shape[0]):
                rows, cols = np.nonzero(paint == b + 1)
                near = rows > h * 0.6  # the near road, where a label row is ~1 stored pixel
                if near.sum() < 20 or not np.isfinite(xs[b]).any():
                    continue
                v = (rows[near] + 0.5) * 720 / h - 0.5
                label_x = np.interp(v, LABEL_ROWS, np.nan_to_num(xs[b], nan=-1e6))
                u = (cols[near] + 0.5) * 1280 / w - 0.5
                assert np.median(np.abs(u - label_x)) < 8.0, (i, k, b)
                checked += 1
    assert checked >= 2


def test_front_slots_left_of_right_and_camera_round_trip(shard):
    front = np.flatnonzero(~shard["is_rear"])
    assert len(front)
    for i in front:
        label = frame_label(shard["xs"][i, -1], shard["slots"][i, -1])
        bottom = {b.slot: b.points_px[np.argmax(b.points_px[:, 1]), 0] for b in label.boundaries}
        if 0 in bottom and 1 in bottom:
            assert bottom[0] < bottom[1]
        camera = camera_from_vector(shard["camera"][i])
        assert camera.width == 1280 and camera.height == 720 and camera.fx > 0


def test_a_shards_content_is_its_world_and_its_frames(shard, tmp_path):
    """lanekeep/evaluation/dataset_content.py reads a stored shard: the world's drawn content
    (from its seed) and a paint contrast measured on its front frames."""
    from lanekeep.evaluation.dataset_content import world_content

    path = tmp_path / "world_00000.npz"
    np.savez(path, **shard)
    content = world_content(path, 0)
    scenario = random_scenario(int(shard["world_seed"]))
    assert content.world_seed == int(shard["world_seed"]) and content.tag == str(shard["tag"])
    assert content.dashcam == (scenario.camera.preset == "dashcam")
    assert 0.0 <= content.shade_share <= 1.0 and content.vehicles_per_lane_km >= 0.0
    assert content.paint_contrast_dn > 10.0  # this world's paint shows (56.5 DN on 2026-11-29)
    assert 100.0 < content.horizon_row < 620.0


def test_recipe_cameras_default_to_both_and_old_recipes_still_load(tmp_path):
    assert DatasetRecipe().cameras == ("front", "rear")
    assert DatasetRecipe(cameras=["rear"]).cameras == ("rear",)  # as recipe.json stores it
    for bad in ((), ("rear", "front"), ("side",)):
        with pytest.raises(ValueError, match="cameras"):
            DatasetRecipe(cameras=bad)
    write_recipe(tmp_path, DatasetRecipe(seed=58, cameras=("rear",)), {"train": 1})
    assert read_recipe(tmp_path)[0] == DatasetRecipe(seed=58, cameras=("rear",))
    blob = json.loads((tmp_path / "recipe.json").read_text())
    del blob["recipe"]["cameras"]  # a recipe.json written before the options
    del blob["recipe"]["rear_mount_share"]
    (tmp_path / "recipe.json").write_text(json.dumps(blob))
    assert read_recipe(tmp_path)[0] == DatasetRecipe(seed=58)


def test_rear_only_recipe_labels_the_two_camera_recipes_rear_frames(shard):
    """`cameras=("rear",)` (#58's observer data) renders the same places, so the same labels
    as the two-camera recipe's rear sequences; only the image noise draws differ."""
    rear = make_shard(dataclasses.replace(SMALL, cameras=("rear",)), "test", 0)
    both = np.flatnonzero(shard["is_rear"])
    assert rear["is_rear"].all() and len(rear["frames"]) == len(both) == SMALL.sequences_per_world
    for key in ("xs", "slots", "ground_y", "camera"):
        np.testing.assert_array_equal(rear[key], shard[key][both], err_msg=key)
    assert rear["frames"].shape == shard["frames"][both].shape


def test_worlds_mounted_near_the_cars_rear_camera_see_the_road_as_the_loop_does():
    """`rear_mount_share` (#58's observer data): such a world keeps its road and weather but
    its rear camera is the car's own give or take a little (the loop's: 150 deg, 1.5 m), where
    the drawn mounts spread it over 104-152 deg and 1.2-1.9 m."""
    nominal = camera_from_model(build(load_scenario("clear_straight")).model, "rear")
    for seed in (3, 11, 58):
        drawn = random_scenario(seed)
        near = near_rear_mount(drawn.camera, np.random.default_rng(seed))
        assert near.jpeg_quality == drawn.camera.jpeg_quality and near.preset == "paper"
        rear = camera_from_model(build(dataclasses.replace(drawn, camera=near)).model, "rear")
        hfov = np.degrees(2 * np.arctan(rear.width / 2 / rear.fx))
        assert 142.0 < hfov < 154.0
        assert abs(rear.position_m[2] - nominal.position_m[2]) <= 0.15 + 1e-9
        assert rear.position_m[0] == pytest.approx(nominal.position_m[0])
    for bad in (-0.1, 1.5):
        with pytest.raises(ValueError, match="rear_mount_share"):
            DatasetRecipe(rear_mount_share=bad)
