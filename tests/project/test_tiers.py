"""The test tiers (tests/tiers.py): what CI keeps of the full-resolution closed loops exists."""

from tiers import CI_SCENARIOS, full_unless

from lanekeep.scenario.schema import shipped_scenarios


def test_every_scenario_ci_drives_is_a_shipped_one():
    """A renamed scenario must not silently drop out of CI's closed loops."""
    assert CI_SCENARIOS <= set(shipped_scenarios())


def test_full_unless_marks_only_what_ci_leaves_out():
    params = full_unless(["a", "b", "c"], {"b"})
    assert params[1] == "b"
    assert [p.marks[0].name for p in (params[0], params[2])] == ["full", "full"]
