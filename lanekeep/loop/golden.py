"""Golden runs: short episodes whose stage hashes and metrics are committed
(tests/data/golden/), so that a machine or a library that computes differently is caught, and
the first stage where it parts is named.

Within one machine, tests/loop/test_determinism.py shows a run repeats to the bit. Across
machines the kernel pins (lanekeep/core/reproducibility.py) are meant to give the same bits;
the golden check is what shows they do on the machine at hand. `tools/golden.py --write`
regenerates the files on purpose; a commit that changes them says why.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from lanekeep.core.reproducibility import (
    kernel_differences,
    library_versions,
    setting_details,
    settings_now,
)
from lanekeep.loop.episode import Episode
from lanekeep.loop.stage_hashes import first_difference, hash_episode
from lanekeep.report.json_io import dumps, report_document
from lanekeep.scenario.schema import load_scenario

# What a report holds that is not a result: wall time, versions, the machine's settings.
NOT_RESULTS = ("wall_s", "lanekeep_version", "reproducibility")


@dataclass(frozen=True)
class GoldenCase:
    """One golden run: a shipped scenario, its seed, how long and at what size (reduced: the
    point is the bits, not the picture)."""

    scenario: str
    seed: int | None = None  # None: the file's own
    seconds: float = 2.0
    size: tuple[int, int] = (320, 180)

    @property
    def file_name(self) -> str:
        return f"{self.scenario}.json"


# A lit straight road with half shade, night (spot lights, LaneNet in the dark), rain (the
# image effects) and a turn with bumps (roll, the trackers on a curve).
CASES = (GoldenCase("case4_half_shade_straight"), GoldenCase("night"),
         GoldenCase("heavy_rain"), GoldenCase("case3_mild_turn_shade_bumps"))


def golden_document(case: GoldenCase, expected: dict[str, Any] | None = None
                    ) -> dict[str, Any]:
    """Run `case` and return what its golden file holds; given the `expected` document, the
    run stops at the first step that differs from it (then "metrics" is None)."""
    scenario = load_scenario(case.scenario)
    if case.seed is not None:
        scenario = replace(scenario, seed=case.seed)
    with Episode(scenario, render_size=case.size) as episode:
        run = hash_episode(episode, case.seconds,
                           None if expected is None else expected["steps"])
    metrics = None
    if run.report is not None:
        metrics = json.loads(dumps({k: v for k, v in report_document(run.report, scenario).items()
                                    if k not in NOT_RESULTS}))
    return {"scenario": case.scenario, "seed": case.seed, "seconds": case.seconds,
            "size": list(case.size), "made_with": settings_now(), "steps": run.steps,
            "metrics": metrics}


def _flat(obj: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(obj, dict):
        out: dict[str, Any] = {}
        for key, value in obj.items():
            out.update(_flat(value, f"{prefix}{key}."))
        return out
    return {prefix.rstrip("."): obj}


def differences(expected: dict[str, Any], actual: dict[str, Any]) -> list[str]:
    """What differs between a golden document and a fresh one, in words (empty: identical)."""
    out = []
    where = first_difference(expected["steps"], actual["steps"])
    if where is not None:
        out.append(f"stage hashes differ from {where}")
    if actual["metrics"] is None:  # the run stopped where it parted
        return out
    want, got = _flat(expected["metrics"]), _flat(actual["metrics"])
    changed = [k for k in sorted(set(want) | set(got)) if want.get(k) != got.get(k)]
    if changed:
        shown = ", ".join(f"{k}: {want.get(k)!r} -> {got.get(k)!r}" for k in changed[:6])
        more = f" and {len(changed) - 6} more" if len(changed) > 6 else ""
        out.append(f"{len(changed)} metrics differ: {shown}{more}")
    return out


def check(folder: Path, cases: tuple[GoldenCase, ...] = CASES) -> dict[str, list[str]]:
    """Each case run afresh against its file in `folder`: the differences per scenario."""
    result = {}
    for case in cases:
        path = folder / case.file_name
        if not path.is_file():
            result[case.scenario] = [f"no golden file {path} (tools/golden.py --write)"]
            continue
        expected = json.loads(path.read_text())
        made = expected.get("made_with", {})
        problems = differences(expected, golden_document(case, expected))
        now = settings_now() if problems else None
        settings = kernel_differences(made, now) if problems else []
        if settings:
            problems.append("settings differ from the golden file's in: " + ", ".join(settings))
            problems.append("  (the file's -> here: "
                            + "; ".join(setting_details(made, now)) + ")")
        result[case.scenario] = problems
    return result


def other_versions(folder: Path, cases: tuple[GoldenCase, ...] = CASES) -> list[str]:
    """The library versions here that differ from those the golden files were made with, in
    words: with another torch, OpenCV, numpy or renderer the bits are another computation, and
    the files must be made anew on purpose before they can check anything."""
    now = library_versions(settings_now())
    out = []
    for case in cases:
        path = folder / case.file_name
        if path.is_file():
            made = library_versions(json.loads(path.read_text()).get("made_with", {}))
            out = [f"{k} {made[k]!r} (here {now[k]!r})" for k in made if made[k] != now[k]]
            break
    return out


def write(folder: Path, cases: tuple[GoldenCase, ...] = CASES) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for case in cases:
        path = folder / case.file_name
        path.write_text(dumps(golden_document(case)))
        written.append(path)
    return written
