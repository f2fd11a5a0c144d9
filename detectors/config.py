"""Tuned numbers of the classical detectors: frozen dataclasses read from `detectors.toml`.

Every threshold and window size lives in the shipped TOML (detectors/detectors.toml), and
the dataclass defaults are the same tuned values (a test holds them equal), so
`DetectorsConfig()` and a partial TOML file are tuned too. Loading is strict (unknown keys
raise, naming the key), as for scenario files.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path

from lanekeep.core.config_io import InvalidValue, from_dict
from lanekeep.geometry.lane_width import LANE_WIDTH_PRIOR_M


@dataclass(frozen=True)
class GroundWindow:
    """The patch of road the bird's-eye view shows, in the vehicle ground frame.

    `x_near_m` is the edge nearest the car (front: ahead of the bumper; rear: behind it, so
    negative), `x_far_m` the far edge; the view spans y in [-y_half_m, +y_half_m]. Pixels are
    `m_per_col` wide and `m_per_row` long (the long axis needs less resolution).
    """

    x_near_m: float = 4.0
    x_far_m: float = 20.0
    y_half_m: float = 6.0
    m_per_col: float = 0.05
    m_per_row: float = 0.1
    lookahead_m: float | None = None  # where the offset is reported; None = the near edge

    def __post_init__(self) -> None:
        if abs(self.x_far_m - self.x_near_m) < 1.0:
            raise InvalidValue("x_far_m", "the window must be at least 1 m long")
        if self.x_near_m * self.x_far_m < 0:
            raise InvalidValue("x_far_m", "near and far edge must lie on the same side of the car")
        for key in ("y_half_m", "m_per_col", "m_per_row"):
            if not getattr(self, key) > 0:
                raise InvalidValue(key, f"must be > 0, got {getattr(self, key)}")

    @property
    def direction(self) -> float:
        """+1 for a window ahead of the car, -1 behind it."""
        return 1.0 if self.x_far_m > self.x_near_m else -1.0


@dataclass(frozen=True)
class Profiles:
    """One ground window per camera kind; a detector picks by the camera's name."""

    front: GroundWindow = GroundWindow()
    rear: GroundWindow = GroundWindow(x_near_m=-4.0, x_far_m=-16.0)
    dashcam: GroundWindow = GroundWindow(x_near_m=6.0, x_far_m=40.0, m_per_row=0.15)


@dataclass(frozen=True)
class Preprocess:
    """Region of interest and working resolution of the image stage."""

    scale: float = 0.5  # image downscale before thresholding
    horizon_margin_px: float = 8.0  # ROI starts this far (full-res px) below the horizon
    max_fill: float = 0.25  # binary share of the ROI above which the frame is rejected (noise)
    min_coherence: float = 0.5  # share of binary pixels that survive a 2x2 opening (paint
    # comes in blobs, sensor noise in isolated pixels); below it the frame is rejected
    streak_min_rows: int = 24  # binary runs at least this tall and near-vertical are rain
    # streaks, not lane paint (0 = keep them); rows of a 720-row frame at full resolution
    streak_max_tilt_deg: float = 15.0  # how far from vertical a streak may lean
    destreak_width_px: float = 6.0  # bright features narrower than this along a row (pixels of
    # a 720-row frame at full resolution) are opened away before binarising: rain streaks
    # Other vehicles (detectors/vehicle_mask.py): the dark band under a vehicle hides the road
    # above it in its columns; 0 turns the cue off.
    vehicle_dark_ratio: float = 0.3  # darker than this share of the road's median: underside
    vehicle_min_width_m: float = 1.0  # a dark run this wide (across the road) or wider ...
    vehicle_max_width_m: float = 4.5  # ... and no wider is a vehicle's underside
    vehicle_margin_m: float = 0.3  # the body reaches this far beside its dark band
    vehicle_edge_px: int = 2  # working pixels along a row from vehicle-dark that are not paint
    max_paint_width_m: float = 0.35  # wider bird's-eye runs are not paint; 0 = keep all
    paint_blur_px: float = 3.0  # working pixels of spread added to that width at each distance

    def __post_init__(self) -> None:
        if not 0.1 <= self.scale <= 1.0:
            raise InvalidValue("scale", f"must be in [0.1, 1], got {self.scale}")
        if self.destreak_width_px < 0:
            raise InvalidValue("destreak_width_px", f"must be >= 0, got {self.destreak_width_px}")
        if self.streak_min_rows < 0:
            raise InvalidValue("streak_min_rows", f"must be >= 0, got {self.streak_min_rows}")
        if not 0.0 <= self.vehicle_dark_ratio < 1.0:
            raise InvalidValue("vehicle_dark_ratio",
                               f"must be in [0, 1), got {self.vehicle_dark_ratio}")
        if not 0.0 < self.vehicle_min_width_m <= self.vehicle_max_width_m:
            raise InvalidValue("vehicle_min_width_m", "must be > 0 and <= vehicle_max_width_m")
        if self.max_paint_width_m < 0 or self.paint_blur_px < 0 or self.vehicle_margin_m < 0:
            raise InvalidValue("max_paint_width_m", "widths and margins must be >= 0")


@dataclass(frozen=True)
class LaneRules:
    """What counts as an ego-lane boundary, in metres."""

    lane_width_m: float = LANE_WIDTH_PRIOR_M  # a belief, not the road's (geometry/lane_width.py)
    width_tolerance_m: float = 0.8  # |measured - lane_width| above this: keep only the better side
    min_half_width: float = 0.1  # a boundary's |y| at the near edge, in lane widths
    max_half_width: float = 1.1
    min_span_m: float = 2.0  # a boundary must cover this much x
    quadratic_span_m: float = 8.0  # fit a parabola only over at least this x span
    max_curvature_1pm: float = 0.05  # |2 c2| above this: a bad fit (R < 20 m)
    max_heading_deg: float = 20.0  # a boundary's direction at the look-ahead, from the car's
    max_extrapolation: float = 1.5  # a short lone boundary reaches this many spans at most
    inlier_m: float = 0.25  # points further from a boundary's fit are refitted without; 0 = off

    def __post_init__(self) -> None:
        if not self.lane_width_m > 0:
            raise InvalidValue("lane_width_m", f"must be > 0, got {self.lane_width_m}")


@dataclass(frozen=True)
class HoughConfig:
    """Model #1: brightness threshold relative to the road beside a ridge, bird's-eye view,
    probabilistic Hough."""

    # A pixel must exceed the road on both sides of it (a paint width away along the row) by
    # `adaptive_ratio` of it: relative to the local light, for paint in shade keeps its ratio
    # to the asphalt (1.5-1.8), not its level; faint sunlit paint is only ~1.2-1.35 of it.
    adaptive_ratio: float = 0.2  # #44 ridge re-tune (closed loop on the tuning scenarios)
    adaptive_c: float = 10.0  # and by at least this many grey levels (sensor noise, dark road)
    min_grey: int = 20  # and be at least this bright (a dark floor: #44's paint is ~58-110)
    rho_px: float = 1.0
    theta_deg: float = 1.0
    votes: int = 12
    min_length_m: float = 1.0
    max_gap_m: float = 1.5
    max_angle_deg: float = 35.0  # segments further from the driving direction are dropped
    seed_length_m: float = 10.0  # boundaries are seeded from segments starting this near
    cluster_m: float = 0.4  # seeds closer than this (at the near edge) are one boundary
    grow_tolerance_m: float = 0.35  # a segment joins a boundary within this of its fit
    sample_m: float = 0.5  # spacing of the points taken along each segment

    def __post_init__(self) -> None:
        if self.adaptive_ratio < 0 or self.adaptive_c < 0:
            raise InvalidValue("adaptive_ratio", "adaptive_ratio and adaptive_c must be >= 0")


@dataclass(frozen=True)
class SlidingWindowConfig:
    """Model #2: Sobel-x + HLS saturation/hue thresholds, histogram, sliding windows."""

    sobel_kernel: int = 3
    # Shade compensation: lightness is scaled so that the local background (a wide box blur)
    # reads `illumination_target`, by a gain of at most `illumination_max_gain` (1 = off)
    # and at least `illumination_min_gain`. Paint in a building's shadow keeps its contrast
    # ratio to the asphalt, not its level.
    illumination_block_px: int = 61
    illumination_target: float = 80.0
    illumination_max_gain: float = 4.0
    illumination_min_gain: float = 0.5  # #44: thresholds below are shares of the light
    sobel_min: float = 25.0  # |d lightness / dx| in grey levels per pixel (Sobel-scaled / 4)
    min_lightness_gain: float = 15.0  # gradient pixels must sit in a brighter-than-local ridge
    local_block_px: int = 25
    white_lightness: int = 105  # normalised HLS L at or above: paint-white (#44: was 180)
    white_saturation_max: int = 255
    yellow_hue: tuple[int, int] = (12, 38)  # OpenCV hue (0..180) range of yellow paint
    yellow_saturation: int = 90
    yellow_lightness: int = 80
    n_windows: int = 11
    margin_m: float = 0.45  # half width of a window
    min_pixels: int = 8  # a window re-centres when it holds this many pixels
    histogram_fraction: float = 0.5  # the near part of the view that the histogram sums
    min_peak_pixels: int = 15
    search_margin_m: float = 0.4  # around the previous frame's fit
    min_fit_pixels: int = 40

    def __post_init__(self) -> None:
        if not 0.0 < self.illumination_min_gain <= max(1.0, self.illumination_max_gain):
            raise InvalidValue("illumination_min_gain", "must be > 0 and <= the max gain")
        if self.sobel_kernel not in (1, 3, 5, 7):
            raise InvalidValue("sobel_kernel", "must be 1, 3, 5 or 7")
        if self.local_block_px < 3 or self.local_block_px % 2 == 0:
            raise InvalidValue("local_block_px", "must be odd and >= 3")


@dataclass(frozen=True)
class DashcamDefaults:
    """An unknown real camera (`lanekeep detect` without --camera): typical highway dashcam."""

    hfov_deg: float = 60.0
    height_m: float = 1.5
    horizon_fraction: float = 0.5  # horizon row / image height when it cannot be estimated
    min_horizon_fraction: float = 0.2
    max_horizon_fraction: float = 0.75


# Top-level tables that belong to detectors registered with their own settings class
# (detectors.registry.register_detector); their contents are checked when such a detector is
# made, against its class.
_DETECTOR_TABLES: set[str] = set()


def register_table(name: str) -> None:
    """Let detectors.toml files carry a `[name]` table for a registered detector."""
    _DETECTOR_TABLES.add(name)


@dataclass(frozen=True)
class DetectorsConfig:
    profiles: Profiles = Profiles()
    preprocess: Preprocess = Preprocess()
    lane: LaneRules = LaneRules()
    hough: HoughConfig = HoughConfig()
    sliding_window: SlidingWindowConfig = SlidingWindowConfig()
    dashcam: DashcamDefaults = DashcamDefaults()
    # Raw tables of registered detectors, by name (not part of the strict schema above).
    tables: dict[str, dict] = field(default_factory=dict, metadata={"toml": False})

    def window_for(self, camera_name: str) -> GroundWindow:
        """The ground window of a camera: by name, real cameras use the dashcam profile."""
        if camera_name in ("front", "rear"):
            return getattr(self.profiles, camera_name)
        return self.profiles.dashcam


def load_config(path: str | Path | None = None) -> DetectorsConfig:
    """Read a detectors TOML file; None reads the shipped, tuned detectors/detectors.toml."""
    if path is None:
        text = resources.files("lanekeep.detectors").joinpath("detectors.toml").read_text()
        source = "detectors.toml"
    else:
        text = Path(path).read_text()
        source = str(path)
    data = tomllib.loads(text)
    tables = {name: data.pop(name) for name in list(data) if name in _DETECTOR_TABLES}
    return replace(from_dict(DetectorsConfig, data, source=source), tables=tables)
