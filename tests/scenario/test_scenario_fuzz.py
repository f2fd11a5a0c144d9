"""Property-based test of the scenario loader (hypothesis): whatever document it is given, it
either loads a scenario that passes every pre-run check or raises the project's own error
(ScenarioError / ConfigError, which the CLI turns into one line and exit 2); never a
TypeError, KeyError or ValueError from deep inside."""

import math
import re
import tomllib
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lanekeep.core.config_io import ConfigError
from lanekeep.loop.checks import check_scenario
from lanekeep.scenario.schema import load_scenario, parse_scenario, shipped_scenarios

BASES = {name: tomllib.loads(Path(load_scenario(name).source).read_text(encoding="utf-8"))
         for name in shipped_scenarios()}
BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")

# -- a small TOML writer (tomllib only reads) ---------------------------------------------------
def _key(key: str) -> str:
    return key if BARE_KEY.match(key) else _string(key)


def _string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"')
    return '"' + "".join(c if c.isprintable() else f"\\u{ord(c):04x}" for c in escaped) + '"'


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(type(value))


def to_toml(document: dict) -> str:
    """Top-level scalars first, then one inline assignment per table (valid TOML 1.0)."""
    return "\n".join(f"{_key(k)} = {_value(v)}" for k, v in document.items()) + "\n"


# -- documents: shipped scenarios with random edits ---------------------------------------------
scalars = st.one_of(
    st.booleans(),
    st.integers(-10**6, 10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(alphabet=st.characters(codec="utf-8", exclude_categories=("Cs",)), max_size=12),
)
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4),
    st.dictionaries(st.text("abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=10), inner,
                    max_size=3)), max_leaves=8)


def _paths(node, prefix=()) -> list[tuple]:
    """Every key path in a document (dict keys and list indices)."""
    out = []
    items = node.items() if isinstance(node, dict) else enumerate(node)
    for key, child in items:
        out.append((*prefix, key))
        if isinstance(child, dict | list):
            out += _paths(child, (*prefix, key))
    return out


@st.composite
def edited_documents(draw) -> dict:
    import copy

    document = copy.deepcopy(BASES[draw(st.sampled_from(sorted(BASES)))])
    for _ in range(draw(st.integers(1, 4))):
        paths = _paths(document)
        path = draw(st.sampled_from(paths))
        parent = document
        for key in path[:-1]:
            parent = parent[key]
        action = draw(st.sampled_from(["replace", "delete", "add_key", "nudge"]))
        leaf = path[-1]
        if action == "delete":
            del parent[leaf]
        elif action == "add_key" and isinstance(parent, dict):
            parent[draw(st.text("abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=12))] = \
                draw(values)
        elif action == "nudge" and isinstance(parent[leaf], int | float) \
                and not isinstance(parent[leaf], bool):
            parent[leaf] = parent[leaf] * draw(st.sampled_from([-1, 0, 1e-9, 0.5, 3, 1e9]))
        else:
            parent[leaf] = draw(values)
    return document


def _loads_or_says_why(text: str) -> None:
    try:
        scenario = parse_scenario(text, source="fuzz.toml")
        check_scenario(scenario, seconds=1.0)
    except ConfigError as err:  # ScenarioError is a ConfigError
        assert str(err).strip(), "an error must say what is wrong"


# Derandomised: CI sees the same 300 documents on every run (a search that finds a new failure
# by chance would make CI flaky); search further by hand with other settings.
@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(edited_documents())
def test_an_edited_scenario_loads_or_raises_the_projects_error(document):
    _loads_or_says_why(to_toml(document))


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.text(max_size=200))
def test_any_text_loads_or_raises_the_projects_error(text):
    _loads_or_says_why(text)


def test_the_writer_round_trips_every_shipped_scenario():
    """The generator's TOML writer is faithful, so the edits are what the loader sees."""
    for name, document in BASES.items():
        assert tomllib.loads(to_toml(document)) == document, name
        _loads_or_says_why(to_toml(document))
        parse_scenario(to_toml(document))  # and they load


def test_a_road_too_long_to_build_is_refused_before_any_allocation():
    """Found by the search above: a segment 2e10 m long asked the road's position table for
    1.46 TiB (a MemoryError, not the project's error). Roads are at most 20 km."""
    import pytest

    from lanekeep.scenario.schema import ScenarioError

    base = BASES["clear_straight"]
    for length in (2e10, math.inf, 20_001.0):
        document = {**base, "road": {**base["road"], "segments": [
            {"kind": "straight", "length_m": length}]}}
        with pytest.raises(ScenarioError, match="length_m"):
            parse_scenario(to_toml(document))
