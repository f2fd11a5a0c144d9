"""tools/dataset_content.py: the real frames' paint contrast read at their labels, and bad
input as one line, exit 2 (the dataset's own worlds are read in tests/evaluation)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SPEC = importlib.util.spec_from_file_location("dataset_content_tool",
                                              ROOT / "tools/dataset_content.py")
tool = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(tool)


def test_a_labelled_frame_is_read_at_its_labels(tmp_path):
    image = np.full((720, 1280, 3), 60, np.uint8)
    image[450:, 636:644] = 140  # a solid line at x = 640 in the near rows
    (tmp_path / "labels").mkdir()
    cv2.imwrite(str(tmp_path / "0.jpg"), image)
    (tmp_path / "labels" / "0.txt").write_text(
        " ".join(f"640 {y}" for y in range(160, 720, 10)) + "\n")
    out = tool.real_contrast(tmp_path)
    value = float(out.splitlines()[1].split(":")[1])
    assert 60.0 < value <= 80.0  # the 80 DN step, area-averaged to the network's size


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert tool.main(["--data", str(tmp_path / "nope")]) == 2
    err = capsys.readouterr().err
    assert "no shards" in err and len(err.strip().splitlines()) == 1
    assert tool.main(["--data", str(tmp_path), "--drop", "traffic"]) == 2
    assert "--drop and --keep go together" in capsys.readouterr().err
