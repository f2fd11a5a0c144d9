"""A scenario's `[detectors]` table: the detectors' settings an episode runs with, kept in the
scenario file so the episode is reproducible from it (and `--detectors-config FILE`, which
sets that table from a detectors file, on `run` and `bench`)."""

from __future__ import annotations

import dataclasses

import pytest
from helpers import small_scenario, small_scenario_text

from lanekeep.cli.main import main
from lanekeep.core.config_io import ConfigError
from lanekeep.detectors.config import load_config
from lanekeep.loop.episode import Episode
from lanekeep.loop.overrides import PluginOverrides
from lanekeep.scenario.keys import scenario_table, with_settings
from lanekeep.scenario.schema import ScenarioError, parse_scenario, scenario_from_dict

RIDGE = '\n[detectors.hough]\nbinarisation = "ridge"\n'


def test_a_scenario_without_the_table_runs_the_shipped_settings():
    scenario = parse_scenario(small_scenario_text("clear_straight"))
    assert scenario.detectors is None


def test_the_table_is_laid_over_the_shipped_settings_key_by_key():
    scenario = parse_scenario(small_scenario_text("clear_straight") + RIDGE
                              + "\n[detectors.profiles.rear]\nx_far_m = -15.0\n")
    shipped = load_config()
    assert scenario.detectors.hough.binarisation == "ridge"
    assert scenario.detectors.hough.rho_px == shipped.hough.rho_px
    assert scenario.detectors.sliding_window == shipped.sliding_window
    # A key left out keeps the default of the table it sits in: the rear window's near edge,
    # not the generic window's (as a detectors file is read).
    assert scenario.detectors.profiles.rear.x_far_m == -15.0
    assert scenario.detectors.profiles.rear.x_near_m == shipped.profiles.rear.x_near_m


def test_a_bad_key_or_value_in_the_table_names_its_dotted_key():
    text = small_scenario_text("clear_straight")
    with pytest.raises(ScenarioError, match=r"detectors\.hough\.no_such_key"):
        parse_scenario(text + "\n[detectors.hough]\nno_such_key = 1\n")
    with pytest.raises(ScenarioError, match=r"detectors\.profiles\.front\.x_far_m"):
        parse_scenario(text + "\n[detectors.profiles.front]\nx_far_m = 4.5\n")


def test_set_reaches_the_table_and_the_table_reads_back_equal():
    scenario = small_scenario("clear_straight", 1.0)
    changed = with_settings(scenario, (("detectors.hough.binarisation", "ridge"),))
    assert changed.detectors.hough.binarisation == "ridge"
    assert scenario_from_dict(scenario_table(changed)).detectors == changed.detectors


def test_the_episode_s_detectors_run_with_the_table(tmp_path):
    """Every detector of the driver is built with the scenario's settings: the front models
    and a classical reference alike."""
    scenario = small_scenario("clear_straight", 0.2,
                              estimation={"front_detectors": ("hough", "sliding_window"),
                                          "reference_detector": "sliding_window"})
    scenario = with_settings(scenario, (("detectors.hough.binarisation", "ridge"),
                                        ("detectors.sliding_window.binarisation", "edges")))
    with Episode(scenario, render_size=(320, 180)) as episode:
        front = episode.driver.front
        assert front["hough"].config.hough.binarisation == "ridge"
        assert front["sliding_window"].config.sliding_window.binarisation == "edges"
        assert episode.driver.reference.config.sliding_window.binarisation == "edges"
        episode.run()


def test_detectors_config_option_sets_every_scenario_s_table(tmp_path):
    config = tmp_path / "ridge.toml"
    config.write_text('[hough]\nbinarisation = "ridge"\n')
    overrides = PluginOverrides(detectors_config=str(config))
    overrides.check()
    scenario = overrides.apply(small_scenario("clear_straight", 1.0))
    assert scenario.detectors.hough.binarisation == "ridge"
    # --set comes after the file, so it can change one of its keys
    later = dataclasses.replace(overrides, settings=(("detectors.hough.binarisation",
                                                      "image"),))
    assert later.apply(small_scenario("clear_straight", 1.0)).detectors.hough.binarisation \
        == "image"


@pytest.mark.parametrize("content, why", [
    (None, "No such file"),
    ("[hough\n", "invalid TOML"),
    ("[hough]\nno_such_key = 1\n", "hough.no_such_key"),
])
def test_a_bad_detectors_config_is_one_line_naming_the_option(tmp_path, capsys, content, why):
    config = tmp_path / "bad.toml"
    if content is not None:
        config.write_text(content)
    with pytest.raises(ConfigError, match="--detectors-config"):
        PluginOverrides(detectors_config=str(config)).check()
    scenario = tmp_path / "s.toml"
    scenario.write_text(small_scenario_text("clear_straight", 0.2))
    assert main(["run", str(scenario), "--detectors-config", str(config)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--detectors-config" in err[0] and why in err[0]
