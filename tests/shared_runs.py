"""Closed-loop runs that several tests read, made once per test session, also under
pytest-xdist: the first worker to ask for a run makes it and pickles the result into the
session's shared temporary folder; a worker that asks meanwhile waits on its lock and reads it.
Runs are deterministic (tests/loop/test_determinism.py), so sharing changes no result.
"""

from __future__ import annotations

import os
import pickle
import re
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from filelock import FileLock

T = TypeVar("T")
_ROOT: list[Path] = []  # the session's shared folder, set by conftest
_MEMO: dict[str, object] = {}


def set_root(basetemp: Path) -> None:
    """The folder the session's workers share: pytest's base temporary folder, or under xdist
    its parent (each worker's base folder is a child of the session's)."""
    root = basetemp.parent if os.environ.get("PYTEST_XDIST_WORKER") else basetemp
    _ROOT[:] = [root / "shared_runs"]
    _ROOT[0].mkdir(exist_ok=True)


def shared(key: str, make: Callable[[], T]) -> T:
    """`make()`'s result, made once per session under `key`."""
    if key in _MEMO:
        return _MEMO[key]  # type: ignore[return-value]
    path = _ROOT[0] / (re.sub(r"[^A-Za-z0-9_.-]", "_", key) + ".pkl")
    with FileLock(str(path) + ".lock"):
        if path.exists():
            value = pickle.loads(path.read_bytes())
        else:
            value = make()
            path.write_bytes(pickle.dumps(value))
    _MEMO[key] = value
    return value
