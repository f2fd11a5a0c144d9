"""Bad input is one clear line: exit code 2, the problem's key named, no traceback, no file.

Checks across a scenario's fields are made when its world is built (a speed bump beyond the
road's end, a vehicle in a lane that does not exist, shadows the sun cannot cast); the CLI
makes them before anything runs or is written, `lanekeep bench` before any worker starts.
`lanekeep --debug` lets the exception through instead.
"""

import subprocess
import sys
from pathlib import Path

import pytest

from lanekeep.cli.main import main
from lanekeep.core.config_io import ConfigError
from lanekeep.scenario.schema import ScenarioError, load_scenario

SHIPPED = Path(load_scenario("clear_straight").source).read_text()


def _scenario(tmp_path: Path, extra: str) -> str:
    assert "[conditions]" not in SHIPPED  # the extra tables below are the only conditions
    path = tmp_path / "bad.toml"
    path.write_text(SHIPPED + "\n" + extra)
    return str(path)


BUMP = "[conditions]\nspeed_bumps_m = [9999.0]\n"
VEHICLE = "[[conditions.vehicles]]\nlane = 5\n"
# The sun in the west (90 deg right of the road): casters on the left throw their shadows
# away from the road.
SHADOWS = ("[conditions]\nsun_azimuth_deg = -90\n"
           "[[conditions.shadows]]\nside = 'left'\ns_start_m = 0\ns_end_m = 50\n")


def _one_clear_line(capsys, code: int, *needles: str) -> str:
    captured = capsys.readouterr()
    assert code == 2
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("lanekeep: error: ")
    assert "Traceback" not in captured.err
    for needle in needles:
        assert needle in lines[0]
    return lines[0]


def _no_files(tmp_path: Path, *names: str) -> None:
    for name in names:
        assert not (tmp_path / name).exists(), name
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


def test_a_speed_bump_beyond_the_roads_end_stops_run_before_any_file(tmp_path, capsys):
    bad = _scenario(tmp_path, BUMP)
    code = main(["run", bad, "--seconds", "0.3", "--json", str(tmp_path / "out.json"),
                 "--record", str(tmp_path / "out.rrd"), "--plots", str(tmp_path / "plots")])
    line = _one_clear_line(capsys, code, "conditions.speed_bumps_m[0]", "beyond the road",
                           "bad.toml")
    assert "9999" in line
    _no_files(tmp_path, "out.json", "out.rrd", "plots")


def test_a_speed_bump_beyond_the_roads_end_stops_bench_before_any_worker(tmp_path, capsys):
    bad = _scenario(tmp_path, BUMP)
    code = main(["bench", "clear_straight", bad, "--seconds", "0.3", "--workers", "1",
                 "--json", str(tmp_path / "bench.json"), "--record-dir", str(tmp_path / "rrd")])
    _one_clear_line(capsys, code, "conditions.speed_bumps_m[0]", "beyond the road")
    _no_files(tmp_path, "bench.json", "rrd")


def test_a_vehicle_in_a_lane_that_does_not_exist(tmp_path, capsys):
    bad = _scenario(tmp_path, VEHICLE)
    code = main(["run", bad, "--seconds", "0.3", "--json", str(tmp_path / "out.json")])
    _one_clear_line(capsys, code, "conditions.vehicles[0].lane", "bad.toml")
    _no_files(tmp_path, "out.json")


def test_shadows_with_the_sun_on_the_wrong_side(tmp_path, capsys):
    bad = _scenario(tmp_path, SHADOWS)
    code = main(["render", bad, "--out", str(tmp_path / "render")])
    _one_clear_line(capsys, code, "conditions.shadows[0]", "sun_azimuth_deg", "bad.toml")
    _no_files(tmp_path, "render")


def test_render_at_beyond_the_road(tmp_path, capsys):
    code = main(["render", "clear_straight", "--at", "99999", "--out", str(tmp_path / "r")])
    _one_clear_line(capsys, code, "--at", "99999", "outside the road")
    _no_files(tmp_path, "r")


@pytest.mark.parametrize("seconds", ["0", "-1"])
def test_run_rejects_a_non_positive_duration(tmp_path, capsys, seconds):
    code = main(["run", "clear_straight", "--seconds", seconds,
                 "--json", str(tmp_path / "out.json")])
    _one_clear_line(capsys, code, "--seconds", "> 0")
    _no_files(tmp_path, "out.json")


def test_run_rejects_a_duration_shorter_than_one_control_step(tmp_path, capsys):
    code = main(["run", "clear_straight", "--seconds", "0.01",
                 "--json", str(tmp_path / "out.json")])
    _one_clear_line(capsys, code, "--seconds", "control step")
    _no_files(tmp_path, "out.json")


def test_bench_rejects_zero_workers(tmp_path, capsys):
    code = main(["bench", "clear_straight", "--workers", "0", "--seconds", "0.3",
                 "--json", str(tmp_path / "bench.json"), "--record-dir", str(tmp_path / "rrd")])
    _one_clear_line(capsys, code, "--workers")
    _no_files(tmp_path, "bench.json", "rrd")


def test_bench_rejects_a_non_positive_duration(tmp_path, capsys):
    code = main(["bench", "clear_straight", "--seconds", "0", "--json", str(tmp_path / "b.json")])
    _one_clear_line(capsys, code, "--seconds")
    _no_files(tmp_path, "b.json")


def test_perf_rejects_a_zero_duration(tmp_path, capsys):
    code = main(["perf", "--seconds", "0", "--json", str(tmp_path / "perf.json")])
    _one_clear_line(capsys, code, "--seconds")
    _no_files(tmp_path, "perf.json")


def test_an_unknown_detector_in_the_scenario_is_named(tmp_path, capsys):
    bad = _scenario(tmp_path, "[estimation]\nfront_detectors = ['hough', 'nope']\n")
    code = main(["run", bad, "--seconds", "0.3", "--json", str(tmp_path / "out.json")])
    _one_clear_line(capsys, code, "estimation.front_detectors[1]", "'nope'")
    _no_files(tmp_path, "out.json")


def test_run_rejects_a_set_of_no_scenario_key(tmp_path, capsys):
    code = main(["run", "clear_straight", "--seconds", "0.3", "--set", "estimation.nope=1",
                 "--json", str(tmp_path / "out.json")])
    _one_clear_line(capsys, code, "--set", "estimation.nope", "not a scenario key")
    _no_files(tmp_path, "out.json")


def test_bench_rejects_a_set_value_a_file_could_not_hold_before_any_worker(tmp_path, capsys):
    code = main(["bench", "clear_straight", "--seconds", "0.3", "--workers", "1",
                 "--set", "estimation.output=bogus", "--json", str(tmp_path / "bench.json"),
                 "--record-dir", str(tmp_path / "rrd")])
    line = _one_clear_line(capsys, code, "estimation.output", "'bogus'", "clear_straight.toml",
                           "--set estimation.output")
    assert "must be one of" in line
    _no_files(tmp_path, "bench.json", "rrd")


def test_debug_lets_the_exception_through(tmp_path, capsys):
    with pytest.raises(ConfigError, match="--seconds"):
        main(["--debug", "run", "clear_straight", "--seconds", "0"])
    bad = _scenario(tmp_path, BUMP)
    with pytest.raises(ScenarioError, match=r"speed_bumps_m\[0\]") as caught:
        main(["--debug", "render", bad, "--out", str(tmp_path / "r")])
    assert caught.value.key == "conditions.speed_bumps_m[0]"
    assert isinstance(caught.value.__cause__, ValueError)  # the build's own error, chained


def test_the_real_process_prints_a_traceback_only_with_debug(tmp_path):
    """What a user sees: stderr of the `lanekeep` process, with and without --debug."""
    command = [sys.executable, "-m", "lanekeep.cli"]
    args = ["render", "clear_straight", "--at", "99999", "--out", str(tmp_path / "r")]
    plain = subprocess.run([*command, *args], capture_output=True, text=True, timeout=300)
    assert plain.returncode == 2
    assert plain.stderr.strip().splitlines() == [
        "lanekeep: error: --at: 99999 m is outside the road (0..400 m)"]
    debug = subprocess.run([*command, "--debug", *args], capture_output=True, text=True,
                           timeout=300)
    assert debug.returncode == 1 and "Traceback" in debug.stderr
    assert "ConfigError" in debug.stderr


@pytest.mark.parametrize("env", [{"MUJOCO_GL": "osmesa"}, {"MUJOCO_GL": "bogus"},
                                 {"MUJOCO_GL": "egl",
                                  "__EGL_VENDOR_LIBRARY_FILENAMES": "/nonexistent.json"}],
                         ids=["osmesa_missing", "unknown_backend", "no_egl_driver"])
def test_a_renderer_that_cannot_start_is_one_line_naming_mujoco_gl(tmp_path, env):
    """A GL backend this machine lacks fails inside PyOpenGL or mujoco.Renderer; the user gets
    one line naming MUJOCO_GL and what to do, exit 2, and no file."""
    import os

    out = tmp_path / "frames"
    result = subprocess.run([str(Path(sys.executable).parent / "lanekeep"), "render",
                             "clear_straight", "--out", str(out)],
                            capture_output=True, text=True, timeout=120,
                            env={**os.environ, **env})
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    (line,) = [ln for ln in result.stderr.splitlines() if ln.startswith("lanekeep: error: ")]
    assert f"MUJOCO_GL={env['MUJOCO_GL']}" in line and "MUJOCO_GL=egl" in line
    assert not out.exists() or not any(out.iterdir())


def test_a_closed_pipe_ends_the_listing_quietly():
    """`lanekeep scenarios | head -1` prints one line and no BrokenPipeError traceback (the
    listing loads each scenario, so head has closed the pipe long before it ends)."""
    proc = subprocess.run(f"'{sys.executable}' -m lanekeep.cli scenarios | head -1", shell=True,
                          capture_output=True, text=True)
    assert proc.stdout.count("\n") == 1
    assert "Traceback" not in proc.stderr and "BrokenPipe" not in proc.stderr
