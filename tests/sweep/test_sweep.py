"""`lanekeep sweep`: strict sweep files, local vs Ray rows, resuming, failed cells, plots."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from lanekeep.cli.main import main
from lanekeep.scenario.nuisance import is_nominal, with_nuisance
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring.statistics import spread
from lanekeep.sweep.spec import SweepError, cell_scenario, check_values, parse_sweep

pq = pytest.importorskip("pyarrow.parquet")

GRID = """
name = "grid"
base = "clear_curve"
seeds = 2
seconds = 0.5
metrics = ["rmse_cm", "car_rms_cm", "lane_departures"]
render = { width = 320, height = 180 }
[parameters]
"conditions.rain" = [0.0, 1.0]
"target_speed_mps" = { start = 10.0, stop = 15.0, num = 2 }
"""


def _write(tmp_path: Path, text: str, name: str = "sweep.toml") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def _journal(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "cells.jsonl").read_text().splitlines()[1:]]


def _rows(out: Path) -> list[dict]:
    return pq.read_table(out / "results.parquet").to_pylist()


def test_cells_expand_through_the_scenario_loader():
    spec = parse_sweep(GRID, "grid.toml")
    cells = spec.cells()
    assert len(cells) == 8 and len({c.cell_id for c in cells}) == 8
    assert spec.parameters[1].values == (10.0, 15.0)
    cell = cells[-1]  # last parameter and seed fastest
    assert cell.values == (1.0, 15.0) and cell.seed == 1
    assert cell.table["conditions"]["rain"] == 1.0 and cell.table["camera"]["width"] == 320
    # ids depend on parameters + seed only: the same cell of another parse is the same id
    assert [c.cell_id for c in parse_sweep(GRID, "other.toml").cells()] == [
        c.cell_id for c in cells]


def test_ranges_and_indexed_keys():
    spec = parse_sweep("""
        base = "clear_curve"
        [parameters]
        "conditions.fog" = { start = 0.0, stop = 0.5, step = 0.25 }
        "road.segments[2].curvature_1pm" = [0.004, 0.008]
        "estimation.front_detectors" = [["hough"], ["hough", "sliding_window"]]
        """, "s.toml")
    assert spec.parameters[0].values == (0.0, 0.25, 0.5)
    table = spec.cells()[0].table
    assert table["road"]["segments"][2]["curvature_1pm"] == 0.004
    assert table["estimation"]["front_detectors"] == ["hough"]


def test_a_cells_nominal_seed_is_the_base_files_and_seed_n_drives_as_in_bench():
    """A cell is built in memory, so its nominal seed used to be 0 whatever the base's: on
    occlusion (seed 12) a sweep's seed 12 drew a drive and its seed 0 drove the file's start,
    the other way round from `run`/`bench`. Now both take the file's seed as the nominal one."""
    spec = parse_sweep('base = "occlusion"\nseeds = [12, 3]\n[parameters]\n'
                       '"target_speed_mps" = [15.0]', "s.toml")  # the file's own speed
    base = load_scenario("occlusion")
    assert spec.nominal_seed == base.seed == 12
    assert [(c.seed, c.nominal_seed) for c in spec.cells()] == [(12, 12), (3, 12)]
    nominal, drawn = (cell_scenario(c.table, spec.source, c.nominal_seed) for c in spec.cells())
    assert is_nominal(nominal) and with_nuisance(nominal) == nominal
    assert not is_nominal(drawn)
    # seed 3 of the sweep is seed 3 of `lanekeep run occlusion --seed 3` (bench's seed 3)
    as_run = with_nuisance(dataclasses.replace(base, seed=3))
    assert dataclasses.replace(with_nuisance(drawn), source="") == dataclasses.replace(
        as_run, source="")
    assert as_run.start != base.start  # a drawn drive, not the file's


@pytest.mark.parametrize(("text", "message"), [
    ('base = "clear_curve"\nseed = 3\n[parameters]\n"conditions.rain" = [0.5]',
     "s.toml: seed: unknown key"),
    ('base = "clear_curve"\n[parameters]\n"conditions.rian" = [0.5]',
     "s.toml: parameters.conditions.rian: 'rian' is not a scenario key"),
    ('base = "clear_curve"\n[parameters]\n"road.segments[9].length_m" = [10]',
     "parameters.road.segments[9].length_m: index [9] does not exist"),
    ('base = "clear_curve"\n[parameters]\n"conditions.rain" = [0.5, 2.0]',
     "parameters.conditions.rain: value 2.0 makes an invalid scenario: conditions.rain"),
    ('base = "clear_curve"\n[parameters]\n"conditions.rain" = {start = 0, stop = 1}',
     "a range needs start, stop and one of num / step"),
    ('base = "clear_curve"\nmetrics = ["rmse"]\n[parameters]\n"conditions.rain" = [0.5]',
     "metrics[0]: unknown metric 'rmse'"),
    ('base = "no_such"\n[parameters]\n"conditions.rain" = [0.5]', "unknown scenario"),
    ('base = "clear_curve"\n[parameters]\nconditions.rain = [0.5]',
     'parameters.conditions: a dotted key needs quotes: "conditions.rain"'),
])
def test_bad_sweep_file_is_one_line_exit_2(tmp_path, capsys, text, message):
    path = _write(tmp_path, text, "s.toml")
    with pytest.raises(SweepError):
        parse_sweep(text, "s.toml")
    assert main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("lanekeep: error: ") and message in err
    assert not (tmp_path / "out").exists()  # nothing written for a bad file


def test_ray_missing_says_how_to_install(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` raises ImportError
    assert main(["sweep", str(_write(tmp_path, GRID)), "--ray"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pip install 'lanekeep[ray]'" in err


@pytest.mark.slow
def test_interrupted_sweep_resumes_only_the_missing_cells(tmp_path, capsys):
    from lanekeep.sweep.run import run_local
    from lanekeep.sweep.spec import load_sweep
    from lanekeep.sweep.store import SweepStore

    path, out = _write(tmp_path, GRID), tmp_path / "out"
    spec = load_sweep(path)
    cells = spec.cells()
    store = SweepStore(out, spec)  # a first run that stopped after three cells
    run_local(cells[:3], spec.source, spec.seconds, 2,
              lambda r: store.add(next(c for c in cells if c.cell_id == r.cell_id), r))
    first = {r["cell_id"]: r for r in _journal(out)}
    assert set(first) == {c.cell_id for c in cells[:3]}

    assert main(["sweep", str(path), "--out", str(out), "--workers", "2"]) == 0
    assert "3 already done, 5 to run" in capsys.readouterr().err
    journal = _journal(out)
    assert len(journal) == 8  # the three finished cells did not run again
    assert {r["cell_id"] for r in journal[3:]} == {c.cell_id for c in cells[3:]}
    rows = _rows(out)
    assert [r["cell_id"] for r in rows] == [c.cell_id for c in cells]
    assert all(r["status"] == "completed" and r["error"] == "" for r in rows)
    for r in rows[:3]:
        assert r == first[r["cell_id"]]  # kept as written, wall time and all
    assert {"rmse_cm@fused", "rmse_cm@reference", "car_rms_cm", "lane_departures",
            "conditions.rain", "target_speed_mps", "seed", "wall_s",
            "lanekeep_version"} <= set(rows[0])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["cells"] == 8 and summary["status"] == {"completed": 8}
    assert summary["cells_missing"] == 0 and len(summary["by_parameters"]) == 4
    for combo in summary["by_parameters"]:  # two seeds each: a t interval around the mean
        car = combo["metrics"]["car_rms_cm"]
        values = [r["car_rms_cm"] for r in rows
                  if all(r[k] == v for k, v in combo["parameters"].items())]
        assert car["ci95"] == pytest.approx(list(spread(values).ci95))
        assert car["ci95"][0] <= car["mean"] <= car["ci95"][1]
    plots = {p.name for p in (out / "plots").iterdir()}
    assert {"rmse_cm__vs__conditions.rain.png", "heatmap__car_rms_cm.png",
            "lane_departures__vs__target_speed_mps.png"} <= plots

    # nothing left: a third run runs nothing; another sweep in the same folder is refused
    assert main(["sweep", str(path), "--out", str(out)]) == 0
    assert len(_journal(out)) == 8
    other = _write(tmp_path, GRID.replace("seeds = 2", "seeds = 3"), "other.toml")
    assert main(["sweep", str(other), "--out", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()[-1]
    assert "holds a different sweep" in err


BOOM = '''
class Boom:
    """A controller that raises on its first step: a cell that fails at run time."""

    def __init__(self, context):
        self.context = context

    def reset(self):
        pass

    def control(self, estimate, signals):
        raise RuntimeError("boom at the first step")
'''


@pytest.mark.slow
def test_a_cell_that_raises_is_recorded_and_the_sweep_goes_on(tmp_path, capsys, monkeypatch):
    (tmp_path / "sweep_boom.py").write_text(BOOM, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))  # spawned workers inherit sys.path
    path, out = _write(tmp_path, """
        base = "clear_straight"
        seeds = [0, 1]
        seconds = 0.5
        metrics = ["car_rms_cm"]
        render = { width = 320, height = 180 }
        [parameters]
        "control.controller" = ["pid", "sweep_boom:Boom"]
        """), tmp_path / "out"
    assert main(["sweep", str(path), "--out", str(out), "--workers", "2"]) == 1
    err = capsys.readouterr().err
    assert err.count("FAILED") == 2 and "RuntimeError: boom at the first step" in err
    rows = _rows(out)
    assert [(r["control.controller"], r["status"]) for r in rows] == [
        ("pid", "completed"), ("pid", "completed"),
        ("sweep_boom:Boom", "failed"), ("sweep_boom:Boom", "failed")]
    assert all(r["car_rms_cm"] is not None for r in rows[:2])
    assert all(r["car_rms_cm"] is None and "boom" in r["error"] for r in rows[2:])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == {"completed": 2, "failed": 2} and len(summary["failed"]) == 2

    # resuming retries the failed cells only
    assert main(["sweep", str(path), "--out", str(out), "--workers", "2"]) == 1
    journal = _journal(out)
    assert len(journal) == 6
    assert {r["control.controller"] for r in journal[4:]} == {"sweep_boom:Boom"}


@pytest.mark.slow
def test_local_workers_and_ray_give_identical_rows(tmp_path):
    pytest.importorskip("ray")
    # One seed a cell (4 cells): enough for both workers and Ray's tasks to share the grid,
    # for half the episodes of the full GRID (CI's time).
    path = _write(tmp_path, GRID.replace("seeds = 2", "seeds = 1"))
    assert main(["sweep", str(path), "--out", str(tmp_path / "local"), "--workers", "2",
                 "--no-plots"]) == 0
    # A local Ray of 2 CPUs (ray.init(num_cpus=2)), one task per episode, in a process of its
    # own as a user runs it: after ray.shutdown() a process keeps Ray's gRPC and GCS-client
    # threads (8 native threads, 2026-11-29), which the test worker's later tests need not share.
    ray_run = subprocess.run(
        [sys.executable, "-m", "lanekeep.cli", "sweep", str(path), "--out", str(tmp_path / "ray"),
         "--ray", "--workers", "2", "--no-plots"],
        capture_output=True, text=True, env={**os.environ, "MUJOCO_GL": "egl"}, timeout=600)
    assert ray_run.returncode == 0, ray_run.stderr[-2000:]
    local, ray_rows = _rows(tmp_path / "local"), _rows(tmp_path / "ray")
    assert len(local) == 4
    for a, b in zip(local, ray_rows, strict=True):
        assert a.pop("wall_s") > 0 and b.pop("wall_s") > 0
        assert a == b
    assert all(r["status"] == "completed" for r in local)


EXAMPLE_SWEEPS = sorted(p for p in (Path(__file__).resolve().parents[2] / "examples" / "sweeps")
                        .glob("*.toml") if "[parameters]" in p.read_text(encoding="utf-8"))


@pytest.mark.parametrize("path", EXAMPLE_SWEEPS, ids=lambda p: p.name)
def test_every_example_sweep_file_is_valid(path):
    """The shipped example sweeps (not their base scenarios) expand into cells that pass the
    scenario checks."""
    spec = parse_sweep(path.read_text(encoding="utf-8"), str(path))
    check_values(spec)
    assert len(EXAMPLE_SWEEPS) >= 2 and spec.cells()
