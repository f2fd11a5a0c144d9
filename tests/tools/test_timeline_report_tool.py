"""tools/timeline_report.py: a LANEKEEP_TEST_TIMELINE file read back as per-worker busy and idle
time and the costliest files; a bad file is one line, exit 2."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))

from timeline_report import main, worker_summary  # noqa: E402

ROWS = [
    {"worker": "gw0", "test": "tests/a.py::one", "start": 100.0, "end": 110.0},
    {"worker": "gw0", "test": "tests/a.py::two", "start": 112.0, "end": 113.0},
    {"worker": "gw1", "test": "tests/b.py::three", "start": 100.5, "end": 104.0},
]


def test_busy_idle_and_finish_per_worker():
    w = worker_summary(ROWS)
    assert w["gw0"] == {"tests": 2, "busy_s": 11.0, "idle_s": 2.0, "end_s": 13.0}
    assert w["gw1"]["busy_s"] == 3.5 and w["gw1"]["idle_s"] == 0.0


def test_report_and_bad_input(tmp_path, capsys):
    path = tmp_path / "t.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in ROWS))
    assert main([str(path), "--top", "1"]) == 0
    out = capsys.readouterr().out
    assert "3 tests, 14 worker-seconds, wall 13 s" in out
    assert "tests/a.py" in out.split("costliest files:")[1].splitlines()[1]
    assert main([str(tmp_path / "missing.jsonl")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing.jsonl" in err
