"""Shared fixtures. Importing lanekeep first selects the EGL backend before mujoco loads."""

import pytest

import lanekeep  # noqa: F401
from lanekeep.scenario import load_scenario
from lanekeep.world import build


@pytest.fixture(scope="session")
def straight_world():
    return build(load_scenario("clear_straight"))


@pytest.fixture(scope="session")
def curve_world():
    return build(load_scenario("clear_curve"))
