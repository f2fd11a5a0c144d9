"""Vegetation and its shade (issue #59): verge grass that is dry and tufted rather than a
smooth saturated lawn, leaf textures with dark gaps and a self-shaded underside, scenery trees
whose soft shadows follow their crowns down to their trunks, and the contact shadow (ambient
occlusion) under every vehicle."""

import numpy as np
import pytest

from lanekeep.scenario.schema import load_scenario
from lanekeep.tuning.realism_gaps import abs_laplacian, green_mask
from lanekeep.world import prop_assets as assets
from lanekeep.world import prop_textures, textures
from lanekeep.world.build import build_spec
from lanekeep.world.parts import OVERLAY_Z_M
from lanekeep.world.shade import TRANSLUCENT_ALPHA, soft_shadow_atlas
from lanekeep.world.traffic import CONTACT_DARKNESS, contact_darkness


def test_grass_is_a_dry_tufted_verge_not_a_saturated_lawn():
    grass = textures.grass(np.random.default_rng(3))
    assert green_mask(grass).mean() < 0.4  # the old lawn: all of it saturated green
    luma = grass.astype(float) @ [0.299, 0.587, 0.114]
    assert luma.mean() < 80  # the old lawn: ~95
    assert np.percentile(luma, 5) < 0.45 * np.median(luma)  # dark gaps between the tufts
    assert abs_laplacian(grass).mean() > 8.0  # texture at the tuft scale
    tan = (grass[..., 0] > grass[..., 1]) & (grass[..., 1] > grass[..., 2])
    assert 0.2 < tan.mean() < 0.8  # dry patches among olive and green ones
    assert np.array_equal(grass, textures.grass(np.random.default_rng(3)))


def test_grass_draws_what_the_lawn_drew():
    """The textures made after the grass from the same generator do not move."""
    a, b = np.random.default_rng(5), np.random.default_rng(5)
    textures.grass(a)
    textures.tiled_noise(b, 256, 0.8)
    textures.tiled_noise(b, 256, 16.0)
    assert a.random() == b.random()


def test_leaves_are_dark_with_gaps_and_crowns_are_darker_underneath():
    leaves = prop_textures.foliage(np.random.default_rng(1)).astype(float)
    luma = leaves @ [0.299, 0.587, 0.114]
    assert luma.mean() < 60  # real crowns: V 40-60
    assert np.percentile(luma, 90) > 2.5 * np.percentile(luma, 10)  # clumps and gaps
    crown = prop_textures.foliage(np.random.default_rng(1), underside=True).astype(float)
    rows = crown.mean(axis=(1, 2))
    assert rows[:16].mean() < 0.6 * rows[-32:].mean()  # v = 0: the crown's underside


@pytest.fixture(scope="module")
def clear_straight():
    scenario = load_scenario("clear_straight")
    spec, _, _ = build_spec(scenario, scenario.build_road())
    return scenario, spec


def test_scenery_trees_cast_one_soft_shadow_each_in_one_geom(clear_straight):
    _, spec = clear_straight
    model = spec.compile()
    names = [model.geom(i).name for i in range(model.ngeom)]
    assert "props_shadow_trees" in names
    alpha = np.frombuffer(spec.texture("props_shadow_trees_shade").data, np.uint8)[3::4]
    soft = (alpha > 5) & (alpha < alpha.max() - 5)
    assert soft.sum() > 0.2 * (alpha > 5).sum()  # soft edges and gaps, not one hard blob


def test_a_tree_shadow_follows_its_crown_and_meets_its_trunk():
    props = assets.Props()
    detail = np.random.default_rng(0)
    assets.tree(props, np.random.default_rng(1), np.array([10.0, 20.0]), 5.0, 3.0,
                detail=detail)
    to_sun = np.array([0.5, -0.3, 0.8])
    to_sun /= np.linalg.norm(to_sun)
    rgba, mesh = soft_shadow_atlas([props.casters], to_sun, 0.3, np.random.default_rng(2))
    alpha = rgba[..., 3].astype(float) * TRANSLUCENT_ALPHA / 255.0
    np.testing.assert_allclose(mesh.vertices[:, 2], OVERLAY_Z_M)
    quad, uv = mesh.vertices[:4, :2], mesh.texcoords[:4]

    def alpha_at(xy):  # texture row k at v = (k + 0.5) / height
        f = (np.asarray(xy) - quad[0]) / (quad[2] - quad[0])
        u, v = uv[0] + f * (uv[2] - uv[0])
        return alpha[int(v * alpha.shape[0]), int(u * alpha.shape[1])]

    per_pass = 1.0 - np.sqrt(0.3)
    away = -to_sun[:2] / np.linalg.norm(to_sun[:2])
    trunk = [alpha_at(np.array([10.0, 20.0]) + d * away) for d in np.linspace(0.2, 1.5, 14)]
    assert np.mean(trunk) > 0.5 * per_pass  # the shade starts at the trunk's foot
    crown = np.array([10.0, 20.0]) - 5.0 * to_sun[:2] / to_sun[2]  # under the crown's centre
    assert alpha_at(crown) > 0.5 * per_pass
    assert alpha_at(np.array([10.0, 20.0]) + 1.3 * to_sun[:2] / np.linalg.norm(to_sun[:2])) \
        < 0.05 * per_pass  # nothing towards the sun
    assert alpha.max() <= per_pass + 0.01  # no darker than the umbra


def test_vehicles_stand_on_a_soft_dark_contact_shadow():
    dark = contact_darkness(4.5, 1.8)
    n = dark.shape[0]
    assert dark[n // 2, n // 2] == pytest.approx(CONTACT_DARKNESS, abs=0.01)  # under the middle
    assert dark[0].max() < 0.01 and dark[:, 0].max() < 0.01  # faded out at the fringe
    row = dark[n // 2]
    assert np.all(np.diff(row[: n // 2]) >= -1e-6)  # rising towards the middle: no hard edge
    assert ((row > 0.1) & (row < 0.5)).sum() >= 2


def test_contact_shadows_are_textured_per_vehicle():
    scenario = load_scenario("occlusion")
    spec, _, _ = build_spec(scenario, scenario.build_road())
    tex = spec.texture("cond_vehicle_0_contact_shadow")
    alpha = np.frombuffer(tex.data, np.uint8)[3::4]
    assert alpha.max() > 150 and alpha.min() == 0


def test_shrubs_sit_on_the_ground_in_the_darkest_tint():
    props = assets.Props()
    assets.shrub(props, np.random.default_rng(4), np.array([5.0, 5.0]), 1.2, 1.6)
    verts = props.meshes[assets.SHRUB_MATERIAL][0].vertices
    assert verts[:, 2].min() == pytest.approx(0.0, abs=1e-9) and verts[:, 2].max() <= 1.6 + 1e-9
    tints = [np.mean(t[:3]) for t in assets.FOLIAGE_TINTS]
    assert int(assets.SHRUB_MATERIAL.rsplit("_", 1)[1]) == int(np.argmin(tints))


def test_the_woods_have_ragged_tops():
    from lanekeep.world.prop_meshes import tree_belt

    n = 16
    radii, heights = np.full(n, 300.0), np.full(n, 10.0)
    ragged = np.random.default_rng(0).uniform(-0.3, 0.15, (n, 4))
    mesh = tree_belt(np.zeros(2), radii, heights, np.ones(n, bool), ragged=ragged)
    tops = mesh.vertices[mesh.vertices[:, 2] > 0.0, 2]
    assert tops.std() > 0.5 and 6.9 < tops.min() and tops.max() < 11.6
    flat = tree_belt(np.zeros(2), radii, heights, np.ones(n, bool))
    assert np.allclose(flat.vertices[flat.vertices[:, 2] > 0.0, 2], 10.0)
