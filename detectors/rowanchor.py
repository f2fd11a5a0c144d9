"""The row-anchor detector: #58's independent rear observer, weights file in, `LaneEstimate` out.

    detector = RowAnchorDetector(camera, weights="detectors/weights/rowanchor.pt")
    estimate = detector.detect(frame)   # ego lane, vehicle frame
    detector.last_points                # {lane name: (N, 2) frame pixels} of that frame
    detector.move(speed, yaw_rate, dt)  # in a loop, before each frame: the car's motion

Selected as the MMAE's reference with `reference_detector = "rowanchor"` (scenario
`[estimation]`) or `--reference-detector rowanchor`; it is not the default.

The learned part (detectors/rowanchor_model.py) shares no weights, architecture or training
data with any front model. What turns its points into a lane is the project's shared geometry,
as LaneNet uses it (detectors/lanenet_decode.py): each boundary's anchor points are brought
down to the ground through the camera model and fitted by RANSAC as a 2nd-order y(x) with the
curvature prior, and the ego pair is refitted as one parallel lane and checked against the
lane width; the offset is read at the camera's window's look-ahead (`detector_view`). With
`mirror` (the default) the frame and its mirror image run as one batch of two and their reads
are pooled, so that a left-right lean of the network cancels.

A weights file is a dict: a format tag, the architecture (`RowAnchorConfig`), the state dict
(float16: the file stays small; loaded as float32) and plain metadata, read with
`torch.load(..., weights_only=True)`. Anything wrong with it is one `WeightsError` naming
the file.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import cv2
import numpy as np
import torch

from lanekeep.core.reproducibility import portable_torch
from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.birds_eye import detector_view
from lanekeep.detectors.config import DetectorsConfig, GroundWindow, load_config
from lanekeep.detectors.lanenet_decode import (
    CURVATURE_PRIOR_PER_M,
    CURVATURE_PRIOR_SHAPE,
    WIDTH_STD_M,
    DecodeSettings,
    Proposals,
    ego_estimate,
    fit_boundaries,
)
from lanekeep.detectors.lanenet_targets import CellGrid
from lanekeep.detectors.network_io import WeightsError, one_torch_thread, read_weights_blob
from lanekeep.detectors.point_memory import PointMemory
from lanekeep.detectors.rowanchor_model import (
    LANES,
    MIRRORED_LANES,
    RowAnchorConfig,
    RowAnchorNet,
    anchor_rows,
    bin_to_x,
    column_spread,
    decode,
)
from lanekeep.detectors.seen_paint import PaintTest, paint_under_points
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.vehicle_motion import PeriodMotion

FORMAT = "lanekeep-rowanchor/1"
DEFAULT_WEIGHTS = "weights/rowanchor.pt"  # inside the detectors package
MIRROR_AGREE_BINS = 2.0  # a frame's and its mirror's points further apart are two readings


def save_weights(model: RowAnchorNet, path: str | Path, meta: dict | None = None,
                 half: bool = True) -> None:
    """Write the architecture, the weights (float16 with `half`) and plain metadata."""
    state = {k: (v.half() if half and v.is_floating_point() else v)
             for k, v in model.state_dict().items()}
    torch.save({"format": FORMAT, "config": model.config.to_dict(), "state_dict": state,
                "meta": dict(meta or {})}, str(path))


def load_weights(path: str | Path) -> RowAnchorNet:
    """The network stored in `path`, float32, in eval mode, or `WeightsError`."""
    p = Path(path)
    blob = read_weights_blob(p, FORMAT, "row-anchor")
    try:
        model = RowAnchorNet(RowAnchorConfig.from_dict(blob["config"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise WeightsError(p, f"unknown row-anchor architecture: {exc}") from None
    state = blob.get("state_dict", {})
    try:
        model.load_state_dict({k: (v.float() if v.is_floating_point() else v)
                               for k, v in state.items()}, strict=True)
    except (RuntimeError, TypeError, AttributeError) as exc:
        first = str(exc).splitlines()
        raise WeightsError(p, "weights do not fit the row-anchor architecture: "
                              f"{first[1].strip() if len(first) > 1 else exc}") from None
    return model.eval()


@dataclass(frozen=True)
class RowAnchorSettings:
    """The detector's settings (a `[rowanchor]` table of the detectors TOML)."""

    weights: str = ""  # "" = the shipped detectors/weights/rowanchor.pt
    presence_threshold: float = 0.5  # an anchor point is kept above this presence probability
    inlier_px: float = 6.0  # RANSAC residual threshold (frame pixels)
    ransac_iterations: int = 100
    min_points: int = 4  # anchor rows a boundary needs
    seed: int = 0  # RANSAC's generator
    curvature_prior_per_m: float = CURVATURE_PRIOR_PER_M  # lanenet_decode.DecodeSettings
    curvature_prior_shape: str = CURVATURE_PRIOR_SHAPE
    width_std_m: float = WIDTH_STD_M
    # Ground points further than this from the camera are not fitted: a rear camera's far
    # anchors span metres per pixel, and the offset is read 2 m behind the camera.
    max_range_m: float = 30.0
    # Also run the frame mirrored left-right (one batch of two) and pool both reads, so that
    # a left-right lean the network learnt cancels (LaneNet's mirror pass, for the same
    # reason; docs/observer.md measures what it changes).
    mirror: bool = True
    # A point whose column distribution spreads wider than this (frame pixels at 1280 wide,
    # one standard deviation) counts as inferred rather than seen, as LaneNet's points off
    # paint do: its weight in the lane fit is seen_spread_px / spread, at least the decoder's
    # unseen_weight. 0 = every point seen (the weights' first behaviour). Why: the network
    # reads across a dash gap from the lines around it and leant into the lane there by about
    # 6 px on case 4's rear frames, biasing the offset by 1-3 cm (docs/observer.md).
    seen_spread_px: float = 0.0
    # Each point checked against the frame: paint-wide ridge under it or not
    # (detectors/seen_paint.py). A point without paint under it weighs `unseen_weight` in the
    # lane fit, as LaneNet's points off paint do. On since 2026-12-02 with the memory below
    # (docs/observer.md, "Painted points carried across frames": on six tuning scenarios the
    # observer's |bias| fell 1.41 cm [1.14, 1.68], its RMSE from 3-4 to 1-2 cm).
    paint_test: bool = True
    paint_min_ratio: float = PaintTest.min_ratio  # the ridge's least height, a share of the road
    paint_min_step: float = PaintTest.min_step  # ... and in grey levels
    paint_tolerance_px: float = PaintTest.tolerance_px  # the network's placement error, at 1280
    # A double line's middle (the gap between its two stripes, where the network places the
    # boundary) counts as paint when a stripe lies either side of it this far apart (m);
    # 0 = one stripe only, which calls a double line unseen throughout (before 2026-12-02,
    # session 38: on s_bend the observer's bias -1.64 -> +0.03 cm; docs/observer.md, "A
    # double line is paint too").
    paint_double_gap_m: float = PaintTest.double_gap_m
    # The ridge read as the brightest stripe-wide mean, not the brightest pixel (seen_paint.py:
    # grain on coarse asphalt passes a one-pixel peak). Off: on eight tuning scenarios neither
    # the observer's |bias| nor its RMSE was better, and a gentle S-curve's RMSE was worse
    # (docs/observer.md, "Grain taken for paint").
    paint_stripe_mean: bool = PaintTest.stripe_mean
    # An unseen point's weight in the ego pair's fit (LaneNet's decoder: 0.3); with painted
    # points carried from earlier frames the inferred ones are hardly needed.
    unseen_weight: float = 0.05
    # The ego lines' painted points of the last `memory_frames` frames, carried into this one
    # by the car's motion (wheel speed and yaw rate; detectors/point_memory.py), join this
    # frame's: a dash seen a few frames ago is painted evidence in a frame whose near view is
    # a gap. Needs `paint_test`. 0 = one frame, no memory (the weights' first behaviour, with
    # paint_test = false and unseen_weight = 0.3).
    memory_frames: int = 10

    def __post_init__(self) -> None:
        if not self.seen_spread_px >= 0.0:
            raise ValueError(f"seen_spread_px must be >= 0 (0 = off), not {self.seen_spread_px}")
        if self.memory_frames < 0 or (self.memory_frames and not self.paint_test):
            raise ValueError("memory_frames must be >= 0, and needs paint_test = true (only "
                             "points with paint under them are carried)")
        self.paint()  # its own checks

    def paint(self) -> PaintTest:
        return PaintTest(tolerance_px=self.paint_tolerance_px, min_ratio=self.paint_min_ratio,
                         min_step=self.paint_min_step, double_gap_m=self.paint_double_gap_m,
                         stripe_mean=self.paint_stripe_mean)

    def decode(self) -> DecodeSettings:
        return DecodeSettings(score_threshold=self.presence_threshold, inlier_px=self.inlier_px,
                              iterations=self.ransac_iterations, min_points=self.min_points,
                              seed=self.seed, curvature_prior_per_m=self.curvature_prior_per_m,
                              curvature_prior_shape=self.curvature_prior_shape,
                              width_std_m=self.width_std_m, score_power=0.0,
                              max_range_m=self.max_range_m, unseen_weight=self.unseen_weight)


def _pooled(position: np.ndarray, presence: np.ndarray, spread: np.ndarray, bins: int
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One read from a frame's (item 0) and its mirror's (item 1), each (2, lanes, anchors):
    the mirror's lanes swapped and columns mapped back; where both passes place a point
    within MIRROR_AGREE_BINS, the presence-weighted mean of position and spread, elsewhere
    the more present one's; the presence is the two passes' mean."""
    back = list(MIRRORED_LANES[:position.shape[1]])
    pos = np.stack([position[0], bins - position[1][back]])
    pres = np.stack([presence[0], presence[1][back]])
    agree = np.abs(pos[0] - pos[1]) <= MIRROR_AGREE_BINS
    weight, more_present = np.maximum(pres.sum(0), 1e-12), pres.argmax(0)[None]

    def pool(v: np.ndarray) -> np.ndarray:
        mean = (pres * v).sum(0) / weight
        return np.where(agree, mean, np.take_along_axis(v, more_present, 0)[0])

    return pool(pos), pres.mean(0), pool(np.stack([spread[0], spread[1][back]]))


class RowAnchorDetector:
    """`Detector` protocol over the row-anchor network: one frame, no state between frames
    unless `memory_frames` carries painted points (then the driver tells it the car's motion
    before each frame, `move`)."""

    weights_format = FORMAT  # the files `--weights` may give it (registry.weights_fit)

    name = "rowanchor"

    def __init__(
        self,
        camera: CameraModel,
        config: DetectorsConfig | None = None,
        distortion: np.ndarray | None = None,
        settings: RowAnchorSettings | None = None,
        weights: str | Path | None = None,
    ) -> None:
        self.camera = camera
        self.config = config or load_config()
        self.settings = settings or RowAnchorSettings()
        path = weights or self.settings.weights or resources.files("lanekeep.detectors").joinpath(
            DEFAULT_WEIGHTS)
        self.model = load_weights(path)
        self.weights_path = str(path)
        self.view, self.x_ref = detector_view(camera, self.config, distortion)
        self.distortion = None
        if distortion is not None and np.any(np.asarray(distortion) != 0):
            self.distortion = np.asarray(distortion, dtype=float)
        self._decode = self.settings.decode()
        self._paint = self.settings.paint()
        self.memory = PointMemory(self.settings.memory_frames, self.settings.max_range_m)
        self.last_points: dict[str, np.ndarray] = {}

    @property
    def window(self) -> GroundWindow:
        return self.view.window

    def reset(self) -> None:
        self.last_points = {}
        self.memory.reset()

    def move(self, speed_mps: float, yaw_rate_rps: float, dt_s: float,
             lateral_speed_mps: float = 0.0) -> None:
        """The car's motion since the last frame, from its own sensors: carries what the memory
        holds (nothing without `memory_frames`)."""
        self.memory.move(PeriodMotion.of(speed_mps, yaw_rate_rps, dt_s, lateral_speed_mps))

    def points(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The network's read of one frame: x (lanes, anchors) in this frame's pixels and the
        presence probability (lanes, anchors)."""
        x, presence, _ = self.read(frame, spread=False)
        return x, presence

    def read(self, frame: np.ndarray, spread: bool = True
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`points` and each point's column spread (lanes, anchors), in pixels at 1280 wide
        (zeros without `spread`: its softmax over every column costs as much as the decoding)."""
        cfg = self.model.config
        h, w = frame.shape[:2]
        small = frame if (h, w) == (cfg.height, cfg.width) else cv2.resize(
            frame, (cfg.width, cfg.height), interpolation=cv2.INTER_AREA)  # as the dataset's
        item = torch.from_numpy(np.ascontiguousarray(small.transpose(2, 0, 1)))[None]
        with torch.inference_mode(), portable_torch(), one_torch_thread():
            if self.settings.mirror:
                item = torch.cat([item, item.flip(-1)])
            logits = self.model(item)
        position, presence = decode(logits)
        columns = (column_spread(logits) * (1280.0 / cfg.bins) if spread
                   else np.zeros_like(position))
        if self.settings.mirror:
            position, presence, columns = _pooled(position, presence, columns, cfg.bins)
        else:
            position, presence, columns = position[0], presence[0], columns[0]
        return bin_to_x(position, w, cfg.bins), presence, columns

    def proposals(self, frame: np.ndarray) -> Proposals:
        """The anchor points above the presence threshold, as the shared fit takes them."""
        cfg = self.model.config
        h, w = frame.shape[:2]
        x, presence, spread = self.read(frame, spread=self.settings.seen_spread_px > 0.0)
        rows = anchor_rows(h, cfg.anchors)
        lane, anchor = np.nonzero(presence > self._decode.score_threshold)
        pts = np.stack([x[lane, anchor], rows[anchor]], -1).reshape(-1, 2)
        boxes = self._cell_boxes(pts, w, h)
        scores = presence[lane, anchor].astype(np.float64)
        seen = np.ones(len(lane))
        if self.settings.seen_spread_px > 0.0:
            seen = np.minimum(1.0, self.settings.seen_spread_px
                              / np.maximum(spread[lane, anchor], 1e-6))
        if self.settings.paint_test:
            seen = seen * paint_under_points(frame, pts, self._camera_for(w, h), self._paint)
        props = Proposals(pts, boxes, scores, lane.astype(np.int64), np.ones(len(lane)), seen)
        if self.distortion is not None and len(pts):
            camera = self._camera_for(w, h)
            und = cv2.undistortPoints(pts.reshape(-1, 1, 2).astype(np.float64), camera.K,
                                      self.distortion, P=camera.K).reshape(-1, 2)
            props = Proposals(und, boxes, scores, props.slots, props.slot_probs, props.paint)
        return props

    def _with_memory(self, props: Proposals, camera: CameraModel, w: int, h: int) -> Proposals:
        """This frame's proposals and the ego lines' painted points of the last frames, carried
        here and projected into this frame (as painted proposals); this frame's painted ego
        points are remembered for the next frames."""
        xy, slots = self.memory.recall()
        ego = (props.slots <= 1) & (props.paint >= 0.5)
        ground, ok = camera.pixels_to_ground(props.points_px[ego])
        ok &= np.all(np.isfinite(ground), axis=-1)
        self.memory.remember(ground[ok], props.slots[ego][ok])
        if not len(xy):
            return props
        px, front = camera.project_ground(xy)
        inside = front & (px[:, 0] >= 0) & (px[:, 0] <= w - 1) & (px[:, 1] >= 0) & (
            px[:, 1] <= h - 1)
        px, slots, n = px[inside], slots[inside], int(inside.sum())
        boxes = self._cell_boxes(px, w, h)
        return Proposals(np.concatenate([props.points_px, px]),
                         np.concatenate([props.boxes_px, boxes]),
                         np.concatenate([props.scores, np.ones(n)]),
                         np.concatenate([props.slots, slots]),
                         np.concatenate([props.slot_probs, np.ones(n)]),
                         np.concatenate([props.paint, np.ones(n)]))

    def _cell_boxes(self, points_px: np.ndarray, w: int, h: int) -> np.ndarray:
        """(N, 4) x0 y0 x1 y1: one column bin wide and one anchor row tall about each point."""
        cfg = self.model.config
        half_w, half_h = w / cfg.bins / 2.0, h / cfg.anchors / 2.0
        return np.stack([points_px[:, 0] - half_w, points_px[:, 1] - half_h,
                         points_px[:, 0] + half_w, points_px[:, 1] + half_h],
                        -1).reshape(-1, 4)

    def _camera_for(self, width: int, height: int) -> CameraModel:
        if (self.camera.width, self.camera.height) == (width, height):
            return self.camera
        return self.camera.scaled(width, height)

    def detect(self, frame: np.ndarray) -> LaneEstimate:
        try:
            if frame.ndim != 3 or frame.shape[2] != 3 or min(frame.shape[:2]) < 16:
                return LaneEstimate.invalid(f"not an RGB frame: shape {frame.shape}",
                                            x_m=self.x_ref)
            h, w = frame.shape[:2]
            props = self.proposals(frame)
            self.last_points = {LANES[s]: props.points_px[props.slots == s]
                                for s in range(len(LANES))}
            camera = self._camera_for(w, h)
            if self.settings.memory_frames:
                props = self._with_memory(props, camera, w, h)
            grid = CellGrid(w, h, self.model.config.anchors, self.model.config.bins)
            boundaries = fit_boundaries(props, grid, self._decode, camera)
            rules = self.config.lane
            return ego_estimate(boundaries, camera, self.x_ref, rules.lane_width_m,
                                rules.width_tolerance_m, self._decode)
        except (np.linalg.LinAlgError, FloatingPointError) as exc:  # a degenerate fit
            return LaneEstimate.invalid(f"fit failed: {type(exc).__name__}", x_m=self.x_ref)
