"""The golden runs (lanekeep/loop/golden.py, tests/data/golden/): this machine computes what
the committed files say, to the bit, and a changed renderer or kernel setting is caught and
named by its first differing stage.

Each check runs in its own process: `import lanekeep` must come before numpy for the kernel
pins to take effect, which a test session cannot promise."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "golden.py"
ONE = "case4_half_shade_straight"


def _check(*args: str, **env: str) -> subprocess.CompletedProcess:
    environment = {**os.environ, **env}
    return subprocess.run([sys.executable, str(TOOL), "--check", *args], cwd=ROOT,
                          env=environment, capture_output=True, text=True, timeout=600)


def test_golden_runs_match_this_machine():
    done = _check()
    if done.returncode == 3:  # another torch, OpenCV, numpy or Mesa: another computation
        pytest.skip(done.stderr.strip())
    assert done.returncode == 0, (
        "the golden runs differ on this machine: if a change meant to alter results, "
        "regenerate with `python tools/golden.py --write` and say why in the commit; if not, "
        "this machine or a library computes differently (docs/reproducibility.md)\n"
        + done.stdout + done.stderr)
    assert done.stdout.count(": identical") == 4


@pytest.mark.parametrize(("env", "stage"), [
    # llvmpipe without AVX and FMA (an older CPU): the renders change
    ({"GALLIUM_OVERRIDE_CPU_CAPS": "sse4.1"}, "stage render_front"),
    # MKL's SSE2 branch instead of the pinned AVX2 one: LaneNet's GEMMs sum in another order
    ({"MKL_CBWR": "COMPATIBLE"}, "stage detections (lanenet, reference)"),
], ids=["renderer", "torch-kernels"])
def test_golden_check_names_the_first_stage_a_setting_changes(env, stage):
    done = _check("--only", ONE, **env)
    if done.returncode == 3:
        pytest.skip(done.stderr.strip())
    assert done.returncode == 1, done.stdout + done.stderr
    assert f"{ONE}: DIFFERS" in done.stdout
    assert stage in done.stdout, done.stdout
    assert "settings differ from the golden file's in: " in done.stdout


def test_golden_tool_refuses_an_unknown_case():
    done = _check("--only", "no_such_case")
    assert done.returncode == 2
    assert done.stderr.strip().startswith("golden: error: no golden case no_such_case")


def test_golden_files_of_other_library_versions_are_not_compared(tmp_path):
    """Another torch (or OpenCV, numpy, Mesa) is another computation: the check says so and
    runs nothing (exit 3) rather than report a drift."""
    golden = json.loads((ROOT / "tests" / "data" / "golden" / f"{ONE}.json").read_text())
    golden["made_with"]["torch"]["version"] = "0.0.0-elsewhere"
    (tmp_path / f"{ONE}.json").write_text(json.dumps(golden))
    done = _check("--only", ONE, "--folder", str(tmp_path))
    assert done.returncode == 3, done.stdout + done.stderr
    assert "torch '0.0.0-elsewhere'" in done.stderr


def test_the_cheap_rows_of_the_dispatch_matrix_give_the_golden_bits():
    """tools/dispatch_matrix.py --quick: the pinned default, oneDNN offered AVX-512 (it is out
    of LaneNet's forward), MKL offered AVX2 only, MKL's own branch, OpenBLAS told of a smaller
    L2 cache and one llvmpipe thread, each its own process: every `cpu` row identical, every
    difference named (docs/reproducibility.md has the whole matrix)."""
    done = subprocess.run([sys.executable, str(ROOT / "tools" / "dispatch_matrix.py"), "--quick"],
                          cwd=ROOT, capture_output=True, text=True, timeout=1800)
    if "made with other library versions" in done.stderr + done.stdout:
        pytest.skip("the golden files were made with other library versions")
    assert done.returncode == 0, done.stdout + done.stderr
    rows = [line for line in done.stdout.splitlines() if line.startswith(("ok ", "NO "))]
    assert len(rows) == 6 and all(line.startswith("ok ") for line in rows), done.stdout
    assert "identical" in rows[0] and "(pinned default)" in rows[0]
    assert "6 of 6 rows as expected" in done.stdout
