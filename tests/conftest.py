"""Shared fixtures. Importing lanekeep first selects the EGL backend before mujoco loads; under
pytest-xdist each worker runs with its share of the cores.

The two worlds are built once per session (a build takes about a second) and put back to
their start state before every test, so that no test sees what another left behind and the
results do not depend on the order tests run in.
"""

import json
import os
import time

import pytest
from shared_runs import set_root

import lanekeep  # noqa: F401
from lanekeep.core.workers import set_thread_counts, worker_threads
from lanekeep.scenario.schema import load_scenario
from lanekeep.world.build import build

if os.environ.get("PYTEST_XDIST_WORKER"):
    # Under `pytest -n N` each worker gets its share of the cores before EGL, OpenCV or torch
    # start, as a bench worker does (lanekeep/core/workers.py): N workers that each started a
    # thread per core would fight over the cores.
    set_thread_counts(worker_threads(int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))))


@pytest.fixture(scope="session", autouse=True)
def _shared_runs_folder(tmp_path_factory):
    """Where tests/shared_runs.py keeps the session's shared closed-loop runs."""
    set_root(tmp_path_factory.getbasetemp())


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


def pytest_collection_modifyitems(config, items):
    """The slow tests (full-resolution closed loops) first, in their order: under pytest-xdist
    the workers start on the long runs and the short tests fill the end, so that no worker
    waits alone on one long run at the end."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


# Where CI's wall time goes: with LANEKEEP_TEST_TIMELINE=FILE every test appends a line (its
# worker, id, start and end in Unix seconds, setup and teardown included; tools/timeline_report.py
# reads it), from which a
# worker's idle tail or a wait on another worker's shared run (tests/shared_runs.py) shows.
_TIMELINE = os.environ.get("LANEKEEP_TEST_TIMELINE")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    start = time.time()
    yield
    if _TIMELINE:
        line = {"worker": os.environ.get("PYTEST_XDIST_WORKER", "main"), "test": item.nodeid,
                "start": start, "end": time.time()}
        with open(_TIMELINE, "a", encoding="utf-8") as f:
            f.write(json.dumps(line) + "\n")
