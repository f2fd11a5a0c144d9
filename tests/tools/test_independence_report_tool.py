"""tools/independence_report.py's summary of the reference's own error: its bias (mean error)
over the steps it gave an offset, per episode too, so that two runs can be paired by seed;
a report written before the bias was kept still prints."""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SPEC = importlib.util.spec_from_file_location("independence_report_tool",
                                              ROOT / "tools/independence_report.py")
tool = importlib.util.module_from_spec(SPEC)
sys.modules[SPEC.name] = tool  # its dataclasses look their module up
SPEC.loader.exec_module(tool)


def _trace(errors_m: list[float]):
    return tool.Trace({tool.REFERENCE: errors_m}, {tool.REFERENCE: [0.0] * len(errors_m)},
                      [], [], [])


def test_the_reference_summary_gives_its_bias_overall_and_per_episode():
    summary = tool.reference_summary([_trace([0.01, 0.03, math.nan]), _trace([-0.02, -0.02])])
    assert summary["mean_cm"] == pytest.approx(0.0)
    assert summary["episode_mean_cm"] == pytest.approx([2.0, -2.0])
    assert summary["episode_rmse_cm"] == pytest.approx([math.sqrt(5.0), 2.0])
    assert summary["episode_valid_share"] == pytest.approx([2 / 3, 1.0])
    assert summary["valid_share"] == pytest.approx(0.8)
    assert summary["steps"] == 5


def test_an_older_report_without_the_bias_still_prints(tmp_path, capsys):
    document = {"settings": {"tau_m": 0.1, "align": "road", "size": "1280x720",
                             "seconds": 15.0, "reference_detector": "rowanchor"},
                "scenarios": {"clear_straight": {
                    "seeds": [2], "statuses": ["completed"],
                    "reference": {"rmse_cm": 1.2, "max_cm": 4.0, "valid_share": 0.95,
                                  "steps": 150},
                    "sources": {}}}}
    path = tmp_path / "old.json"
    path.write_text(json.dumps(document))
    assert tool.main(["--read", str(path)]) == 0
    assert "RMSE 1.20 cm, max 4.0 cm, mean - cm, valid 95.0%" in capsys.readouterr().out
