"""A hash of every stage of every step of an episode, to find the first stage at which two
machines (or two kernel settings on one machine) disagree.

A closed loop grows a one-ulp difference into another drive within seconds, so comparing end
metrics says only *that* two runs differ. Per step this hashes the raw renders, the frames
after the camera chain, each detector's estimate, the trackers, the MMAE, the controller's
command and the car's pose after the period (read from the simulator: this is instrumentation
beside the loop, like the scoring, and feeds nothing back into it).
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.loop.episode import Episode, StepResult
from lanekeep.scoring.metrics import EpisodeReport

# The stages in the order the loop runs them: the first that differs is where two runs part.
STAGES = ("render_front", "render_rear", "frame_front", "frame_rear", "detections",
          "tracks", "mmae", "command", "pose")
DETECTOR_PREFIX = "detector:"  # one more key per detector, to name the one that differed


def digest(parts: Iterable[object]) -> str:
    """A short hash of arrays, numbers and strings, exact to the bit (16 hex digits)."""
    h = hashlib.blake2b(digest_size=8)
    for part in parts:
        if part is None:
            h.update(b"None")
        elif isinstance(part, np.ndarray):
            h.update(f"{part.dtype}{part.shape}".encode())
            h.update(np.ascontiguousarray(part).tobytes())
        elif isinstance(part, float | int | np.floating | np.integer | bool):
            h.update(np.float64(part).tobytes())
        else:
            h.update(str(part).encode())
    return h.hexdigest()


def _estimate_parts(estimate: LaneEstimate) -> list[object]:
    return [estimate.valid, estimate.offset_m, estimate.x_m, estimate.confidence, estimate.reason,
            None if estimate.left is None else np.asarray(estimate.left, float),
            None if estimate.right is None else np.asarray(estimate.right, float)]


@dataclass
class HashedRun:
    steps: list[dict[str, str]]  # stage -> hash, per step
    report: EpisodeReport | None  # None when the run stopped at a step unlike `expected`'s


class _Parted(Exception):
    """Raised from the step hook to end a run that has already parted from the expected one."""


def hash_episode(episode: Episode, seconds: float,
                 expected: list[dict[str, str]] | None = None) -> HashedRun:
    """Run `episode` for `seconds`, hashing each stage of each step (the episode is wrapped
    for the run: its renders and detections pass through unchanged). With `expected` (another
    run's steps) the run stops at the first step whose hashes differ: the rest says nothing
    more about where the two parted."""
    raw: dict[str, str] = {}
    detected: dict[str, str] = {}
    render_rgb, detect = episode.simulator.rig.render_rgb, episode.driver.detect  # instrumentation

    def hashed_render(data, camera: str) -> np.ndarray:
        rgb = render_rgb(data, camera)
        raw[camera] = digest([rgb])
        return rgb

    def hashed_detect(frames, events) -> dict[str, LaneEstimate]:
        out = detect(frames, events)
        detected.clear()
        detected.update({DETECTOR_PREFIX + name: digest(_estimate_parts(e))
                         for name, e in out.items()})
        detected["detections"] = digest([p for name in sorted(out)
                                         for p in [name, *_estimate_parts(out[name])]])
        return out

    steps: list[dict[str, str]] = []

    def on_step(r: StepResult, _total: int) -> None:
        tracked = sorted(r.tracked)
        steps.append({
            "render_front": raw.get("front", ""), "render_rear": raw.get("rear", ""),
            "frame_front": digest([r.frames["front"]]), "frame_rear": digest([r.frames["rear"]]),
            **detected,
            "tracks": digest([*tracked, *(r.tracked[n] for n in tracked)]),
            "mmae": digest([r.probabilities, r.selected, r.output_offset_m, r.reference_m,
                            r.mmae_residuals_m]),
            "command": digest([r.steer, r.throttle]),
            "pose": digest([*r.pose, r.speed_mps]),
        })
        index = len(steps) - 1
        if expected is not None and (index >= len(expected)
                                     or first_difference([expected[index]], steps[-1:])):
            raise _Parted

    episode.simulator.rig.render_rgb, episode.driver.detect = hashed_render, hashed_detect
    try:
        report: EpisodeReport | None = episode.run(seconds, on_step=on_step)
    except _Parted:
        report = None
    finally:
        episode.simulator.rig.render_rgb, episode.driver.detect = render_rgb, detect
    return HashedRun(steps, report)


def first_difference(a: list[dict[str, str]], b: list[dict[str, str]]) -> str | None:
    """Where two runs' stage hashes first disagree, in loop order, in words; None if nowhere."""
    for index, (ra, rb) in enumerate(zip(a, b, strict=False)):
        for stage in STAGES:
            if ra.get(stage) != rb.get(stage):
                which = ""
                if stage == "detections":
                    names = [k.removeprefix(DETECTOR_PREFIX) for k in ra
                             if k.startswith(DETECTOR_PREFIX) and ra[k] != rb.get(k)]
                    which = f" ({', '.join(names)})" if names else ""
                later = [s for s in STAGES if any(x.get(s) != y.get(s) for x, y in
                                                  zip(a[index:], b[index:], strict=False))]
                return (f"step {index}, stage {stage}{which} (stages that differ from there "
                        f"on: {', '.join(later)})")
    if len(a) != len(b):
        return f"length: {len(a)} steps against {len(b)}"
    return None
