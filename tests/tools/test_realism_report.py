"""tools/realism_report.py: each statistic (lanekeep/tuning/realism.py) on constructed images
with known answers, the simulator frame it measures (lanekeep/tuning/realism_report.py), and
the command line's exit status on bad input.

No real photos here (they are not ours to ship); one small render of one shipped scenario.
"""

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from lanekeep.tuning import realism as rr
from lanekeep.tuning import realism_report as report
from lanekeep.tuning.scenarios import TuningInputError

TOOL = Path(__file__).resolve().parents[2] / "tools" / "realism_report.py"


def _main(*args: str) -> subprocess.CompletedProcess:
    """tools/realism_report.py run with `args`, as from a shell."""
    return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True,
                          timeout=300)


H, W = 360, 640


def grey(value: float, h: int = H, w: int = W) -> np.ndarray:
    return np.full((h, w, 3), value, np.uint8)


def with_noise(img: np.ndarray, sigma: float, seed: int = 0) -> np.ndarray:
    """The same Gaussian noise on all three channels, so the luma's noise sigma is `sigma`."""
    noise = np.random.default_rng(seed).normal(0.0, sigma, img.shape[:2] + (1,))
    return np.clip(img.astype(float) + noise, 0, 255).round().astype(np.uint8)


# -- edges -----------------------------------------------------------------------------------
def test_flat_and_mildly_noisy_images_have_no_edges():
    assert rr.edge_density(grey(120), 150) == (0.0, 0.0)
    above, below = rr.edge_density(with_noise(grey(120), 3.0), 150)
    assert above < 0.002 and below < 0.002


def test_edge_density_splits_at_the_horizon():
    img = grey(120)
    y, x = np.mgrid[0:100, 0:W]
    img[:100][((x // 10 + y // 10) % 2) == 1] = 220  # checkerboard above row 100 only
    above, below = rr.edge_density(img, 150)
    assert above > 0.05
    assert below == 0.0
    assert math.isnan(rr.edge_density(img, 0)[0])


# -- sky ---------------------------------------------------------------------------------------
def test_half_blue_gives_half_sky_above_the_horizon():
    img = with_noise(grey(70), 4.0)  # dark grey, not sky
    img[:100] = with_noise(np.full((100, W, 3), (90, 140, 220), np.uint8), 4.0, seed=1)
    assert rr.sky_share(img, 200) == pytest.approx(0.5, abs=0.04)


def test_bright_smooth_is_sky_but_textured_or_dark_is_not():
    assert rr.sky_share(grey(200), 200) == pytest.approx(1.0)  # overcast / fog
    assert rr.sky_share(grey(60), 200) == 0.0  # night sky: not what the camera shows as sky
    textured = grey(200)
    textured[:, (np.arange(W) // 4) % 2 == 1] = 120  # bright, 8 px stripes: roadside, not sky
    assert rr.sky_share(textured, 200) < 0.05
    assert math.isnan(rr.sky_share(grey(200), 0))


# -- brightness and colour ---------------------------------------------------------------------
def test_luma_stats_below_the_horizon_only():
    img = grey(250)
    img[100:230] = 50
    img[230:] = 150
    stats = rr.luma_stats(img, 100)
    assert stats["luma_p5"] == pytest.approx(50.0, abs=0.5)
    assert stats["luma_p95"] == pytest.approx(150.0, abs=0.5)
    assert stats["luma_mean"] == pytest.approx(100.0, abs=0.5)


def test_colour_stats_of_grey_and_red():
    flat = rr.colour_stats(grey(128))
    assert flat["saturation"] == 0.0 and flat["colourfulness"] == pytest.approx(0.0)
    red = np.zeros((10, 10, 3), np.uint8)
    red[..., 0] = 255
    stats = rr.colour_stats(red)
    assert stats["saturation"] == pytest.approx(1.0)
    assert (stats["mean_r"], stats["mean_g"], stats["mean_b"]) == (255.0, 0.0, 0.0)
    # rg = 255, yb = 127.5, no spread: M = 0.3 * hypot(255, 127.5)
    assert stats["colourfulness"] == pytest.approx(0.3 * math.hypot(255, 127.5))


# -- noise -------------------------------------------------------------------------------------
@pytest.mark.parametrize("sigma", [2.0, 5.0, 10.0])
def test_noise_estimator_recovers_the_sigma_on_a_flat_image(sigma):
    assert rr.noise_sigma(with_noise(grey(128), sigma), 100) == pytest.approx(sigma, rel=0.2)


def test_noise_estimator_ignores_structure():
    y, x = np.mgrid[0:H, 0:W]
    base = 60 + 0.2 * x + 40 * ((x // 40) % 2) + 30 * ((y // 50) % 2)  # ramps and steps
    img = np.repeat(base[..., None], 3, axis=2).astype(np.uint8)
    assert rr.noise_sigma(img, 100) < 0.3
    assert rr.noise_sigma(with_noise(img, 5.0), 100) == pytest.approx(5.0, rel=0.2)
    assert rr.noise_sigma(grey(128), 100) == 0.0
    assert math.isnan(rr.noise_sigma(grey(128), H - 4))  # no whole 8x8 block below


# -- paint contrast ----------------------------------------------------------------------------
def test_road_ring_is_15_to_30_px_beside_the_paint():
    paint = np.zeros((5, 200), bool)
    paint[:, 100] = True
    cols = np.flatnonzero(rr.road_ring(paint)[0])
    assert cols.tolist() == list(range(70, 86)) + list(range(115, 131))


def test_white_stripe_on_grey_gives_the_expected_contrast():
    img = grey(100)
    img[:, 300:311] = 200
    paint = np.zeros((H, W), bool)
    paint[:, 300:311] = True
    diff, ratio, diff90 = rr.paint_contrast(img, paint, 100)
    assert (diff, ratio, diff90) == pytest.approx((100.0, 2.0, 100.0))
    assert all(math.isnan(v) for v in rr.paint_contrast(img, paint, H))  # nothing below


def test_label_band_through_dash_gaps_is_a_lower_bound():
    """A labelled line runs through the gaps: the medians see road, the 90th percentile paint."""
    img = grey(100)
    rows = np.arange(H)
    dashes = rows[(rows // 20) % 4 == 0]  # 25% duty dashes, 11 px wide
    img[dashes, 300:311] = 200
    lanes = [np.array([[305.0, 0.0], [305.0, H - 1.0]])]
    paint = rr.label_paint_mask(lanes, (H, W))
    assert paint[:, 303:308].all() and not paint[:, 302].any() and not paint[:, 308].any()
    diff, _, diff90 = rr.paint_contrast(img, paint, 0)
    assert diff == pytest.approx(0.0)
    assert diff90 == pytest.approx(100.0)


def test_read_label_lanes(tmp_path):
    path = tmp_path / "0.txt"
    path.write_text("632 280 625 290 617 300\n\n10 700 20 710\n")
    lanes = rr.read_label_lanes(path)
    assert [lane.shape for lane in lanes] == [(3, 2), (2, 2)]
    assert lanes[0][1].tolist() == [625.0, 290.0]


# -- geometry ------------------------------------------------------------------------------------
def test_camera_horizon_row_is_where_a_far_ground_point_projects():
    from lanekeep.geometry.camera_model import CameraModel

    K = np.array([[1000.0, 0, 639.5], [0, 1000.0, 359.5], [0, 0, 1]])  # noqa: N806
    cam = CameraModel.from_mounting("front", K, 1280, 720, height_m=1.4,
                                    pitch_rad=math.radians(-4.0))
    uv, in_front = cam.project_ground(np.array([[10_000.0, 0.0]]))
    assert in_front[0]
    assert rr.camera_horizon_row(cam) == pytest.approx(uv[0, 1], abs=0.5)
    assert rr.camera_horizon_row(cam) < 359.5  # pitched down: horizon above the centre


def test_frames_of_another_size_are_measured_at_the_work_width():
    img = with_noise(grey(128), 5.0)
    paint = np.zeros((H, W), bool)
    big, horizon, big_paint = rr.to_work_size(img, 100.0, paint)
    assert big.shape == (720, 1280, 3) and big_paint.shape == (720, 1280)
    assert horizon == pytest.approx(200.5)


def test_render_front_is_the_snapshot_the_car_sees(tmp_path):
    """The tool's frame is render_snapshot's front.png (effects on): snow has noise and tone."""
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.sensing.snapshot import render_snapshot

    scenario = load_scenario("snow")
    small = dataclasses.replace(scenario,
                                camera=dataclasses.replace(scenario.camera, width=320, height=180))
    rgb, paint, horizon = report.render_front(small)
    render_snapshot(small, tmp_path, effects=True)
    snapshot = cv2.cvtColor(cv2.imread(str(tmp_path / "front.png")), cv2.COLOR_BGR2RGB)
    np.testing.assert_array_equal(rgb, snapshot)
    assert paint.shape == (180, 320) and paint[int(horizon) + 1:].sum() > 50
    assert 0 < horizon < 180
    stats = rr.frame_stats(rgb, horizon, paint)
    assert stats["paint_minus_road"] > 0  # markings are brighter than asphalt
    with pytest.raises(TuningInputError, match="outside"):
        report.render_front(small, at_s=-5.0)


# -- command line ------------------------------------------------------------------------------
def test_missing_real_folder_is_one_line_and_exit_2(tmp_path):
    result = _main("--real", str(tmp_path / "nope"))
    assert result.returncode == 2
    err = result.stderr.strip()
    assert err.count("\n") == 0 and "no such folder" in err


def test_folder_without_images_is_one_line_and_exit_2(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "notes.txt").write_text("x")
    result = _main("--real", str(tmp_path))
    assert result.returncode == 2
    err = result.stderr.strip()
    assert err.count("\n") == 0 and "no .jpg" in err


def test_unknown_scenario_is_one_line_and_exit_2(tmp_path):
    cv2.imwrite(str(tmp_path / "a.png"), grey(100, 72, 128))
    result = _main("--real", str(tmp_path), "--scenarios", "no_such_scenario")
    assert result.returncode == 2
    assert "unknown scenario" in result.stderr


def test_real_folder_stats_and_table(tmp_path):
    """A synthetic "real" set with a label file: rows, a mean row, the table's columns."""
    folder = tmp_path / "tusimple_dev"
    (folder / "labels").mkdir(parents=True)
    img = with_noise(grey(100, 720, 1280), 2.0)
    img[260:, 600:611] = 200
    cv2.imwrite(str(folder / "0.png"), img)
    (folder / "labels" / "0.txt").write_text("605 300 605 700\n")
    info = report.real_set(folder, None)
    assert info.horizon_row == 250.0
    rows = report.real_folder_stats(folder, info)
    assert len(rows) == 1 and rows[0]["paint_minus_road"] == pytest.approx(100.0, abs=2.0)
    table = report.markdown_table([("TuSimple (mean of 1)", rr.mean_stats(
        [{k: v for k, v in rows[0].items() if k != "image"}]))])
    assert table.count("\n") == 2 and "| TuSimple (mean of 1) | 250 |" in table
    assert report.real_set(tmp_path, None).horizon_row is None  # unknown set: centre row, said so
