"""Detector settings (detectors/config.py): each default defined once, in the dataclasses; the
shipped detectors.toml, like a user's file, holds overrides only and is read strictly."""

from __future__ import annotations

import dataclasses
import tomllib
from importlib import resources

import pytest

from lanekeep.core.config_io import ConfigError
from lanekeep.detectors.config import DetectorsConfig, load_config

SHIPPED = resources.files("lanekeep.detectors").joinpath("detectors.toml").read_text()
# A user's overrides: an int, an array, and one key of a window whose defaults are not
# GroundWindow's (the rear keeps its own near edge); every other key keeps its default.
USER = ("[hough]\nvotes = 14\n[sliding_window]\nyellow_hue = [10, 40]\n"
        "[profiles.rear]\nx_far_m = -18\n")


def _with_overrides(defaults, table: dict):
    """`defaults` with a parsed TOML table's values put in, field by field (a reference
    computation beside the loader's strict one)."""
    changes = {}
    for key, value in table.items():
        current = getattr(defaults, key)
        if dataclasses.is_dataclass(current):
            changes[key] = _with_overrides(current, value)
        else:
            changes[key] = tuple(value) if isinstance(value, list) else value
    return dataclasses.replace(defaults, **changes)


def _leaves(table: dict, path: str = ""):
    for key, value in table.items():
        if isinstance(value, dict):
            yield from _leaves(value, f"{path}{key}.")
        else:
            yield f"{path}{key}", value


@pytest.mark.parametrize("text", [SHIPPED, USER], ids=["shipped", "user"])
def test_a_loaded_config_is_the_defaults_with_the_files_overrides(tmp_path, text):
    data = tomllib.loads(text)
    fields = {f.name for f in dataclasses.fields(DetectorsConfig)}
    tables = {name: data.pop(name) for name in list(data) if name not in fields}  # plug-ins'
    expected = dataclasses.replace(_with_overrides(DetectorsConfig(), data), tables=tables)
    path = tmp_path / "detectors.toml"
    path.write_text(text)
    assert load_config(path) == expected
    if text is SHIPPED:
        assert load_config() == expected
    else:
        assert expected != DetectorsConfig() and expected.hough.votes == 14
        assert expected.profiles.rear.x_near_m == DetectorsConfig().profiles.rear.x_near_m


def test_the_shipped_file_repeats_no_default():
    """An override equal to its default would be a second definition of it."""
    defaults = DetectorsConfig()
    for key, value in _leaves(tomllib.loads(SHIPPED)):
        default = defaults
        for part in key.split("."):
            default = getattr(default, part)
        assert (tuple(value) if isinstance(value, list) else value) != default, key


@pytest.mark.parametrize("text, key", [
    ("[hough]\nvotse = 14\n", "hough.votse"),
    ("[profiles.front]\nx_near = 5.0\n", "profiles.front.x_near"),
    ("[hogh]\nvotes = 14\n", "hogh"),
])
def test_an_unknown_key_fails_with_one_line_naming_it(tmp_path, text, key):
    path = tmp_path / "mine.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    message = str(info.value)
    assert info.value.key == key
    assert message.startswith(f"{path}: {key}: unknown key (known keys: ") and "\n" not in message


@pytest.mark.parametrize("value", [-1.0, 90.0])
def test_a_lane_line_divergence_outside_its_range_is_one_line_naming_it(tmp_path, value):
    path = tmp_path / "mine.toml"
    path.write_text(f"[lane]\nmax_divergence_deg = {value}\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    message = str(info.value)
    assert "lane.max_divergence_deg" in message and "\n" not in message
