"""What a new user of the command line meets first (issue 46): progress when stderr is no
terminal, `--size`, tables that fit 100 columns, `--json -`, where outputs went, `render
--offset` off the road, help on every bench option, `detect` on a folder, `scenarios --json`,
and the sweep plots in the run plots' colours."""

from __future__ import annotations

import argparse
import dataclasses
import json
from functools import partial
from types import SimpleNamespace

import cv2
import numpy as np
import pytest
from cli.error_lines import one_error_line  # tests/ is on sys.path

import lanekeep.driver.driver
from lanekeep.cli.main import build_parser, main
from lanekeep.report.json_io import report_from_dict
from lanekeep.report.palette import COLOURS, matplotlib_colour
from lanekeep.report.seed_summary import summarise
from lanekeep.report.tables import WIDTH, episode_table, interval_table, summary_table
from lanekeep.scenario.schema import load_scenario, shipped_scenarios
from lanekeep.sensing.snapshot import paved_offsets
from lanekeep.world.parts import WorldLayout

_one_error_line = partial(one_error_line, stdout_empty=False)

def test_run_at_a_size_writes_json_to_stdout_and_everything_else_to_stderr(
        tmp_path, capsys, monkeypatch):
    """`--size 160x90`: the detectors get a 160x90 camera model; `--json -`: stdout is the
    report alone; the tables (compact: within WIDTH columns) and the progress lines (stderr
    is no terminal here: whole lines, no carriage returns) are on stderr."""
    sizes = []
    real = lanekeep.driver.driver.make_detector

    def spy(name, camera, *args, **kwargs):
        sizes.append((camera.width, camera.height))
        return real(name, camera, *args, **kwargs)

    monkeypatch.setattr(lanekeep.driver.driver, "make_detector", spy)
    code = main(["run", "clear_straight", "--size", "160x90", "--seconds", "0.3",
                 "--front-detectors", "hough,sliding_window", "--json", "-"])
    assert code in (0, 1)  # a 0.3 s episode may or may not meet the file's criteria
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert doc["steps"] == 3 and set(sizes) == {(160, 90)}
    assert "scenario clear_straight (seed 0)" in err and "\r" not in err
    progress = [line for line in err.splitlines() if line.startswith("clear_straight: ")]
    assert progress[0].startswith("clear_straight: 0.0/0.3 s simulated (0%), wall ")
    assert progress[-1].startswith("clear_straight: 0.3/0.3 s simulated (100%), wall ")
    report = report_from_dict(doc)
    compact = episode_table(report)
    assert compact in err
    assert max(len(line) for line in compact.splitlines()) <= WIDTH
    rows = [line.split()[0] for line in compact.splitlines()[1:len(report.sources) + 1]]
    assert rows == list(report.sources)  # one row per source
    assert episode_table(report, wide=True) == report.table()
    # the bench's summary and seed tables too, for the longest shipped scenario name
    longest = max(shipped_scenarios(), key=len)
    runs = [dataclasses.replace(report, scenario=longest, seed=seed) for seed in range(3)]
    doc = summarise(longest, runs, load_scenario("clear_straight"))
    for table in (summary_table(runs[:1]), interval_table([doc])):
        assert longest in table and max(len(line) for line in table.splitlines()) <= WIDTH
    assert max(len(line) for line in interval_table([doc], wide=True).splitlines()) > WIDTH


def test_quiet_silences_the_progress(capsys):
    assert main(["run", "clear_straight", "--size", "128x72", "--seconds", "0.1", "--quiet",
                 "--front-detectors", "hough", "--json", "-"]) in (0, 1)
    out, err = capsys.readouterr()
    assert json.loads(out)["steps"] == 1
    assert "clear_straight: " not in err and "scenario clear_straight" in err


@pytest.mark.parametrize("size", ["640", "640x", "x360", "640x36", "0x360", "abcxdef",
                                  "640x360x2", "99999x720", "-640x360"])
@pytest.mark.parametrize("command", ["run", "bench"])
def test_a_bad_size_is_one_line(capsys, command, size):
    _one_error_line(capsys, main([command, "clear_straight", f"--size={size}"]), "--size",
                    repr(size))


def test_json_and_junit_outputs_are_checked_before_anything_runs(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    _one_error_line(capsys, main(["run", "clear_straight", "--json",
                                  str(blocker / "report.json")]), "--json", "not a folder")
    _one_error_line(capsys, main(["bench", "clear_straight", "--junit", "-"]), "--junit",
                    "for --json only")
    _one_error_line(capsys, main(["run", "clear_straight", "--json", str(tmp_path)]),
                    "--json", "is a folder")
    _one_error_line(capsys, main(["run", "clear_straight", "--record",
                                  str(blocker / "deeper" / "x.rrd")]), "--record",
                    "cannot create the folder", "not a folder")
    _one_error_line(capsys, main(["bench", "clear_straight", "--plots", str(blocker)]),
                    "--plots", "not a folder")
    assert [p.name for p in tmp_path.iterdir()] == ["a_file"]  # nothing was created


def test_json_to_a_missing_folder_creates_it_and_says_so(tmp_path, capsys):
    out = tmp_path / "new" / "deeper" / "run.json"
    assert main(["run", "clear_straight", "--size", "128x72", "--seconds", "0.1", "--quiet",
                 "--front-detectors", "hough", "--json", str(out)]) in (0, 1)
    assert json.loads(out.read_text())["steps"] == 1
    assert f"wrote {out}" in capsys.readouterr().err


def test_render_refuses_an_offset_off_the_paved_surface(tmp_path, capsys):
    scenario = load_scenario("clear_straight")
    low, high = paved_offsets(scenario)
    road, shoulder = scenario.road, WorldLayout().shoulder_m
    # the car's centre at the paved edge, either side: the lanes plus a shoulder
    assert high - low == pytest.approx(road.n_lanes * road.lane_width_m + 2 * shoulder)
    assert low < 0 < high
    for offset in (high + 0.01, low - 0.01, 50.0):
        line = _one_error_line(capsys, main(["render", "clear_straight", "--offset",
                                             str(offset), "--out", str(tmp_path / "r")]),
                               "--offset", "off the road", f"{low:+.2f}..{high:+.2f}")
        assert line.startswith("lanekeep: error: ")
    assert not (tmp_path / "r").exists()


def test_every_bench_and_run_option_has_help():
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name in ("run", "bench"):
        silent = [action.option_strings for action in commands.choices[name]._actions
                  if action.option_strings and not action.help]
        assert silent == [], (name, silent)


def _road_png(path, shift: int) -> None:
    """A straight road: grey asphalt, two white lines to a vanishing point, sky above."""
    image = np.full((360, 640, 3), 90, np.uint8)
    image[:160] = (200, 170, 140)
    for x_bottom in (120 + shift, 520 + shift):
        cv2.line(image, (x_bottom, 359), (320, 160), (255, 255, 255), 6)
    cv2.imwrite(str(path), image)


def test_detect_takes_a_folder_of_images_in_sorted_order(tmp_path, capsys):
    folder = tmp_path / "photos"
    folder.mkdir()
    for name, shift in (("b.png", 0), ("a.jpg", 20), ("c.PNG", -20)):
        _road_png(folder / name, shift)
    (folder / "notes.txt").write_text("not an image")
    (folder / "sub").mkdir()
    _road_png(folder / "sub" / "d.png", 0)  # subfolders are not walked
    assert main(["detect", str(folder)]) == 0
    files = [json.loads(line)["raw_file"] for line in capsys.readouterr().out.splitlines()]
    assert files == [str(folder / n) for n in ("a.jpg", "b.png", "c.PNG")]
    empty = tmp_path / "empty"
    empty.mkdir()
    _one_error_line(capsys, main(["detect", str(empty)]), str(empty), "no images")


def test_scenarios_json_lists_every_scenario_with_its_keys(capsys):
    assert main(["scenarios", "--json"]) == 0
    docs = json.loads(capsys.readouterr().out)
    assert [d["name"] for d in docs] == shipped_scenarios()
    for doc in docs:
        scenario = load_scenario(doc["name"])
        assert doc["description"] == scenario.description and len(doc["description"]) > 20
        assert doc["duration_s"] == scenario.duration_s
        assert doc["road_length_m"] == scenario.road.length_m
        assert doc["camera"] == f"{scenario.camera.width}x{scenario.camera.height}"
        assert doc["front_detectors"] == list(scenario.estimation.front_detectors)


def test_sweep_plots_draw_each_source_in_its_run_plot_colour(tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from lanekeep.sweep import plots

    drawn = []
    monkeypatch.setattr(plt, "close", lambda fig: drawn.append(fig))
    spec = SimpleNamespace(name="s", metrics=("rmse_cm",), seeds=(0, 1),
                           parameters=(SimpleNamespace(key="conditions.fog", values=(0.0, 0.5)),))
    rows = [{"status": "completed", "conditions.fog": fog, "rmse_cm@hough": 1.0 + seed,
             "rmse_cm@hough:track": 0.8 + seed, "rmse_cm@fused": 0.5 + fog}
            for fog in (0.0, 0.5) for seed in (0, 1)]
    assert plots.plot_sweep(spec, rows, tmp_path)
    lines = {line.get_label(): line for line in drawn[0].axes[0].get_lines()}
    for label, base in (("hough", "hough"), ("hough:track", "hough"), ("fused", "fused")):
        assert matplotlib.colors.to_rgb(lines[label].get_color()) == pytest.approx(
            tuple(c / 255 for c in COLOURS[base]))
        assert matplotlib_colour(label) == matplotlib_colour(base)
