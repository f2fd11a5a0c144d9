"""The fixed test sets of `lanekeep eval`: rendered sequences per condition, cached on disk.

Each condition's worlds come from the dataset's random worlds (`random_scenario(seed, tag)`)
with the condition forced on them, so that what is scored is the condition and not a lucky
draw. The paint is forced too: every boundary a readable line (solid, dashed or double; worn
paint, Botts' dots and missing lines as drawn by the dataset become lines, `readable`) except
where the condition is the paint ("worn", "dots"). Without it "clear" held worlds whose ego lane was
worn on both sides or unpainted, and `--quick`'s one clear world was such a one.
Seeds come from their own SeedSequence namespace, SeedSequence([EVAL_NAMESPACE,
condition index, world index]), never one the dataset's splits use ([recipe seed, split, i]).

Two splits of sets, the same conditions drawn from two namespaces: `test` (EVAL_NAMESPACE), the
sets `lanekeep eval` scores, and `tuning` (TUNING_NAMESPACE), other worlds of every condition
for choosing a detector's settings (`lanekeep eval --split tuning`). A number chosen on the
test sets would be scored on the worlds it was chosen on.

    clear       day, no shadows, no weather
    curve       clear, the road one arc of radius 150-300 m after a short lead-in
    buildings   clear, building shadows across the whole road (hard-edged, 40-80% of it)
    half_shade  clear, one continuous shadow covering about half the carriageway's width
    night       the dataset's night (headlights only)
    rain, fog, snow   the dataset's conditions of those names
    worn        clear, every inner boundary worn paint
    dots        clear, every inner boundary Botts' dots (rows of raised ceramic markers, no
                paint), as many real highways mark their lanes (TuSimple's); labelled as
                the line they mark
    occlusion_40, occlusion_60   clear, with image-space occluders (below) over 40% / 60% of
                the visible marking pixels of each frame; the labels stay, as TuSimple keeps
                a lane labelled behind a car

Occluders are opaque blocks in vehicle colours, sized as a vehicle standing at their row (width
and height from the camera's height and horizon), dropped one at a time on a marking pixel not
yet covered until the asked share of the frame's marking pixels (the dataset's `paint` ids > 0)
is covered; a block that would overshoot by more than OVERSHOOT is shrunk. A sequence keeps its
blocks from frame to frame (traffic moves with the car) and adds blocks when a later frame's
share falls short.

Only the front camera is kept (what `lanekeep eval` scores). A set is cached as one .npz per
condition under the cache folder, named by a hash of everything that makes it (the recipe, the
condition, the seeds, the dataset format); files are written to a temporary name and renamed.
"""

from __future__ import annotations

import functools
import hashlib
import json
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from lanekeep.core.files import atomic_path
from lanekeep.evaluation.dataset import FORMAT as DATASET_FORMAT
from lanekeep.evaluation.dataset import DatasetRecipe, camera_from_vector, render_world
from lanekeep.evaluation.dataset_world import ROAD_LENGTH_M, random_scenario
from lanekeep.geometry.markings import MarkingStyle
from lanekeep.geometry.road import SegmentSpec
from lanekeep.scenario.conditions import ShadowZone
from lanekeep.scenario.schema import Scenario, ScenarioError

EVAL_NAMESPACE = 0xE7A1
TUNING_NAMESPACE = 0x7C1E  # the tuning split's sets: the same conditions, other worlds
SPLITS = {"test": EVAL_NAMESPACE, "tuning": TUNING_NAMESPACE}
FORMAT = "lanekeep-eval-set/1"
CONDITIONS = ("clear", "curve", "buildings", "half_shade", "night", "rain", "fog", "snow",
              "worn", "occlusion_40", "occlusion_60", "dots")
BASE_TAG = {"night": "night", "rain": "rain", "fog": "fog", "snow": "snow"}  # else "clear"
OVERSHOOT = 0.03  # an occluder may take the covered share this far past the target
VEHICLE_W_M, VEHICLE_H_M = (1.7, 2.6), (1.3, 3.2)  # occluder sizes (m): car to truck
ATTEMPTS = 32  # worlds tried per slot when the builder rejects a forced condition (the
# shade side is drawn apart from the sun: about half the draws cast it off the road; 8 left
# a tuning world without one, and a set that found its worlds in 8 keeps them)


@dataclass(frozen=True)
class EvalRecipe:
    """Size of each condition's set; `quick()` is the one-world set for tests."""

    worlds: int = 6  # many worlds, few places in each: cameras and roads vary more
    sequences: int = 5
    frames: int = 3
    render_width: int = 640
    render_height: int = 360
    split: str = "test"  # "test": the scored sets; "tuning": other worlds, for tuning

    def __post_init__(self) -> None:
        if min(self.worlds, self.sequences, self.frames) < 1:
            raise ValueError("worlds, sequences and frames must be >= 1")
        if self.split not in SPLITS:
            raise ValueError(f"unknown split {self.split!r}; known: {', '.join(SPLITS)}")

    @property
    def namespace(self) -> int:
        """The seed namespace of this split's worlds."""
        return SPLITS[self.split]

    @classmethod
    def quick(cls) -> EvalRecipe:
        return cls(worlds=1, sequences=1)

    def dataset_recipe(self) -> DatasetRecipe:
        return DatasetRecipe(seed=self.namespace, sequences_per_world=self.sequences,
                             frames=self.frames, render_width=self.render_width,
                             render_height=self.render_height, store_width=self.render_width,
                             store_height=self.render_height)


def occlusion_share(condition: str) -> float:
    """The share of marking pixels to cover (0 for conditions without occluders)."""
    return int(condition.split("_")[1]) / 100.0 if condition.startswith("occlusion_") else 0.0


def condition_seed(condition: str, index: int, attempt: int = 0,
                   namespace: int = EVAL_NAMESPACE) -> int:
    parts = [namespace, CONDITIONS.index(condition), index] + ([attempt] if attempt else [])
    return int(np.random.SeedSequence(parts).generate_state(1)[0])


def readable(marking: MarkingStyle) -> MarkingStyle:
    """`marking` as a painted line: worn paint as the line it wore from, Botts' dots as dashes
    of their rows' length, no paint as a solid line; solid, dashed and double as they are."""
    if marking.kind == "worn":
        return replace(marking, kind=marking.pattern)
    if marking.kind == "dots":
        return replace(marking, kind="dashed")
    if marking.kind == "none":
        return replace(marking, kind="solid")
    return marking


def _force(condition: str, s: Scenario, rng: np.random.Generator) -> Scenario:
    """`s` with `condition` imposed (see the module docstring)."""
    c = s.conditions
    if condition not in BASE_TAG:
        c = replace(c, shadows=())  # the clear family: no shadows but those asked for
    road = replace(s.road, markings=tuple(readable(m) for m in s.road.markings))
    if condition == "curve":
        k = float(rng.choice([-1.0, 1.0])) / float(rng.uniform(150.0, 300.0))
        road = replace(road, segments=(
            SegmentSpec("straight", 25.0), SegmentSpec("clothoid", 15.0, 0.0, k),
            SegmentSpec("arc", ROAD_LENGTH_M - 40.0, k)))
    elif condition == "worn":
        m = road.markings
        road = replace(road, markings=(m[0], *(replace(x, kind="worn") for x in m[1:-1]), m[-1]))
    elif condition == "dots":
        m = road.markings
        road = replace(road, markings=(m[0], *(replace(x, kind="dots") for x in m[1:-1]), m[-1]))
    elif condition in ("buildings", "half_shade"):
        half = condition == "half_shade"
        c = replace(c, time_of_day="day", shadows=(ShadowZone(
            s_start_m=30.0, s_end_m=ROAD_LENGTH_M - 10.0, kind="buildings",
            side=str(rng.choice(["left", "right"])),
            reach=float(rng.uniform(0.45, 0.55) if half else rng.uniform(0.6, 1.2)),
            coverage=1.0 if half else float(rng.uniform(0.4, 0.8)),
            darkness=float(rng.uniform(0.45, 0.75))),))
    return replace(s, road=road, conditions=c, name=f"eval_{condition}_{s.seed}")


def condition_scenario(condition: str, index: int, namespace: int = EVAL_NAMESPACE
                       ) -> Scenario:
    """World `index` of `condition`'s set in a split's `namespace` (redrawn from the next
    seed if the builder rejects the forced condition, e.g. a shadow the drawn sun cannot
    cast)."""
    from lanekeep.world.build import check_buildable

    if condition not in CONDITIONS:
        raise ValueError(f"unknown condition {condition!r}; known: {', '.join(CONDITIONS)}")
    last: Exception | None = None
    for attempt in range(ATTEMPTS):
        seed = condition_seed(condition, index, attempt, namespace)
        rng = np.random.default_rng([seed, namespace])
        try:
            scenario = _force(condition, random_scenario(seed, BASE_TAG.get(condition, "clear")),
                              rng)
            check_buildable(scenario)
            return scenario
        except (ScenarioError, ValueError, RuntimeError) as err:
            last = err
    raise RuntimeError(f"eval set {condition}: no valid world {index} in {ATTEMPTS} seeds: {last}")


def _vehicle_colour(rng: np.random.Generator) -> np.ndarray:
    grey = rng.uniform(0.05, 0.95)
    rgb = rng.uniform(0.05, 0.95, 3) if rng.random() < 0.6 else np.full(3, grey)
    return np.round(rgb * 255).astype(np.uint8)


def _block(rng: np.random.Generator, v: int, u: int, horizon: float, px_per_m: float,
           scale: float) -> tuple[int, int, int, int]:
    """Rows / cols (top, bottom, left, right; bottom/right exclusive) of a vehicle at row v
    holding pixel (v, u); `px_per_m` is image pixels per metre per row below the horizon."""
    dv = max(v + 1.0 - horizon, 2.0)
    w = max(2, int(round(scale * rng.uniform(*VEHICLE_W_M) * px_per_m * dv)))
    h = max(2, int(round(scale * rng.uniform(*VEHICLE_H_M) * px_per_m * dv)))
    bottom = v + 1 + int(rng.integers(0, max(1, h // 4)))
    left = u - int(rng.integers(0, w))
    return max(0, bottom - h), bottom, max(0, left), left + w


def occlude(frames: np.ndarray, paint: np.ndarray, horizon_row: float, height_m: float,
            share: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """One sequence (T, H, W, 3) with occluders over `share` of each frame's marking pixels;
    returns the occluded frames and the share reached per frame (NaN: no paint in view)."""
    out, reached = frames.copy(), np.full(len(frames), np.nan)
    covered = np.zeros(frames.shape[1:3], bool)
    colour = np.zeros(frames.shape[1:], np.uint8)
    px_per_m = 1.0 / height_m  # a flat road: 1 m across at row v spans (v - horizon) / h px
    for t in range(len(frames)):
        marks = paint[t] > 0
        total = int(marks.sum())
        if total == 0:
            continue
        hit = int((marks & covered).sum())
        while hit < share * total:
            free = np.flatnonzero(marks & ~covered)
            v, u = np.unravel_index(int(free[rng.integers(len(free))]), marks.shape)
            rgb, seed = _vehicle_colour(rng), int(rng.integers(2**31))
            for scale in (1.0, 0.7, 0.5, 0.35, 0.25, 0.15, 0.1, 0.0):
                top, bottom, left, right = _block(np.random.default_rng(seed), int(v), int(u),
                                                  horizon_row, px_per_m, scale)
                box = np.zeros_like(covered)
                box[top:bottom, left:right] = True
                new = int((marks & (box | covered)).sum())
                if new <= (share + OVERSHOOT) * total or scale == 0.0:
                    break
            colour[box & ~covered] = rgb
            shade = box.copy()  # the lower quarter darker: bumper, tyres, shadow
            shade[:bottom - max(1, (bottom - top) // 4)] = False
            colour[shade & ~covered] = rgb // 4
            covered |= box
            hit = new
        out[t][covered] = colour[covered]
        reached[t] = hit / total
    return out, reached


def build_set(condition: str, recipe: EvalRecipe) -> dict[str, np.ndarray]:
    """Render `condition`'s set: front sequences and their labels (lanekeep/evaluation/dataset.py's
    arrays), the world seeds and, for occlusion, the share covered per frame."""
    parts: dict[str, list] = {}
    share = occlusion_share(condition)
    for i in range(recipe.worlds):
        scenario = condition_scenario(condition, i, recipe.namespace)
        rng = np.random.default_rng([scenario.seed, recipe.namespace, 1])
        arrays = render_world(scenario, recipe.dataset_recipe(), rng)
        front = ~arrays["is_rear"]
        for key in ("frames", "paint", "xs", "slots", "ground_y", "camera"):
            parts.setdefault(key, []).append(arrays[key][front])
        parts.setdefault("world_seed", []).append(np.full(int(front.sum()), scenario.seed,
                                                          np.uint64))
    out = {k: np.concatenate(v) for k, v in parts.items()}
    out["coverage"] = np.full(out["frames"].shape[:2], np.nan)
    if share > 0.0:
        occ_rng = np.random.default_rng([recipe.namespace, CONDITIONS.index(condition), 0x0CC])
        small_h = out["frames"].shape[2]
        for q in range(len(out["frames"])):
            cam = camera_from_vector(out["camera"][q])
            horizon = (cam.horizon_row() + 0.5) * small_h / cam.height - 0.5
            out["frames"][q], out["coverage"][q] = occlude(
                out["frames"][q], out["paint"][q], horizon, cam.height_m, share, occ_rng)
    return out


@functools.cache  # once per process (~0.4 s): the code a process runs does not change under it
def renderer_fingerprint() -> str:
    """Hash of the code and models that draw a set: every package module this one reaches
    through its imports (lanekeep/core/import_closure.py: the world, camera, scenario and
    dataset code) and the MJCF files. A cached set made by other code is rendered again rather
    than silently scored. Only this folder's modules were hashed once, and the world, camera
    and scenario code had moved to lanekeep/world, lanekeep/sensing and lanekeep/scenario: a
    changed renderer then read the old renders. Then the whole package was, until 2026-11-29:
    an edit of a detector or a metric made every cached set unreadable, and documents scored
    by two checkouts unpairable, though their sets were the same pixels."""
    digest = hashlib.sha256()
    for name, path in fingerprinted_files():
        digest.update(name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def fingerprinted_files() -> list[tuple[str, Path]]:
    """(name, path) of every file `renderer_fingerprint` hashes, sorted by name: sources as
    their path inside the package (e.g. "world/build.py"), MJCF files as "mjcf/NAME"."""
    from lanekeep.core.import_closure import import_closure
    from lanekeep.mjcf import CAR_XML

    paths = []
    for name, path in import_closure(__name__).items():
        parts = name.split(".")[1:]
        if path.name == "__init__.py":
            parts.append("__init__")
        paths.append(("/".join(parts) + ".py" if parts else "__init__.py", path))
    paths += [(f"mjcf/{p.name}", p) for p in Path(CAR_XML).parent.glob("*.xml")]
    return sorted(paths)


def set_key(condition: str, recipe: EvalRecipe) -> str:
    """Hash of everything that makes the set, the renderer's code included."""
    seeds = [condition_seed(condition, i, namespace=recipe.namespace)
             for i in range(recipe.worlds)]
    blob = json.dumps({"format": FORMAT, "dataset": DATASET_FORMAT, "condition": condition,
                       "recipe": asdict(recipe), "rendered": asdict(recipe.dataset_recipe()),
                       "seeds": seeds, "ns": recipe.namespace, "code": renderer_fingerprint()},
                      sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def load_set(condition: str, recipe: EvalRecipe, cache: str | Path | None
             ) -> tuple[dict[str, np.ndarray], str]:
    """`condition`'s set from the cache, else rendered (and cached); returns (arrays, key)."""
    key = set_key(condition, recipe)
    if cache is None:
        return build_set(condition, recipe), key
    prefix = "" if recipe.split == "test" else f"{recipe.split}-"
    path = Path(cache) / f"{prefix}{condition}-{key[:16]}.npz"
    if path.is_file():
        try:
            with np.load(path) as z:
                return {k: z[k] for k in z.files}, key
        except (OSError, ValueError, EOFError):
            pass  # a damaged cache file is rendered again and replaced
    arrays = build_set(condition, recipe)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez_compressed(f, **arrays)
    return arrays, key
