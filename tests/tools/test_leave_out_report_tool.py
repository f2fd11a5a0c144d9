"""tools/leave_out_report.py: each leave-content-out run paired with the control over the real
frames and the eval conditions; bad input is one line, exit 2."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SPEC = importlib.util.spec_from_file_location("leave_out_report_tool",
                                              ROOT / "tools/leave_out_report.py")
tool = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(tool)


def _write(folder: Path, name: str, accuracies: list[float], aps: list[float]) -> None:
    lines = [f"lanenet         {i}.jpg    horizon   250 valid True  lanes 4 "
             f"acc {a * 100:.1f}% ego {a * 100:.1f}% " for i, a in enumerate(accuracies)]
    (folder / f"{name}.real.txt").write_text("\n".join(lines) + "\nlanenet: mean\n")
    conditions = {f"c{i}": {"set_sha256": f"s{i}", "detectors": {"lanenet": {
        "ap": ap, "f1": ap, "iou_ego": ap, "ade_cm": 5.0, "offset_err_cm": 2.0, "valid": 1.0}}}
        for i, ap in enumerate(aps)}
    (folder / f"{name}.eval.json").write_text(json.dumps({"conditions": conditions}))


def test_a_run_that_loses_real_accuracy_is_found_worse(tmp_path, capsys):
    _write(tmp_path, "random", [0.90, 0.92, 0.88, 0.95, 0.91, 0.90], [0.8, 0.7, 0.9, 0.6])
    _write(tmp_path, "traffic", [0.80, 0.83, 0.77, 0.86, 0.80, 0.81], [0.8, 0.7, 0.9, 0.6])
    assert tool.main([str(tmp_path)]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("| without traffic"))
    cells = [c.strip() for c in row.split("|")]
    assert cells[2] == "0.812" and cells[5].startswith("-0.098 [") and cells[5].endswith("worse")
    assert cells[7].startswith("+0.000")  # the same AP everywhere
    assert "paired over 6 frames" in out


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert tool.main([str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "no random.real.txt" in err and len(err.strip().splitlines()) == 1
    (tmp_path / "random.real.txt").write_text("nothing here\n")
    assert tool.main([str(tmp_path)]) == 2
    assert "no lanenet frame lines" in capsys.readouterr().err
