"""What many tests build the same way: a shipped scenario made small, in memory or as TOML text
at a small camera size. (The one error line of a refused CLI command: tests/cli/error_lines.py.)

Imported as `from helpers import ...` (tests/ is on the path, as for truth_guard).
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

from lanekeep.scenario.schema import Scenario, load_scenario


def small_scenario(name: str = "clear_curve", seconds: float | None = None,
                   **changes) -> Scenario:
    """The shipped scenario `name`, `seconds` long (None: the file's own length), with
    `changes` to its fields: a dict for a table (`camera=`, `estimation=`, `control=`, ...)
    changes only the keys it names, e.g. `small_scenario("clear_curve", 2.0, seed=0,
    estimation={"mode": "paper"})`. Tests run a few seconds of a drive: the length is what
    makes an episode cheap, the render size is `Episode(render_size=...)`'s."""
    scenario = load_scenario(name)
    if seconds is not None:
        changes["duration_s"] = seconds
    for key, value in changes.items():
        if isinstance(value, dict):
            changes[key] = dataclasses.replace(getattr(scenario, key), **value)
    return dataclasses.replace(scenario, **changes)


def small_scenario_text(name: str = "clear_straight", seconds: float | None = None,
                        width: int = 320, height: int = 180, keep_criteria: bool = False) -> str:
    """The shipped scenario file `name` as TOML text, `seconds` long (None: the file's own), with
    its `[camera]` (or a new one) at `width` x `height`, for tests that hand a file to the CLI.
    Without its `[criteria]` (the last table of a shipped file; its limits are tuned for
    1280x720 frames) unless `keep_criteria`."""
    text = Path(load_scenario(name).source).read_text(encoding="utf-8")
    if seconds is not None:
        text, n = re.subn(r"^duration_s = [0-9.]+", f"duration_s = {seconds}", text, count=1,
                          flags=re.M)
        assert n == 1, f"{name} names no duration_s"
    if not keep_criteria:
        text = text.split("\n[criteria]")[0]
    size = f"width = {width}\nheight = {height}\n"
    if "\n[camera]" not in text:
        return text + f"\n[camera]\n{size}"
    # its own [camera] table (the dashcam preset, #59): the size goes in there
    head, tail = text.split("\n[camera]", 1)
    header, body = tail.split("\n", 1)
    table = body.split("\n[", 1)[0]
    assert not re.search(r"^(width|height)\s*=", table, flags=re.M), f"{name} sets its size"
    return f"{head}\n[camera]{header}\n{size}{body}"

