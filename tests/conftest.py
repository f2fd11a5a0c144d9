"""Shared fixtures. Importing lanekeep first selects the EGL backend before mujoco loads.

The two worlds are built once per session (a build takes about a second) and put back to
their start state before every test, so that no test sees what another left behind and the
results do not depend on the order tests run in.
"""

import pytest

import lanekeep  # noqa: F401
from lanekeep.scenario.schema import load_scenario
from lanekeep.world.build import build


@pytest.fixture(scope="session")
def straight_world():
    return build(load_scenario("clear_straight"))


@pytest.fixture(scope="session")
def curve_world():
    return build(load_scenario("clear_curve"))


@pytest.fixture(autouse=True)
def _fresh_worlds(request):
    """Reset the shared worlds that this test uses (its own or through its fixtures)."""
    for name in ("straight_world", "curve_world"):
        if name in request.fixturenames:
            request.getfixturevalue(name).reset()
