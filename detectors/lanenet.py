"""The LaneNet detector: weights file in, `LaneEstimate` out, GRU state kept between frames.

    detector = LaneNetDetector(camera, weights="detectors/weights/lanenet.pt")
    estimate = detector.detect(frame)      # ego lane, vehicle frame
    detector.last.boundaries               # every boundary it saw in that frame

A weights file is a dict saved by `save_weights`: a format tag, the architecture
(`LaneNetConfig`) and the state dict, read back with `torch.load(..., weights_only=True)` so a
file can hold tensors and plain values only, never code. Anything wrong with it (missing, empty,
corrupt, another architecture, other shapes) is one `WeightsError` naming the file.

The state is dropped on `reset()` and on a scene change, seen as a jump of the mean grey
difference between consecutive thumbnails: what the GRU remembers of another road would mislead.

With `mirror` (the default) each frame is also run mirrored left-right, in the same batch, and
the boundaries are fitted to the proposals of both passes (the mirrored ones mapped back, their
slots swapped). Why: though trained with mirrored frames, the network is not mirror-symmetric
(likely because its stride-2 convolutions sample each cell off its centre, which training
cancels only where the evidence is strong): it places far, faint markings 1-3 px to the image's
left. Seen from the rear camera, whose fits lean on a few far points, a straight road read as a
1200-1500 m radius bend and the reference 1 cm off. The pooled fit is mirror-symmetric by
construction (so is the RANSAC, lanenet_decode.fit_boundaries); it costs 1.3-1.6x the time of
one pass (one batch of two), not 2x.

`LaneNetDetector.detect_many` runs detectors that hold the same weights as one batch (the
loop's front LaneNet and rear reference: four items), each keeping its own state and camera,
with the results of `detect` bit for bit; it takes 1.1x less time than two `detect` calls.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
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
    MAX_RANGE_M,
    SCORE_POWER,
    UNSEEN_WEIGHT,
    WIDTH_STD_M,
    Boundary,
    DecodeSettings,
    Proposals,
    ego_estimate,
    fit_boundaries,
    proposals,
)
from lanekeep.detectors.lanenet_model import (
    LaneNet,
    LaneNetConfig,
    LaneNetOutput,
    LaneNetState,
    prepare_frame,
)
from lanekeep.detectors.lanenet_targets import SLOTS, CellGrid
from lanekeep.detectors.network_io import WeightsError, one_torch_thread, read_weights_blob
from lanekeep.geometry.camera_model import CameraModel

FORMAT = "lanekeep-lanenet/1"
CANDIDATE_SCORE = 0.05  # the lowest objectness kept as a candidate proposal (for AP)
DEFAULT_WEIGHTS = "weights/lanenet.pt"  # inside the detectors package
# Slot order of a mirrored frame's outputs: its ego-left is the frame's ego-right, and so on.
MIRRORED_SLOTS = [SLOTS.index(n.replace("left", "?").replace("right", "left").replace("?", "right"))
                  for n in SLOTS]


def save_weights(model: LaneNet, path: str | Path, meta: dict | None = None) -> None:
    """Write the model's architecture and weights (and plain metadata) to `path`."""
    torch.save({"format": FORMAT, "config": model.config.to_dict(),
                "state_dict": model.state_dict(), "meta": dict(meta or {})}, str(path))


def load_weights(path: str | Path) -> LaneNet:
    """The network stored in `path`, in eval mode, or `WeightsError`."""
    p = Path(path)
    blob = read_weights_blob(p, FORMAT, "LaneNet")
    try:
        model = LaneNet(LaneNetConfig.from_dict(blob["config"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise WeightsError(p, f"unknown LaneNet architecture: {exc}") from None
    try:
        model.load_state_dict(blob.get("state_dict", {}), strict=True)
    except (RuntimeError, TypeError, AttributeError) as exc:
        first = str(exc).splitlines()
        raise WeightsError(p, "weights do not fit the LaneNet architecture: "
                              f"{first[1].strip() if len(first) > 1 else exc}") from None
    return model.eval()


def _proposals_of(out, b: int, grid: CellGrid, floor: float, mirrored: bool = False
                  ) -> Proposals:
    """Proposals of batch item `b` (first time step); `mirrored`: that item is the frame
    mirrored left-right, so its cells, offsets and slots are mapped back to the frame's
    (the grid's columns mirror exactly: the working width is a whole number of cells)."""
    objectness, x_offset = out.objectness[b, 0].numpy(), out.x_offset[b, 0].numpy()
    slot, marking = out.slot[b, 0].numpy(), out.marking[b, 0].numpy()
    if mirrored:
        objectness, marking = objectness[:, ::-1], marking[:, ::-1]
        x_offset = 1.0 - x_offset[:, ::-1]
        slot = slot[MIRRORED_SLOTS][:, :, ::-1]
    return proposals(objectness, x_offset, slot, grid, floor, marking)


@dataclass(frozen=True)
class LaneNetSettings:
    """The detector's settings (a `[lanenet]` table of the detectors TOML, once registered)."""

    weights: str = ""  # "" = the shipped detectors/weights/lanenet.pt
    score_threshold: float = 0.5
    inlier_px: float = 6.0
    ransac_iterations: int = 100
    min_points: int = 4
    seed: int = 0
    scene_change_grey: float = 30.0  # mean |grey difference| of thumbnails (0..255) = new scene
    mirror: bool = True  # also run the mirrored frame and fit to both passes' proposals
    curvature_prior_per_m: float = CURVATURE_PRIOR_PER_M  # lanenet_decode.DecodeSettings
    curvature_prior_shape: str = CURVATURE_PRIOR_SHAPE  # lanenet_decode.DecodeSettings
    unseen_weight: float = UNSEEN_WEIGHT  # lanenet_decode.DecodeSettings
    width_std_m: float = WIDTH_STD_M  # lanenet_decode.DecodeSettings
    score_power: float = SCORE_POWER  # lanenet_decode.DecodeSettings
    max_range_m: float = MAX_RANGE_M  # lanenet_decode.DecodeSettings

    def decode(self) -> DecodeSettings:
        return DecodeSettings(score_threshold=self.score_threshold, inlier_px=self.inlier_px,
                              iterations=self.ransac_iterations, min_points=self.min_points,
                              seed=self.seed, curvature_prior_per_m=self.curvature_prior_per_m,
                              curvature_prior_shape=self.curvature_prior_shape,
                              unseen_weight=self.unseen_weight, width_std_m=self.width_std_m,
                              score_power=self.score_power, max_range_m=self.max_range_m)


@dataclass(frozen=True)
class Decoded:
    """Everything one frame gave: its proposals (score above the threshold: what the
    boundaries are fitted to), every fitted boundary, and the candidates down to
    CANDIDATE_SCORE (for AP, which ranks proposals over all confidences)."""

    proposals: Proposals  # with `mirror`, both passes' (the mirrored one mapped back)
    boundaries: list[Boundary]
    scene_change: bool
    candidates: Proposals | None = None  # the frame's own pass only: what AP scores


class LaneNetDetector:
    """`Detector` protocol over the spatiotemporal network (paper 000)."""

    weights_format = FORMAT  # the files `--weights` may give it (registry.weights_fit)

    name = "lanenet"

    def __init__(
        self,
        camera: CameraModel,
        config: DetectorsConfig | None = None,
        distortion: np.ndarray | None = None,
        settings: LaneNetSettings | None = None,
        weights: str | Path | None = None,
    ) -> None:
        self.camera = camera
        self.config = config or load_config()
        self.settings = settings or LaneNetSettings()
        path = weights or self.settings.weights or resources.files("lanekeep.detectors").joinpath(
            DEFAULT_WEIGHTS)
        self.model = load_weights(path)
        self.weights_path = str(path)
        # detectors whose files hold the same bytes run as one batch (`detect_many`)
        self._weights_digest = hashlib.sha256(Path(path).read_bytes()).hexdigest()
        self.view, self.x_ref = detector_view(camera, self.config, distortion)
        self.distortion = None
        if distortion is not None and np.any(np.asarray(distortion) != 0):
            self.distortion = np.asarray(distortion, dtype=float)
        self._decode = self.settings.decode()
        self._state: LaneNetState | None = None
        self._thumb: np.ndarray | None = None
        self._frame_size = (camera.height, camera.width)
        self.last: Decoded | None = None

    @property
    def window(self) -> GroundWindow:
        return self.view.window

    def reset(self) -> None:
        self._state = None
        self._thumb = None
        self.last = None

    def _scene_changed(self, image: np.ndarray) -> bool:
        """Compare a 40x22 grey thumbnail with the previous frame's."""
        grey = image.astype(np.float32).mean(axis=0)
        thumb = cv2.resize(grey, (40, 22), interpolation=cv2.INTER_AREA)
        changed = self._thumb is not None and float(
            np.abs(thumb - self._thumb).mean()) > self.settings.scene_change_grey
        self._thumb = thumb
        return changed

    def _camera_for(self, width: int, height: int) -> CameraModel:
        if (self.camera.width, self.camera.height) == (width, height):
            return self.camera
        return self.camera.scaled(width, height)

    def infer(self, frame: np.ndarray) -> Decoded:
        """Run the network on one frame (keeping state) and decode every boundary."""
        return _infer_together([self], [frame])[0]

    def _begin(self, frame: np.ndarray) -> tuple[np.ndarray, bool]:
        """The frame at the working size, and whether it starts a new scene (state dropped)."""
        self._frame_size = frame.shape[:2]
        image = prepare_frame(frame, self.model.config)
        changed = self._scene_changed(image)
        if changed:
            self._state = None
        return image, changed

    def _items(self, image: np.ndarray) -> list[torch.Tensor]:
        """The frame's batch items, (1, 1, 3, h, w) each: the frame, and its mirror."""
        item = torch.from_numpy(image)[None, None]
        return [item, item.flip(-1)] if self.settings.mirror else [item]

    def _decode_items(self, out: LaneNetOutput, first: int, frame: np.ndarray,
                      changed: bool) -> Decoded:
        """Decode the frame from its batch items `first` (and `first + 1`, the mirror)."""
        rows, cols = self.model.config.grid
        grid = CellGrid(frame.shape[1], frame.shape[0], rows, cols)
        floor = min(CANDIDATE_SCORE, self._decode.score_threshold)
        candidates = _proposals_of(out, first, grid, floor)
        pooled = candidates
        if self.settings.mirror:
            mirrored = _proposals_of(out, first + 1, grid, floor, mirrored=True)
            pooled = Proposals(*(np.concatenate([getattr(candidates, f.name),
                                                 getattr(mirrored, f.name)])
                                 for f in fields(Proposals)))
        keep = pooled.scores > self._decode.score_threshold
        props = Proposals(*(getattr(pooled, f.name)[keep] for f in fields(Proposals)))
        camera = self._camera_for(frame.shape[1], frame.shape[0])
        boundaries = fit_boundaries(self._undistorted(props, camera), grid, self._decode, camera)
        self.last = Decoded(props, boundaries, changed, candidates)
        return self.last

    def boundaries_in_image(self) -> list[Boundary]:
        """The last frame's boundaries fitted in the image (u = A + B d + C / d, d = rows below
        a horizon found from the boundaries themselves) instead of on the ground: for a photo
        whose camera is a guess (no camera file), where a wrong pitch or height would bend the
        ground fit. On 10 TuSimple frames this fit scored better than the ground fit through
        the guessed dashcam camera (tools/tune_real.py)."""
        if self.last is None:
            return []
        rows, cols = self.model.config.grid
        frame_h, frame_w = self._frame_size
        props = self._undistorted(self.last.proposals, self._camera_for(frame_w, frame_h))
        return fit_boundaries(props, CellGrid(frame_w, frame_h, rows, cols), self._decode, None)

    def _undistorted(self, props: Proposals, camera: CameraModel) -> Proposals:
        """The proposals with their points moved to the pinhole image (no-op without a lens
        distortion), where the fits' flat-road models hold."""
        if self.distortion is None or not len(props.points_px):
            return props
        pts = cv2.undistortPoints(props.points_px.reshape(-1, 1, 2).astype(np.float64),
                                  camera.K, self.distortion, P=camera.K).reshape(-1, 2)
        return replace(props, points_px=pts)

    def detect(self, frame: np.ndarray) -> LaneEstimate:
        return self._estimate(self.infer(frame), frame)

    def _estimate(self, decoded: Decoded, frame: np.ndarray) -> LaneEstimate:
        rules = self.config.lane
        return ego_estimate(decoded.boundaries, self._camera_for(frame.shape[1], frame.shape[0]),
                            self.x_ref, rules.lane_width_m, rules.width_tolerance_m, self._decode)

    @classmethod
    def detect_many(cls, detectors: Sequence[LaneNetDetector], frames: Sequence[np.ndarray]
                    ) -> list[LaneEstimate]:
        """Each detector's `detect` of its frame, with one network call for those that hold
        the same weights (the loop's front LaneNet and its rear reference: one batch of four,
        the frames and their mirrors), so the per-call work is paid once. Each keeps its own
        state, camera and settings and gets what `detect` gives, bit for bit (a batch item's
        outputs do not depend on the others; tests/detectors/test_lanenet_speed_equivalence.py).
        Should anything raise, every detector is left as it was before the call, so that the
        caller may run them one at a time instead (lanekeep/driver/detection.py does)."""
        saved = [(d._state, d._thumb, d._frame_size, d.last) for d in detectors]
        try:
            decoded = _infer_together(list(detectors), list(frames))
            return [d._estimate(x, f) for d, x, f in zip(detectors, decoded, frames, strict=True)]
        except Exception:
            for d, (state, thumb, size, last) in zip(detectors, saved, strict=True):
                d._state, d._thumb, d._frame_size, d.last = state, thumb, size, last
            raise


def _infer_together(detectors: list[LaneNetDetector], frames: list[np.ndarray]) -> list[Decoded]:
    """`infer` for each detector, one network call per set of detectors with the same weights
    and alike state (all fresh, or all carrying one: a fresh start is the network's own case,
    `state=None`, for the whole batch)."""
    if len(detectors) != len(frames):
        raise ValueError(f"{len(detectors)} detectors for {len(frames)} frames")
    if len({id(d) for d in detectors}) != len(detectors):
        raise ValueError("a detector listed twice (its state cannot take two frames at once)")
    begun = [d._begin(f) for d, f in zip(detectors, frames, strict=True)]
    groups: dict[tuple[str, bool], list[int]] = {}
    for i, d in enumerate(detectors):
        groups.setdefault((d._weights_digest, d._state is None), []).append(i)
    placed: list[tuple[LaneNetOutput | None, int]] = [(None, 0)] * len(detectors)
    # Every torch call inside: one outside would run on the process's thread count and, on
    # a machine whose other core is busy, wait milliseconds for its second thread.
    with torch.inference_mode(), portable_torch(), one_torch_thread():
        for members in groups.values():
            items, starts = [], []
            for i in members:
                starts.append(len(items))
                items += detectors[i]._items(begun[i][0])
            states = [detectors[i]._state for i in members]
            state = states[0] if len(states) == 1 or states[0] is None else LaneNetState(
                *(torch.cat(parts) for parts in zip(*states, strict=True)))
            out, state = detectors[members[0]].model(torch.cat(items), state)
            for i, start, end in zip(members, starts, [*starts[1:], len(items)], strict=True):
                detectors[i]._state = LaneNetState(state.features[start:end],
                                                   state.hidden[start:end])
                placed[i] = (out, start)
    return [d._decode_items(out, start, frame, changed)
            for d, (out, start), frame, (_, changed)
            in zip(detectors, placed, frames, begun, strict=True)]
