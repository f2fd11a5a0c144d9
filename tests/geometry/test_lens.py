"""Lens distortion (lanekeep/geometry/lens.py, `[camera] distortion`): frames, masks and the
detectors'
camera all bent by the same lens; a lens that folds the image is one clear error."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import cv2
import mujoco
import numpy as np
import pytest

import lanekeep
from lanekeep.scenario.schema import ScenarioError, load_scenario
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import place_on_road
from lanekeep.world.build import build

BARREL = (-0.08, 0.008, 0.0, 0.0, 0.0)  # a wide dashcam lens on the 120 deg front camera


def _with_lens(name: str, coefficients=BARREL):
    scenario = load_scenario(name)
    return dataclasses.replace(scenario, camera=dataclasses.replace(
        scenario.camera, distortion=coefficients))


def test_the_maps_invert_the_lens_model():
    """Each delivered pixel samples the render where OpenCV's model sends its ray."""
    scenario = _with_lens("clear_straight")
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, 1280, 720)) as rig:
        lens, render = rig.lenses["front"], rig.lenses["front"].render
        assert "rear" not in rig.lenses and lens.zoom > 1.0  # barrel: a little longer
        assert rig.cameras["front"].fx == pytest.approx(render.fx * lens.zoom)
        np.testing.assert_allclose(rig.distortion("front"), BARREL)
    src_x, src_y = cv2.convertMaps(lens.map_x, lens.map_y, cv2.CV_32FC1)
    rng = np.random.default_rng(0)
    v, u = rng.integers(0, 720, 200), rng.integers(0, 1280, 200)
    rays = np.c_[(src_x[v, u] - render.cx) / render.fx, (src_y[v, u] - render.cy) / render.fy,
                 np.ones(200)]
    cam = rig.cameras["front"]
    k = np.array([[cam.fx, 0, cam.cx], [0, cam.fy, cam.cy], [0, 0, 1]])
    back, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), k, np.array(BARREL))
    np.testing.assert_allclose(back.reshape(-1, 2), np.c_[u, v], atol=0.1)  # map rounding


def test_masks_and_frames_are_bent_alike():
    scenario = _with_lens("clear_straight")
    world = build(scenario)
    with CameraRig(world.model, RenderSettings.of(scenario, 1280, 720)) as rig:
        place_on_road(world, 20.0)
        mujoco.mj_forward(world.model, world.data)
        luma = rig.render_rgb(world.data, "front").astype(float).mean(axis=2)
        paint = world.marking_mask(rig.render_segmentation(world.data, "front"))
    road = ~paint & (np.arange(720)[:, None] > 450)
    assert paint.sum() > 1000
    assert np.median(luma[paint]) > np.median(luma[road]) + 60.0  # the mask lies on the paint


def test_a_lens_that_folds_the_image_is_one_clear_error(tmp_path):
    # case 4, a straight road with the paper's 120 deg camera (no [camera] table), where these
    # coefficients fold; clear_straight has the 60 deg dashcam since #59, where they do not.
    with pytest.raises(ScenarioError, match="camera.distortion: .* folds the image"):
        build(_with_lens("case4_half_shade_straight", (-0.28, 0.08, 0.0, 0.0, -0.01)))
    shipped = Path(lanekeep.__file__).parent / "scenario" / "shipped"
    body = (shipped / "case4_half_shade_straight.toml").read_text()
    path = tmp_path / "folded.toml"
    path.write_text(body + "\n[camera]\ndistortion = [-0.28, 0.08, 0, 0, -0.01]\n")
    proc = subprocess.run([sys.executable, "-m", "lanekeep.cli", "render", str(path), "--out",
                           str(tmp_path / "out")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "camera.distortion" in proc.stderr, proc.stderr


@pytest.mark.slow
def test_the_loop_keeps_its_lane_through_a_barrel_lens():
    """clear_curve with the lens, the detectors given its coefficients (as from a camera
    file): measured fused RMSE 4.9 cm over 30 s (5.2 without a lens)."""
    from lanekeep.loop.episode import Episode

    with Episode(_with_lens("clear_curve"), render_size=(1280, 720)) as episode:
        episode.run(10.0)
        report = episode.report()
    assert report.lane_departures == 0, report.table()
    assert report.sources["fused"].rmse_cm < 10.0, report.table()
