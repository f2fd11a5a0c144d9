"""What the paper's two classical models share: construction, the image stage, assembly.

A classical detector is its binarisation of the region of interest (`binarise`) and its way of
finding the lane lines in the binary bird's-eye view (`find_boundaries`: the car's two and the
other lanes', detectors/lane_lines.py); everything
around them, the ground window and look-ahead, the shared image stage (crop, scale, rain
streaks, noise tests, warp) and the assembly into a `LaneEstimate`, is here once. Models that
read the same frame share its region of interest (`image_stage.SHARED_ROIS`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, ClassVar

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.birds_eye import detector_view
from lanekeep.detectors.boundaries import assemble, support_confidence
from lanekeep.detectors.config import DetectorsConfig, GroundWindow, load_config
from lanekeep.detectors.image_stage import (
    SHARED_ROIS,
    RegionOfInterest,
    RoiMemo,
    binary_bird_eye,
    drop_blobs,
    grain_noise,
    join_along_road,
    join_dot_rows,
    reject_noise,
    warped_roi,
)
from lanekeep.detectors.lane_lines import LaneLines
from lanekeep.detectors.vehicle_mask import VehicleFilter
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.lane_poly import LanePoly

WIDTH_GAIN = 0.3  # weight of a new frame's measured width in the running width


class ClassicalDetector:
    """Base of models #1 and #2: `detect(frame)` = image stage -> boundaries -> estimate."""

    default_name = "classical"
    # The `DetectorsConfig` table holding this model's `binarisation` and `fallback`.
    settings_table: ClassVar[str] = ""
    # The binarisation that finds paint in the bird's-eye view rather than in the image.
    bird_eye_binarisation: ClassVar[str] = ""

    def __init__(
        self,
        camera: CameraModel,
        config: DetectorsConfig | None = None,
        distortion: np.ndarray | None = None,
        name: str | None = None,
    ) -> None:
        self.name = name or self.default_name
        self.camera = camera
        self.config = config or load_config()
        self.view, self.x_ref = detector_view(camera, self.config, distortion)
        self.vehicles = VehicleFilter.of(self.view, self.config.preprocess)
        # Where the region of interest is shared with the other models (None: not shared).
        self.rois: RoiMemo | None = SHARED_ROIS
        self._width: float | None = None  # the lane's width as measured on earlier frames
        # The same model with its fallback binarisation, asked on the frames where this
        # one finds no lane (None: no fallback set).
        mode = self.fallback_binarisation
        self._fallback: ClassicalDetector | None = None if not mode else type(self)(
            camera, self.with_binarisation(mode), distortion, name=self.name)

    @property
    def window(self) -> GroundWindow:
        """The patch of ground the detector looks at (vehicle frame)."""
        return self.view.window

    def reset(self) -> None:
        """Forget state carried between frames: the lane width measured so far (and what a
        model keeps of its own)."""
        self._width = None
        if self._fallback is not None:
            self._fallback.reset()

    @property
    def settings(self) -> Any:
        """This model's own table of the detectors' settings (`settings_table`)."""
        return getattr(self.config, self.settings_table)

    @property
    def fallback_binarisation(self) -> str:
        """The binarisation tried on a frame where this model's own finds no valid lane
        ("": none)."""
        return self.settings.fallback if self.settings_table else ""

    def with_binarisation(self, mode: str) -> DetectorsConfig:
        """This model's settings with binarisation `mode` and no fallback of its own."""
        own = replace(self.settings, binarisation=mode, fallback="")
        return replace(self.config, **{self.settings_table: own})

    @property
    def bird_eye_paint(self) -> bool:
        """Whether this model finds paint in the bird's-eye view (its binarisation setting
        is `bird_eye_binarisation`); such a model also fits unweighted and remembers the
        lane's measured width."""
        if not self.settings_table:
            return False
        return self.settings.binarisation == self.bird_eye_binarisation

    @property
    def lane_width_m(self) -> float:
        """The width a lone boundary is offset by: as measured on earlier frames of this
        drive, else the car's prior."""
        return self._width if self._width is not None else self.config.lane.lane_width_m

    def _measure_width(self, estimate: LaneEstimate) -> None:
        """Fold a frame's measured width (both boundaries, consistent with the prior) into
        the running width: roads are 3.0-3.9 m wide where the prior says one figure, and a
        lone boundary offset by the wrong width errs by half the difference."""
        if not estimate.valid or estimate.left is None or estimate.right is None:
            return
        x = estimate.x_m
        measured = float(LanePoly.of(estimate.left).y(x) - LanePoly.of(estimate.right).y(x))
        rules = self.config.lane
        if abs(measured - rules.lane_width_m) > rules.width_tolerance_m:
            return
        self._width = (measured if self._width is None
                       else (1.0 - WIDTH_GAIN) * self._width + WIDTH_GAIN * measured)

    def binarise(self, roi: RegionOfInterest) -> np.ndarray:
        """Paint candidates (0/255) in the region of interest at the working scale (its
        arrays are shared with the other models: read them, never write)."""
        raise NotImplementedError

    def find_boundaries(self, bev: np.ndarray) -> LaneLines:
        """The car's (left, right) boundaries in the binary bird's-eye view (None where not
        found) and the other lanes' lines."""
        raise NotImplementedError

    def remember(self, estimate: LaneEstimate) -> None:
        """Keep what the next frame needs from this frame's estimate (nothing by default)."""

    def bird_eye(self, frame: np.ndarray) -> tuple[np.ndarray | None, str]:
        """The frame's binary bird's-eye view (0/255), or None and why it is noise: the
        shared image stage with this model's `binarise`, or, for a model that finds paint
        in the bird's-eye view, the region's warp with this model's `bird_eye_mask`."""
        pre = self.config.preprocess
        if not self.bird_eye_paint:
            return binary_bird_eye(frame, self.camera, self.view, pre, self.binarise,
                                   self.vehicles, self.rois)
        roi, seen = warped_roi(frame, self.camera, self.view, pre, self.vehicles, self.rois)
        noise = grain_noise(roi, pre)
        if noise:
            return None, noise
        mask = self.bird_eye_mask(roi, seen)
        noise = reject_noise(mask, self.bird_eye_max_fill, 0.0)
        return (None, noise) if noise else (mask, "")

    def bird_eye_mask(self, roi: RegionOfInterest, seen: np.ndarray) -> np.ndarray:
        """Paint (0/255) in the bird's-eye view, from the region of interest and where the
        road is seen there (the models with `bird_eye_paint`)."""
        raise NotImplementedError

    @property
    def bird_eye_max_fill(self) -> float:
        """The share of the bird's-eye view above which a paint mask is noise."""
        return self.config.preprocess.max_fill

    def detect(self, frame: np.ndarray) -> LaneEstimate:
        """The frame's lane by this model's binarisation; where that finds no valid lane and a
        fallback binarisation is set, the fallback's lane if it finds a valid one. Both keep
        the lane a frame settled on (a model that searches near its last fit searches near
        it on the next frame, whichever binarisation found it)."""
        estimate = self._detect_own(frame)
        if self._fallback is None:
            return estimate
        if estimate.valid:
            self._fallback.remember(estimate)
            return estimate
        backup = self._fallback.detect(frame)
        if not backup.valid:
            return estimate
        self.remember(backup)
        return backup

    def _detect_own(self, frame: np.ndarray) -> LaneEstimate:
        bev, noise = self.bird_eye(frame)
        if bev is None:
            estimate = LaneEstimate.invalid(noise, self.x_ref)
            self.remember(estimate)  # a noisy frame drops the fit, not the measured width
            return estimate
        pre, w = self.config.preprocess, self.view.window
        if pre.join_min_dots:
            bev = join_dot_rows(bev, w.m_per_row, w.m_per_col, pre.join_along_m,
                                pre.join_min_dots)
        else:
            bev = join_along_road(bev, w.m_per_row, pre.join_along_m)
        bev = drop_blobs(bev, w.m_per_row, w.m_per_col, pre.min_blob_length_m,
                         pre.min_blob_elongation)
        lines = self.find_boundaries(bev)
        width = self.lane_width_m if self.bird_eye_paint else None
        estimate = assemble(lines.left, lines.right, self.x_ref, self.config.lane, self.camera,
                            support_confidence(lines.left, lines.right, self.view), width,
                            lines.others)
        if self.bird_eye_paint:
            self._measure_width(estimate)
        self.remember(estimate)
        return estimate
