"""tools/paper_tables.py: its stored rows print the tables and the verdicts again; bad input is
one line and exit 2 (the episodes themselves are not run here: minutes each)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SPEC = importlib.util.spec_from_file_location("paper_tables_tool", ROOT / "tools/paper_tables.py")
tool = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(tool)


def test_the_stored_rows_print_the_papers_table_beside_ours_and_the_verdicts(capsys):
    assert tool.main(["--read", str(ROOT / "docs/data/paper_tables_letter.json")]) == 0
    out = capsys.readouterr().out
    assert "| paper | 21.12 | 47.29 | 20.40 | 13.87 |" in out  # Table 3 beside case 2
    case1 = out.split("case1_building_shadows")[1].split("case2_sharp_turn")[0]
    assert "model #2 - model #1 in the event:  -72.77 cm" in case1 and "better" in case1


def test_open_loop_rows_print_the_models_without_a_paper_mmae(capsys):
    """--open-loop rows (the default loop drives, the paper's two models read its frames):
    the ratio and the turn's verdict print, and no MMAE share is made up for them."""
    rows = ROOT / "docs/data/paper_tables_case2_open_loop_keep_binarisation.json"
    assert tool.main(["--read", str(rows)]) == 0
    out = capsys.readouterr().out
    assert "model #2 / model #1 (geometric mean): 2.05 [1.88, 2.23]; no paper MMAE" in out
    assert "model #2 - model #1 in the event:  +39.34 cm" in out and "worse" in out


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    garbage = tmp_path / "rows.json"
    garbage.write_text("not json")
    bad_config = tmp_path / "detectors.toml"
    bad_config.write_text("[paper]\nwhite_level = 300\n")
    assert tool.main(["--read", str(garbage)]) == 2
    assert tool.main(["no_such_case"]) == 2
    assert tool.main(["--seeds", "0"]) == 2
    assert tool.main(["--detectors-config", str(tmp_path / "missing.toml")]) == 2
    assert tool.main(["--detectors-config", str(bad_config)]) == 2
    assert tool.main(["case1_building_shadows", "--set", "conditions.no_such_key=1"]) == 2
    assert tool.main(["case1_building_shadows", "--set", "no equals sign"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 7 and all(line.startswith("error: ") for line in lines)
