"""Detectors scored on the fixed rendered test sets (`lanekeep eval`): every detector on every
condition's set, a table and the JSON document.

The sets are lanekeep/evaluation/eval_sets.py's (rendered once, then read from the cache), the
metrics lanekeep/evaluation/lane_metrics.py's (their definitions are in its docstring).
Detectors see only the frames (upscaled to 1280x720) and the camera model; labels are read only
to score. Each sequence is fed in order to a detector reset before it, so LaneNet's recurrent
state spans a sequence and no more. `plan_eval` checks every argument before anything is
rendered (BadInput, one line).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

DEFAULT_DETECTORS = "hough,sliding_window,lanenet"
TABLE_COLUMNS = (("ap", "AP", "{:.3f}"), ("ap_ego", "APego", "{:.3f}"),
                 ("iou", "IoU", "{:.3f}"), ("f1", "F1", "{:.3f}"),
                 ("iou_ego", "IoUego", "{:.3f}"), ("ade_cm", "ADE cm", "{:.1f}"),
                 ("fde_cm", "FDE cm", "{:.1f}"), ("offset_err_cm", "off cm", "{:.1f}"),
                 ("valid", "valid", "{:.2f}"), ("ms", "ms", "{:.1f}"))


class BadInput(ValueError):
    """An argument or file `eval` cannot use (one error line, exit 2)."""


def parse_names(text: str, known: list[str], what: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise BadInput(f"no {what} given")
    for n in names:
        if n not in known:
            raise BadInput(f"unknown {what} {n!r}; known: {', '.join(known)}")
    return list(dict.fromkeys(names))


def check_writable(path: str, what: str, folder: bool) -> None:
    """Raise BadInput if `path` (a file, or a folder) cannot be written, creating nothing."""
    p = Path(path)
    if p.exists() and p.is_dir() != folder:
        raise BadInput(f"{what} {path}: exists and is {'not ' if folder else ''}a folder")
    existing = p if folder and p.exists() else p.parent
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir() or not os.access(existing, os.W_OK | os.X_OK):
        raise BadInput(f"{what} {path}: cannot write there ({existing} is not a writable folder)")


class DetectorRunner:
    """One detector over the sets: built per camera, reset per sequence, timed per frame."""

    def __init__(self, name: str, weights: str | None, config=None) -> None:
        self.name, self.weights, self.config = name, weights, config
        self._made: dict[bytes, object] = {}
        self.warm = False

    def _detector(self, camera):
        from lanekeep.detectors.registry import make_detector

        key = camera.K.tobytes() + camera.position_m.tobytes() + camera.rotation.tobytes()
        if key not in self._made:  # the settings file's [lanenet] table reaches LaneNet too
            weights = self.weights if self.name == "lanenet" else None
            self._made[key] = make_detector(self.name, camera, self.config, weights=weights)
        return self._made[key]

    def start(self, camera, first_frame) -> None:
        """Reset for a new sequence (and, once, warm up untimed: imports, allocations)."""
        self.camera, self.det = camera, self._detector(camera)
        if not self.warm:
            self.det.detect(first_frame)
            self.warm = True
        self.det.reset()

    def predict(self, frame):
        """(FramePrediction, ms) of one 1280x720 frame."""
        from lanekeep.evaluation.dataset import LABEL_ROWS
        from lanekeep.evaluation.lane_metrics import FramePrediction, estimate_prediction, eval_grid

        det, cam = self.det, self.camera
        if self.name == "lanenet":
            start = time.perf_counter()
            est = det.detect(frame)
            ms = 1000.0 * (time.perf_counter() - start)
            decoded = det.last  # the proposals and boundaries `detect` made the estimate from
            lanes = [b.x_at_rows(LABEL_ROWS, cam) for b in decoded.boundaries]
            props = decoded.candidates  # all confidences: AP ranks them
            return FramePrediction(props.boxes_px, props.scores, lanes, est), ms
        start = time.perf_counter()
        est = det.detect(frame)
        ms = 1000.0 * (time.perf_counter() - start)
        x_range = (float(cam.position_m[0]) + 1.0, det.window.x_far_m * 1.3)  # as `detect`
        return estimate_prediction(est, cam, x_range, eval_grid()), ms


def evaluate(conditions: list[str], detectors: list[str], weights: str | None, recipe,
             cache: str | None, progress: Callable[[str], None] | None = None,
             stateless: bool = False, config=None) -> dict:
    """Scores per condition per detector, with what made each set (the JSON's `conditions`).
    `stateless`: each detector reset before every frame, not only before each sequence (what
    it gives without its memory of earlier frames: LaneNet without its recurrent state).
    `config`: the detectors' settings (a `DetectorsConfig`; None: the shipped ones)."""
    import cv2
    import numpy as np

    from lanekeep.evaluation.dataset import LABEL_HEIGHT, LABEL_WIDTH, camera_from_vector
    from lanekeep.evaluation.eval_sets import load_set, occlusion_share
    from lanekeep.evaluation.lane_metrics import Tally

    runners = [DetectorRunner(n, weights, config) for n in detectors]
    out = {}
    for condition in conditions:
        t0 = time.perf_counter()
        data, key = load_set(condition, recipe, cache)
        tallies = {r.name: Tally() for r in runners}
        for q in range(len(data["frames"])):
            camera = camera_from_vector(data["camera"][q])
            seq = [cv2.resize(f, (LABEL_WIDTH, LABEL_HEIGHT), interpolation=cv2.INTER_LINEAR)
                   for f in data["frames"][q]]
            for r in runners:
                r.start(camera, seq[0])
                for t, frame in enumerate(seq):
                    if stateless:
                        r.det.reset()
                    pred, ms = r.predict(frame)
                    tallies[r.name].add(pred, data["xs"][q, t], data["slots"][q, t],
                                        data["ground_y"][q, t], ms)
        cover = data["coverage"]
        out[condition] = {
            "set_sha256": key,
            "frames": int(np.prod(data["frames"].shape[:2])),
            "world_seeds": sorted({int(s) for s in data["world_seed"]}),
            "occlusion_share": occlusion_share(condition),
            "coverage_mean": float(np.nanmean(cover)) if np.isfinite(cover).any() else None,
            "detectors": {name: t.summary() for name, t in tallies.items()},
        }
        if progress:
            progress(f"eval: {condition}: {out[condition]['frames']} frames, "
                     f"{time.perf_counter() - t0:.1f} s")
    return out


def table(results: dict) -> str:
    """Rows: condition x detector; columns: TABLE_COLUMNS ("-" where nothing was scored)."""
    head = f"{'condition':<13} {'detector':<15}" + "".join(f"{h:>8}" for _, h, _ in TABLE_COLUMNS)
    lines = [head, "-" * len(head)]
    for condition, entry in results.items():
        for k, (name, s) in enumerate(entry["detectors"].items()):
            cells = "".join(
                f"{(fmt.format(s[key]) if s[key] is not None and s[key] == s[key] else '-'):>8}"
                for key, _, fmt in TABLE_COLUMNS)
            lines.append(f"{condition if k == 0 else '':<13} {name:<15}{cells}")
    lines.append("AP: proposals vs marking boxes at IoU 0.5 (APego: the ego boundaries' boxes "
                 "only, an ego-lane model's like-for-like figure); IoU/F1: 30 px lane masks, "
                 "Hungarian "
                 "pairs; ADE/FDE/off: ego boundaries 4-20 m, valid frames only; ms: per 1280x720 "
                 "frame (lanekeep/evaluation/lane_metrics.py)")
    return "\n".join(lines)


def check_weights(weights: str | None, detectors: list[str]) -> str | None:
    """The LaneNet weights file to use, loaded once here so a bad one stops everything."""
    if weights is None and "lanenet" not in detectors:
        return None
    from importlib import resources

    from lanekeep.detectors.lanenet import DEFAULT_WEIGHTS, WeightsError, load_weights

    path = weights or str(resources.files("lanekeep.detectors").joinpath(DEFAULT_WEIGHTS))
    try:
        load_weights(path)
    except WeightsError as err:
        raise BadInput(str(err)) from None
    return path


@dataclass(frozen=True)
class EvalPlan:
    """What `eval` scores, checked: the detectors, the conditions, the weights file and the
    detectors' settings file (None: the shipped settings) with what it loads to."""

    detectors: list[str]
    conditions: list[str]
    weights: str | None
    detectors_config: str | None = None
    config: object = None  # the loaded DetectorsConfig when a file was given


def plan_eval(detectors: str, conditions: str, weights: str | None,
              json_path: str | None = None, cache: str | None = None,
              detectors_config: str | None = None) -> EvalPlan:
    """The comma-separated detector and condition names ("all": every condition) checked, the
    outputs writable, the weights loadable, the detectors file readable with known keys;
    BadInput (one line) otherwise."""
    from lanekeep.detectors.registry import known_detectors
    from lanekeep.evaluation.eval_sets import CONDITIONS

    names = parse_names(detectors, sorted(set(known_detectors()) | {"lanenet"}), "detector")
    chosen = (list(CONDITIONS) if conditions == "all"
              else parse_names(conditions, list(CONDITIONS), "condition"))
    if json_path:
        check_writable(json_path, "--json", folder=False)
    if cache:
        check_writable(cache, "--cache", folder=True)
    return EvalPlan(names, chosen, check_weights(weights, names), detectors_config,
                    load_detectors_config(detectors_config))


def load_detectors_config(path: str | None):
    """The `--detectors-config` file's settings (None: none given), or BadInput naming the
    option, the file and what is wrong with it (the same check as `run`'s option)."""
    if path is None:
        return None
    import tomllib

    from lanekeep.core.config_io import ConfigError
    from lanekeep.detectors.config import load_config

    try:
        return load_config(path)
    except OSError as err:
        raise BadInput(f"--detectors-config: {path}: {err.strerror or err}") from None
    except tomllib.TOMLDecodeError as err:
        raise BadInput(f"--detectors-config: {path}: invalid TOML: {err}") from None
    except ConfigError as err:
        raise BadInput(f"--detectors-config: {err}") from None


def eval_document(plan: EvalPlan, recipe, quick: bool, results: dict,
                  stateless: bool = False) -> dict:
    """`eval --json`: the results with what made them."""
    from lanekeep.report.json_io import SCHEMA_VERSION, lanekeep_version

    return {"schema_version": SCHEMA_VERSION, "lanekeep_version": lanekeep_version(),
            "command": "eval", "quick": bool(quick), "stateless": bool(stateless),
            "recipe": asdict(recipe),
            "weights": plan.weights, "detectors": plan.detectors,
            "detectors_config": detectors_config_record(plan), "conditions": results}


def detectors_config_record(plan: EvalPlan) -> dict | None:
    """The settings file's path and the settings it gave, in full (None: the shipped ones), so
    that a JSON says which settings its numbers belong to even after the file changed."""
    if plan.detectors_config is None:
        return None
    from lanekeep.detectors.config import config_table

    return {"path": plan.detectors_config, "settings": config_table(plan.config)}
