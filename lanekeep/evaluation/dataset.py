"""The LaneNet dataset: short sequences rendered from random worlds, with exact labels.

    python tools/make_dataset.py --out data/lanenet [--worlds 240] [--seed 0]

A recipe (`DatasetRecipe`) and a split name fix everything: world `i` of split `split` is
`random_scenario` of the seed SeedSequence([recipe.seed, SPLIT_IDS[split], i]); in it,
`sequences_per_world` places on the road, each seen by the recipe's cameras (both unless
`cameras` says otherwise) for `frames` consecutive frames `frame_period_s` apart as the car
moves on (a lateral drift now and then: a lane change). Splits by seed: train, val and test
worlds never share a seed.

Labels (exact, from the road geometry and the segmentation render, never from the image):
  - every painted boundary as a polyline continuous through dash gaps (as TuSimple labels
    lanes), sampled at frame rows LABEL_ROWS of the 1280x720 frame (x in 1280x720 pixels,
    NaN where the boundary is not in view), each with its slot (ego-left, ego-right,
    next-left, next-right, other: detectors.lanenet_targets.slots_from_lateral, counted from
    the camera's own optical axis, so the rear camera's left is its own). A boundary is
    labelled out to `label_range_m` (less in fog: the visibility; at night: the headlights);
  - the per-pixel boundary id (0 none, 1 + boundary index) of visible paint (segmentation);
  - each boundary's lateral y (m, vehicle frame) at the ADE points 4..20 m ahead of the car
    (front camera) or behind it (rear), for metric scores;
  - the camera: intrinsics at 1280x720, position and rotation (vehicle frame).
Frames are stored at the network's working size (320x176, RGB uint8, area-averaged from the
640x360 render as `prepare_frame` shrinks any frame) in compressed .npz shards, one per world.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np

from lanekeep.detectors.lanenet_model import LaneNetConfig
from lanekeep.detectors.lanenet_targets import BoundaryLabel, FrameLabel, slots_from_lateral
from lanekeep.evaluation.dataset_world import ROAD_LENGTH_M, near_rear_mount, random_scenario
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.scenario.schema import Scenario
from lanekeep.scoring.metrics import ADE_POINTS_M
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.snapshot import camera_frame, make_effects
from lanekeep.world.build import World, build
from lanekeep.world.camera_mount import camera_from_model
from lanekeep.world.street_lights import update_pools
from lanekeep.world.traffic import update_dynamic

SPLIT_IDS = {"train": 0, "val": 1, "test": 2}
LABEL_WIDTH, LABEL_HEIGHT = 1280, 720  # label pixels: our cameras' frame
LABEL_ROWS = np.arange(0, LABEL_HEIGHT, 5, dtype=np.float32)  # 144 rows, 5 px apart
MAX_BOUNDARIES = 6  # a five-lane road's six boundaries
CAMERAS = ("front", "rear")
FORMAT = "lanekeep-lanenet-data/1"


@dataclass(frozen=True)
class DatasetRecipe:
    """Everything that fixes the data (stored beside it as recipe.json)."""

    seed: int = 0
    sequences_per_world: int = 6
    frames: int = 3  # consecutive frames per sequence (the GRU's context)
    frame_period_s: float = 0.1
    render_width: int = 640
    render_height: int = 360
    label_range_m: float = 80.0
    lane_change_share: float = 0.2
    # Stored frame size: the network's working size for training data; `lanekeep eval` keeps
    # 640x360, which the classical detectors shrink to anyway (2x2 pixels per working pixel).
    store_width: int = LaneNetConfig.width
    store_height: int = LaneNetConfig.height
    # The cameras each sequence is seen by, in CAMERAS' order. Both by default (LaneNet learns
    # from both, and every two-camera shard stays as it was); ("rear",) for a rear-only model
    # (#58's observer) skips the front renders. Its worlds and
    # places are the two-camera recipe's of the same seed; its image noise is not (the front's
    # frames no longer take their draws from the world's stream).
    cameras: tuple[str, ...] = CAMERAS
    # Share of worlds whose camera mount is drawn near the car's own rear camera instead of
    # the world's draw (`dataset_world.near_rear_mount`): a rear-only model meets one camera
    # in the loop (150 deg, 1.5 m, 20 deg down), at the wide end of the drawn range, where
    # #58's observer leant into the lane across dash gaps. 0 keeps every existing recipe.
    rear_mount_share: float = 0.0

    def __post_init__(self):
        if self.frames < 1 or self.sequences_per_world < 1:
            raise ValueError("frames and sequences_per_world must be >= 1")
        cameras = tuple(self.cameras)  # recipe.json stores a list
        if not cameras or any(c not in CAMERAS for c in cameras) or \
                cameras != tuple(c for c in CAMERAS if c in cameras):
            raise ValueError(f"cameras must be a non-empty subset of {CAMERAS} in that order, "
                             f"not {self.cameras!r}")
        object.__setattr__(self, "cameras", cameras)
        if not 0.0 <= self.rear_mount_share <= 1.0:
            raise ValueError(f"rear_mount_share must be in [0, 1], not {self.rear_mount_share}")


def world_seed(recipe: DatasetRecipe, split: str, index: int) -> int:
    """The world seed of sample `index` of `split` (distinct across splits)."""
    return int(np.random.SeedSequence([recipe.seed, SPLIT_IDS[split], index]).generate_state(1)[0])


def _vehicle_frame(road, s: np.ndarray, r: float, pose: tuple[float, float, float]) -> np.ndarray:
    x, y, yaw = pose
    d = road.position(s, r) - (x, y)
    c, sn = math.cos(yaw), math.sin(yaw)
    return np.stack([d[:, 0] * c + d[:, 1] * sn, -d[:, 0] * sn + d[:, 1] * c], -1)


def label_range(scenario: Scenario, recipe: DatasetRecipe) -> float:
    """How far a boundary is labelled: the recipe's range, less where it cannot be seen."""
    c = scenario.conditions
    reach = recipe.label_range_m
    if c.fog > 0.0:  # visibility 400 m .. 25 m (lanekeep/sensing/weather.py), paint ~ half
        visibility = 400.0 * (25.0 / 400.0) ** c.fog
        reach = min(reach, max(15.0, 0.6 * visibility))
    if c.time_of_day == "night":
        reach = min(reach, 50.0)
    return reach


def boundary_labels(world: World, pose: tuple[float, float, float], s_car: float,
                    camera: CameraModel, reach_m: float) -> dict:
    """Row-sampled x (1280x720 px), slot and ADE-point y of every painted boundary."""
    road = world.road
    rear = camera.position_m[0] < 0.0
    sign = -1.0 if rear else 1.0
    s = s_car + sign * np.arange(0.0, reach_m + 0.25, 0.25)
    s = s[(s >= 0.0) & (s <= road.length_m)]
    xs = np.full((MAX_BOUNDARIES, len(LABEL_ROWS)), np.nan, np.float32)
    ys = np.full((MAX_BOUNDARIES, len(ADE_POINTS_M)), np.nan, np.float32)
    lateral = np.full(MAX_BOUNDARIES, np.nan)
    painted = np.zeros(MAX_BOUNDARIES, bool)
    for b in range(road.n_lanes + 1):
        if road.markings[b].kind == "none":
            continue
        local = _vehicle_frame(road, s, road.boundary_r(b), pose)
        ahead = sign * local[:, 0]
        ys[b] = np.interp(ADE_POINTS_M, ahead, local[:, 1], left=np.nan, right=np.nan)
        pts = np.concatenate([local, np.zeros((len(local), 1))], 1)
        cv = camera.to_opencv_frame(pts)
        ok = cv[:, 2] > 0.5
        if ok.sum() < 2:
            continue
        uv, _ = camera.project(pts[ok])
        depth = cv[ok, 2]
        # The boundary's side of the camera near it: lateral in the camera's frame at ~8 m.
        lateral[b] = -float(np.interp(8.0, depth, cv[ok, 0])) if depth.max() >= 8.0 else \
            -float(cv[ok, 0][np.argmax(depth)])
        v = uv[:, 1]
        order = np.argsort(v)
        v_sorted, u_sorted = v[order], uv[order, 0]
        inside = (LABEL_ROWS >= v_sorted[0]) & (LABEL_ROWS <= v_sorted[-1])
        x = np.interp(LABEL_ROWS, v_sorted, u_sorted)
        x[~inside | (x < 0) | (x > LABEL_WIDTH - 1)] = np.nan
        xs[b] = x
        painted[b] = np.isfinite(x).sum() >= 2
    slots = np.full(MAX_BOUNDARIES, -1, np.int8)
    idx = np.flatnonzero(painted)
    if len(idx):
        slots[idx] = slots_from_lateral(lateral[idx]).astype(np.int8)
    xs[~painted] = np.nan
    return {"xs": xs, "slots": slots, "ground_y": ys}


def frame_label(xs: np.ndarray, slots: np.ndarray, mask: np.ndarray | None = None) -> FrameLabel:
    """The `FrameLabel` (targets' input) of one stored frame's row-sampled boundaries."""
    out = []
    for x, slot in zip(xs, slots, strict=True):
        ok = np.isfinite(x)
        if slot < 0 or ok.sum() < 2:
            continue
        out.append(BoundaryLabel(np.stack([x[ok], LABEL_ROWS[ok]], 1).astype(float), int(slot)))
    return FrameLabel(tuple(out), mask)


def camera_vector(camera: CameraModel) -> np.ndarray:
    """fx fy cx cy (at 1280x720), position (3), rotation (9): 16 numbers."""
    return np.concatenate([[camera.fx, camera.fy, camera.cx, camera.cy], camera.position_m,
                           camera.rotation.reshape(-1)]).astype(np.float64)


def camera_from_vector(v: np.ndarray, name: str = "front") -> CameraModel:
    v = np.asarray(v, dtype=float)
    return CameraModel(name, LABEL_WIDTH, LABEL_HEIGHT, v[0], v[1], v[2], v[3], v[4:7].copy(),
                       v[7:16].reshape(3, 3).copy())


def _clear_of_traffic(scenario: Scenario, road, s_car: float, r_car: float) -> bool:
    """No other vehicle where the ego car stands (a camera inside a truck labels nothing)."""
    for v in scenario.conditions.vehicles:
        r = road.lane_center_r(v.lane) + v.offset_m
        if abs(v.s_m - s_car) < 0.5 * v.length_m + 4.0 and abs(r - r_car) < 2.6:
            return False
    return True


def render_world(scenario: Scenario, recipe: DatasetRecipe, rng: np.random.Generator) -> dict:
    """All sequences of one world, as arrays (see the module docstring for what they hold)."""
    world = build(scenario)
    road = world.road
    width, height = recipe.store_width, recipe.store_height
    cameras = recipe.cameras
    n, t = recipe.sequences_per_world * len(cameras), recipe.frames
    out = {
        "frames": np.zeros((n, t, height, width, 3), np.uint8),
        "paint": np.zeros((n, t, height, width), np.uint8),
        "xs": np.full((n, t, MAX_BOUNDARIES, len(LABEL_ROWS)), np.nan, np.float32),
        "slots": np.full((n, t, MAX_BOUNDARIES), -1, np.int8),
        "ground_y": np.full((n, t, MAX_BOUNDARIES, len(ADE_POINTS_M)), np.nan, np.float32),
        "camera": np.zeros((n, 16), np.float64),
        "is_rear": np.zeros(n, bool),
    }
    settings = RenderSettings.of(scenario, recipe.render_width, recipe.render_height)
    label_cams = {c: camera_from_model(world.model, c, LABEL_WIDTH, LABEL_HEIGHT) for c in cameras}
    reach = label_range(scenario, recipe)
    lane_r = road.lane_center_r(scenario.road.ego_lane)
    speed = float(rng.uniform(12.0, 30.0))
    with CameraRig(world.model, settings) as rig:
        for q in range(recipe.sequences_per_world):
            for _ in range(50):  # a place clear of other vehicles
                s0 = float(rng.uniform(45.0, ROAD_LENGTH_M - 95.0))
                offset = float(rng.uniform(-0.6, 0.6))
                drift = 0.0
                if rng.random() < recipe.lane_change_share:
                    drift = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 1.5))  # m/s
                    offset = float(rng.uniform(-1.6, 1.6))
                if _clear_of_traffic(scenario, road, s0, lane_r + offset):
                    break
            heading = float(rng.uniform(-2.0, 2.0)) + math.degrees(math.atan2(drift, speed))
            t0 = float(rng.uniform(0.0, 2.0))
            effects = make_effects(scenario, world, rig, rng)
            for k in range(t):
                s_car = s0 + speed * k * recipe.frame_period_s
                r_car = lane_r + offset + drift * k * recipe.frame_period_s
                x, y = road.position(s_car, r_car)
                yaw = float(road.heading_at(s_car)) + math.radians(heading)
                world.car.place(float(x), float(y), yaw, speed)
                update_dynamic(world, t0 + k * recipe.frame_period_s)
                update_pools(world)
                for ci, cam in enumerate(cameras):
                    i = q * len(cameras) + ci
                    rgb = camera_frame(rig, world, cam, effects[cam], rng, speed)
                    out["frames"][i, k] = rgb if rgb.shape[:2] == (height, width) else \
                        cv2.resize(rgb, (width, height), interpolation=cv2.INTER_AREA)
                    seg = rig.render_segmentation(world.data, cam)
                    ids = (np.append(world.marking_boundary, -1)[seg] + 1).astype(np.uint8)
                    labels = boundary_labels(world, (float(x), float(y), yaw), s_car,
                                             label_cams[cam], reach)
                    out["paint"][i, k] = _shrink_ids(ids, width, height, labels)
                    out["xs"][i, k] = labels["xs"]
                    out["slots"][i, k] = labels["slots"]
                    out["ground_y"][i, k] = labels["ground_y"]
                    out["camera"][i] = camera_vector(label_cams[cam])
                    out["is_rear"][i] = cam == "rear"
    return out


def _shrink_ids(ids: np.ndarray, width: int, height: int, labels: dict) -> np.ndarray:
    """Boundary ids at the stored size (a pixel keeps any paint it covered), only rows where
    the boundary is labelled (so paint beyond the label range is not taught either)."""
    h, w = ids.shape
    f = max(1, w // width)  # 640x360 -> 320x180 keeping any paint, then 176 rows
    pooled = ids[:h - h % f, :w - w % f].reshape(h // f, f, w // f, f).max(axis=(1, 3))
    small = cv2.resize(pooled, (width, height), interpolation=cv2.INTER_NEAREST)
    rows_px = (np.arange(height) + 0.5) * LABEL_HEIGHT / height - 0.5
    for b in range(MAX_BOUNDARIES):
        labelled = np.isfinite(labels["xs"][b])
        if not labelled.any():
            small[small == b + 1] = 0
            continue
        top = LABEL_ROWS[labelled].min()
        small[(rows_px[:, None] < top) & (small == b + 1)] = 0
    return small


def make_shard(recipe: DatasetRecipe, split: str, index: int) -> dict:
    """World `index` of `split`: its arrays plus its seed and condition tag."""
    seed = world_seed(recipe, split, index)
    scenario = random_scenario(seed)
    if recipe.rear_mount_share > 0.0:  # its own stream: the world's draws stay as they were
        mount = np.random.default_rng([seed, 0x2EA2])
        if mount.random() < recipe.rear_mount_share:
            scenario = dataclasses.replace(scenario,
                                           camera=near_rear_mount(scenario.camera, mount))
    arrays = render_world(scenario, recipe, np.random.default_rng([seed, 0x5E0]))
    arrays["world_seed"] = np.array(seed, np.uint64)
    arrays["tag"] = np.array(scenario.name.rsplit("_", 1)[1])
    return arrays


def shard_path(root: Path, split: str, index: int) -> Path:
    return Path(root) / split / f"world_{index:05d}.npz"


def write_recipe(root: Path, recipe: DatasetRecipe, counts: dict[str, int]) -> None:
    Path(root).mkdir(parents=True, exist_ok=True)
    (Path(root) / "recipe.json").write_text(json.dumps(
        {"format": FORMAT, "recipe": asdict(recipe), "worlds": counts}, indent=1) + "\n")


def read_recipe(root: Path) -> tuple[DatasetRecipe, dict[str, int]]:
    blob = json.loads((Path(root) / "recipe.json").read_text())
    if blob.get("format") != FORMAT:
        raise ValueError(f"{root}: not a LaneNet dataset (format {blob.get('format')!r})")
    return DatasetRecipe(**blob["recipe"]), blob["worlds"]


def load_split(root: Path, split: str, worlds: Sequence[int] | None = None
               ) -> dict[str, np.ndarray]:
    """All shards of a split concatenated (sequences along axis 0); `tag` per sequence.
    `worlds`: only these world indices (each must be there)."""
    if worlds is None:
        paths = sorted((Path(root) / split).glob("world_*.npz"))
    else:
        paths = [shard_path(root, split, i) for i in sorted(set(worlds))]
        missing = [p.name for p in paths if not p.is_file()]
        if missing:
            raise FileNotFoundError(f"{Path(root) / split}: no shard {missing[0]}")
    if not paths:
        raise FileNotFoundError(f"{Path(root) / split}: no shards")
    parts: dict[str, list] = {}
    for p in paths:
        with np.load(p) as z:
            n = len(z["frames"])
            for k in ("frames", "paint", "xs", "slots", "ground_y", "camera", "is_rear"):
                parts.setdefault(k, []).append(z[k])
            parts.setdefault("tag", []).append(np.full(n, str(z["tag"]), dtype="U8"))
    return {k: np.concatenate(v) for k, v in parts.items()}
