"""A setting's one definition (lanekeep/core/setting.py): the field carries its default, its
words and its rule, and `check_settings` enforces the rule in one line naming the field."""

from __future__ import annotations

import dataclasses

import pytest

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, setting, unit_of


@dataclasses.dataclass(frozen=True)
class Probe:
    gap_m: float = setting(1.0, "A gap.", bounds=(0.5, 2.0))
    mode: str = setting("a", "A mode.", choices=("a", "b"))
    limit_s: float | None = setting(None, "Unset = not checked.", bounds=(0.0, 1.0))
    names: tuple[str, ...] = setting(factory=tuple, doc="Some names.", unit="px")

    def __post_init__(self):
        check_settings(self)


def test_the_field_carries_default_words_and_rule():
    fields = {f.name: f for f in dataclasses.fields(Probe)}
    assert Probe() == Probe(1.0, "a", None, ())
    assert fields["gap_m"].metadata["allowed"] == "0.5..2" and unit_of(fields["gap_m"]) == "m"
    assert fields["mode"].metadata["allowed"] == '"a", "b"'
    assert unit_of(fields["names"]) == "px" and unit_of(fields["mode"]) == ""


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"gap_m": 2.5}, "gap_m: must be in [0.5, 2] m, got 2.5"),
    ({"gap_m": float("nan")}, "gap_m: must be in [0.5, 2] m, got nan"),
    ({"mode": "c"}, "mode: must be one of ('a', 'b'), got 'c'"),
    ({"limit_s": -0.1}, "limit_s: must be in [0, 1] s, got -0.1"),
])
def test_a_value_outside_its_rule_is_one_line_naming_the_field(kwargs, message):
    with pytest.raises(InvalidValue) as err:
        Probe(**kwargs)
    assert str(err.value) == message


def test_ends_and_unset_optionals_pass():
    Probe(gap_m=0.5, limit_s=None)
    Probe(gap_m=2.0, mode="b", limit_s=1.0)
