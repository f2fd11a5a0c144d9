"""Bring your own detector and controller: a module outside the package, on PYTHONPATH, runs
through `lanekeep detect --detector mod:Class`, `lanekeep run --front-detectors hough,mod:Class`
and `--controller mod:Class`, and through the entry points of an installed distribution; a bad
name is one clear line and exit 2 (lanekeep/core/plugins.py, lanekeep/cli/plugins.py).

The user's module is tests/plugins/byo.py copied as `my_lane_plugins` into a temporary folder,
so that nothing of the test tree can stand in for it.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from helpers import small_scenario_text

from lanekeep.cli.main import main
from lanekeep.control.registry import ControlContext, known_controllers, make_controller
from lanekeep.core.config_io import ConfigError
from lanekeep.core.plugins import DETECTORS, plugin_labels
from lanekeep.detectors.registry import known_detectors, make_detector

MOD = "my_lane_plugins"
BYO = Path(__file__).parents[1] / "plugins" / "byo.py"
CLI = "import sys; from lanekeep.cli.main import main; sys.exit(main())"


@pytest.fixture
def plugin_dir(tmp_path) -> Path:
    """A folder holding the user's module (not on sys.path until a test puts it there)."""
    folder = tmp_path / "user_code"
    folder.mkdir()
    shutil.copy(BYO, folder / f"{MOD}.py")
    return folder


@pytest.fixture
def installed(tmp_path, plugin_dir) -> Path:
    """A folder as site-packages looks after `pip install dummy` of a distribution that
    registers the user's classes as entry points: importlib.metadata reads dist-info folders
    on sys.path, so no pip is needed."""
    info = plugin_dir / "dummy-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: dummy\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        f"[lanekeep.detectors]\nmedian_hough = {MOD}:MedianHough\n\n"
        f"[lanekeep.control.registry]\npursuit = {MOD}:PurePursuit\n")
    return plugin_dir


def small_scenario(tmp_path: Path) -> Path:
    """clear_straight at 320x180 without its [criteria] (tuned for 1280x720 frames)."""
    path = tmp_path / "small_straight.toml"
    path.write_text(small_scenario_text("clear_straight"))
    return path


def lanekeep(pythonpath: Path, *args: str) -> subprocess.CompletedProcess:
    """The CLI in a fresh interpreter with `pythonpath` on PYTHONPATH, as a user runs it."""
    env = dict(os.environ, MUJOCO_GL="egl",
               PYTHONPATH=os.pathsep.join(filter(None, [str(pythonpath),
                                                        os.environ.get("PYTHONPATH")])))
    return subprocess.run([sys.executable, "-c", CLI, *args], capture_output=True, text=True,
                          env=env, timeout=300)


def road_png(path: Path) -> Path:
    """A 640x360 picture of a straight road: grey asphalt, two white lines to a vanishing
    point, sky above."""
    image = np.full((360, 640, 3), 90, np.uint8)
    image[:160] = (200, 170, 140)  # sky (BGR)
    for x_bottom in (120, 520):
        cv2.line(image, (x_bottom, 359), (320, 160), (255, 255, 255), 6)
    cv2.imwrite(str(path), image)
    return path


def test_a_detector_outside_the_package_runs_through_detect(tmp_path, plugin_dir):
    done = lanekeep(plugin_dir, "detect", "--detector", f"{MOD}:MedianHough",
                    str(road_png(tmp_path / "road.png")))
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout.strip().splitlines()[-1])
    # the picture is symmetric about its middle: a lane centred on the camera
    assert record["raw_file"].endswith("road.png") and record["valid"]
    assert abs(record["offset_m"]) < 0.2 and record["left"][0] > 1.0 > -1.0 > record["right"][0]


def test_a_detector_outside_the_package_runs_as_a_front_model(tmp_path, plugin_dir):
    out = tmp_path / "report.json"
    done = lanekeep(plugin_dir, "run", str(small_scenario(tmp_path)), "--seconds", "2",
                    "--front-detectors", f"hough,{MOD}:MedianHough", "--json", str(out))
    assert done.returncode == 0, done.stderr
    sources = json.loads(out.read_text())["sources"]
    # labelled by its own `name`, as its author calls it, not by its import path
    assert list(sources) == ["hough", "hough:track", "median_hough", "median_hough:track",
                             "fused", "reference"]
    # it wraps a Hough detector of its own: valid on the frames the scenario's Hough is
    mine, hough = sources["median_hough"], sources["hough"]
    assert mine["valid_share"] == hough["valid_share"] > 0
    assert 0 < mine["rmse_cm"] < 50.0


def test_a_controller_outside_the_package_drives_the_car(tmp_path, plugin_dir):
    out = tmp_path / "report.json"
    done = lanekeep(plugin_dir, "run", str(small_scenario(tmp_path)), "--seconds", "2",
                    "--controller", f"{MOD}:PurePursuit", "--json", str(out))
    assert done.returncode == 0, done.stderr
    report = json.loads(out.read_text())
    assert report["lane_departures"] == 0 and report["car_max_cm"] < 50.0


def test_an_installed_distribution_registers_both_by_entry_point(tmp_path, installed):
    out = tmp_path / "report.json"
    done = lanekeep(installed, "run", str(small_scenario(tmp_path)), "--seconds", "2",
                    "--front-detectors", "hough,median_hough", "--reference-detector",
                    "median_hough", "--controller", "pursuit", "--json", str(out))
    assert done.returncode == 0, done.stderr
    report = json.loads(out.read_text())
    assert "median_hough" in report["sources"] and report["lane_departures"] == 0


def test_entry_points_are_known_names(installed, monkeypatch):
    monkeypatch.syspath_prepend(str(installed))
    assert "median_hough" in known_detectors()
    assert "pursuit" in known_controllers()
    context = ControlContext(dt_s=0.1, target_speed_mps=15.0, wheelbase_m=2.8,
                             max_steer_rad=0.6, control_lookahead_m=8.0)
    assert type(make_controller("pursuit", context)).__name__ == "PurePursuit"


def test_an_import_path_detector_is_built_as_the_registered_ones(plugin_dir, monkeypatch):
    from lanekeep.geometry.camera_model import CameraModel

    monkeypatch.syspath_prepend(str(plugin_dir))
    K = np.array([[369.29, 0.0, 639.5], [0.0, 369.29, 359.5], [0.0, 0.0, 1.0]])
    front = CameraModel.from_mounting("front", K, 1280, 720, 1.5, np.radians(10.0), x_m=1.0)
    detector = make_detector(f"{MOD}:MedianHough", front)
    assert detector.x_ref == make_detector("hough", front).x_ref
    with pytest.raises(ConfigError, match=f"'{MOD}:NotADetector'.*not a Detector.*detect"):
        make_detector(f"{MOD}:NotADetector", front)


def test_a_plug_in_given_by_import_path_is_labelled_by_its_own_name(plugin_dir, monkeypatch):
    monkeypatch.syspath_prepend(str(plugin_dir))
    mine = f"{MOD}:MedianHough"
    assert plugin_labels(["hough", mine], DETECTORS) == ["hough", "median_hough"]
    # its name taken (a built-in's or a report's column, a name given beside it, the label
    # of another), no `name`, or a path that does not import: the import path
    assert plugin_labels(["hough", mine], DETECTORS, reserved={"median_hough"}) == [
        "hough", mine]
    assert plugin_labels(["median_hough", mine], DETECTORS) == ["median_hough", mine]
    assert plugin_labels([mine, mine], DETECTORS) == ["median_hough", mine]
    assert plugin_labels([f"{MOD}:PurePursuit", "no_such_module:X"], DETECTORS) == [
        f"{MOD}:PurePursuit", "no_such_module:X"]


def _one_clear_line(capsys, code: int, *needles: str) -> str:
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2 and len(lines) == 1, captured.err
    assert "Traceback" not in captured.err
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


@pytest.mark.parametrize(("option", "value", "why"), [
    ("--front-detectors", "hough,no_such_module:Det", "cannot import 'no_such_module'"),
    ("--front-detectors", f"hough,{MOD}:Missing", "has no attribute 'Missing'"),
    ("--front-detectors", f"hough,{MOD}:NOT_CALLABLE", "not a class or function"),
    ("--reference-detector", "nope", "unknown detector 'nope'"),
    ("--controller", f"{MOD}:Nope", "has no attribute 'Nope'"),
    ("--controller", "no.such.module:Ctl", "cannot import 'no.such.module'"),
    ("--controller", "lqr", "unknown controller 'lqr'"),
])
def test_a_bad_name_on_run_is_one_line_naming_it(option, value, why, tmp_path, plugin_dir,
                                                 monkeypatch, capsys):
    monkeypatch.syspath_prepend(str(plugin_dir))
    out = tmp_path / "report.json"
    code = main(["run", "clear_straight", "--seconds", "0.2", option, value,
                 "--json", str(out)])
    _one_clear_line(capsys, code, option, value.split(",")[-1], why)
    assert not out.exists()


def test_a_bad_name_in_a_scenario_file_names_its_key(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(small_scenario(tmp_path).read_text()
                    + "\n[control]\ncontroller = 'no_such_module:Ctl'\n")
    code = main(["bench", str(path), "--seconds", "0.2"])
    _one_clear_line(capsys, code, "bad.toml", "control.controller", "no_such_module:Ctl")


def test_a_bad_detector_on_detect_is_one_line(tmp_path, capsys):
    code = main(["detect", "--detector", "no_such_module:Det",
                 str(road_png(tmp_path / "road.png"))])
    _one_clear_line(capsys, code, "no_such_module:Det", "cannot import")


@pytest.mark.parametrize(("option", "value", "why"), [
    # a detector given as the controller: its constructor fails on the ControlContext
    ("--controller", f"{MOD}:MedianHough", "failed to build"),
    ("--front-detectors", f"{MOD}:NotADetector", "not a Detector"),
])
def test_a_plugin_that_breaks_in_the_episode_is_one_line(option, value, why, tmp_path,
                                                         plugin_dir):
    """Found and imported, it fails once the episode builds it (renderers already open): one
    line naming it, exit 2, and no traceback from the plugin or from EGL at exit."""
    done = lanekeep(plugin_dir, "run", str(small_scenario(tmp_path)), "--seconds", "0.2",
                    option, value)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and "EGLError" not in done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and f"'{value}'" in lines[0] and why in lines[0], done.stderr
