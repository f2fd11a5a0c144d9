"""The scenario-format reference: every key a scenario file may hold is described, and the
committed docs/scenario_format.md is what `python -m lanekeep.scenario.reference` generates."""

import dataclasses
import subprocess
import sys
from pathlib import Path

from lanekeep.core.setting import setting
from lanekeep.scenario import reference as ref
from lanekeep.scenario.schema import Scenario, StartConfig

DOC = Path(__file__).resolve().parents[2] / "docs" / "scenario_format.md"
REGENERATE = "python -m lanekeep.scenario.reference -o docs/scenario_format.md"


def test_every_scenario_key_has_a_description():
    missing = ref.missing_descriptions()
    assert not missing, (f"describe these scenario keys at their fields (`setting(default, "
                         f"\"what it means\", ...)`), then run `{REGENERATE}`: {missing}")


def test_the_committed_reference_is_the_generated_one():
    assert DOC.read_text(encoding="utf-8") == ref.render(), (
        f"docs/scenario_format.md is out of date: run `{REGENERATE}`")


def test_a_field_added_without_a_description_is_named():
    @dataclasses.dataclass(frozen=True)
    class Start(StartConfig):
        lateral_speed_mps: float = 0.0

    @dataclasses.dataclass(frozen=True)
    class Extended(Scenario):
        start: Start = setting(factory=Start, doc="Where the car starts.")
        tolerance_m: float = 0.1

    assert sorted(ref.missing_descriptions(Extended)) == ["start.lateral_speed_mps", "tolerance_m"]
    assert "(undocumented)" in ref.render(Extended)
    assert "(undocumented)" not in ref.render()


def test_the_reference_states_the_sign_conventions_and_units():
    text = ref.render()
    assert "`road.ego_lane = 0` is the **rightmost** lane" in text
    assert "**- = turning right**" in text
    row = next(line for line in text.splitlines() if line.startswith("| `curvature_1pm`"))
    assert "| 1/m |" in row and "+ = turning left" in row
    row = next(line for line in text.splitlines() if line.startswith("| `target_speed_mps`"))
    assert "| m/s | 15 |" in row


def test_the_module_writes_the_file(tmp_path):
    out = tmp_path / "format.md"
    subprocess.run([sys.executable, "-m", "lanekeep.scenario.reference", "-o", str(out)],
                   check=True)
    assert out.read_text(encoding="utf-8") == ref.render()
