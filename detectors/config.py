"""Tuned numbers of the classical detectors: frozen dataclasses, overridable from TOML.

Each setting is defined once, here: its default is the tuned value, with a comment saying what
it is and, for a tuned or measured number, where it came from. The shipped
detectors/detectors.toml holds overrides of these defaults only (none today), and so does a
user's file (`lanekeep detect --config`, `python -m lanekeep.tuning.detector_replay score
--config`): a key it leaves out keeps the default. Loading is strict (unknown keys raise,
naming the key), as for scenario files.

"#44" marks the re-tune of the classical detectors on the realistic renders (closed loop and
`python -m lanekeep.tuning.detector_replay` on the tuning scenarios only,
lanekeep/tuning/scenario_files); "traffic" the tuning on its unscored traffic scenarios.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, fields, is_dataclass, replace
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

    x_near_m: float = 4.0  # near edge of the view, metres ahead (negative: behind)
    x_far_m: float = 20.0  # far edge of the view
    y_half_m: float = 6.0  # the view spans y in [-y_half_m, +y_half_m]: the lane and its neighbours
    m_per_col: float = 0.05  # across-road size of a bird's-eye pixel
    m_per_row: float = 0.1  # along-road size of a bird's-eye pixel
    lookahead_m: float | None = None  # where the offset is reported; None = the near edge
    # The nearest metres of the window where the bird's-eye models look for no paint (the
    # boundaries are extrapolated over them): the front camera's hood hides the paint there
    # and its edge, meeting a line, makes a short false ridge beside it. 0.5 m on the front:
    # on frames with the hood (tests/detectors' clear_straight poses) the median offset
    # error went 10.6 -> 2.7 cm (sliding_window) and the worst boundary 17 -> 7 cm (hough);
    # on the tuning sets, half of whose worlds show no hood, IoU-ego fell 0.016 / 0.012.
    blind_m: float = 0.0

    def __post_init__(self) -> None:
        if abs(self.x_far_m - self.x_near_m) < 1.0:
            raise InvalidValue("x_far_m", "the window must be at least 1 m long")
        if self.x_near_m * self.x_far_m < 0:
            raise InvalidValue("x_far_m", "near and far edge must lie on the same side of the car")
        for key in ("y_half_m", "m_per_col", "m_per_row"):
            if not getattr(self, key) > 0:
                raise InvalidValue(key, f"must be > 0, got {getattr(self, key)}")
        if not 0.0 <= self.blind_m < abs(self.x_far_m - self.x_near_m) / 2:
            raise InvalidValue("blind_m", "must be >= 0 and under half the window's length")

    @property
    def direction(self) -> float:
        """+1 for a window ahead of the car, -1 behind it."""
        return 1.0 if self.x_far_m > self.x_near_m else -1.0


@dataclass(frozen=True)
class Profiles:
    """One ground window per camera kind; a detector picks by the camera's name."""

    front: GroundWindow = GroundWindow(blind_m=0.5)  # the simulated front cameras (the scored
    # ADE window)
    rear: GroundWindow = GroundWindow(x_near_m=-4.0, x_far_m=-16.0)  # the rear camera
    # Real cameras (any camera not named front or rear): a longer, coarser window.
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
    # above it in its columns; 0 turns the cue off. Tuned on the traffic scenarios.
    vehicle_dark_ratio: float = 0.3  # darker than this share of the road's median: underside
    vehicle_min_width_m: float = 1.0  # a dark run this wide (across the road) or wider ...
    vehicle_max_width_m: float = 4.5  # ... and no wider is a vehicle's underside
    vehicle_margin_m: float = 0.3  # the body reaches this far beside its dark band
    vehicle_edge_px: int = 2  # working pixels along a row from vehicle-dark that are not paint
    max_paint_width_m: float = 0.35  # wider bird's-eye runs are not paint; 0 = keep all
    paint_blur_px: float = 3.0  # working pixels of spread added to that width at each distance
    # For the models that find paint in the bird's-eye view (hough's "ridge", sliding_window's
    # "edges"): the region of interest's grain (median |grey - its 3x3 mean| / median grey)
    # above which the frame is noise: at most 0.051 on the tuning sets (half shade), 0.031 in
    # the shipped night scenario's frames, 0.091 on uniform noise, whose random streaks the
    # along-line average would otherwise join into lines.
    max_grain: float = 0.07
    # Sun flecks under a tree's crown (lanekeep/world/shade.py: blobs of 2-20 cm) are as bright
    # against the leaf shade as paint against its road, and as wide as paint in the bird's-eye
    # view: no threshold on contrast or width tells them apart. Their shape does: a lane line,
    # even a dash (3 m), runs along the road, a fleck is a blob. A connected piece of the
    # binary bird's-eye view shorter than `min_blob_length_m` along its own principal axis is
    # dropped unless it is at least `min_blob_elongation` times longer than wide (a fragment of
    # a worn or occluded line). 0 (the default) keeps every piece. 1.0 m and 3 were chosen on
    # tune_right_turn_shade_bumps' recorded drive and the tuning eval sets; on the tuning
    # scenarios the two-model loop then kept its lane in all three drives of that scenario
    # (2 of 3 departed before). Not the default: the rear camera's sliding_window loses a
    # clear-road frame with it, and on the scored bench the two-model loop departed in 4 of
    # 95 episodes with it (0 without; docs/experiments.md, session 20).
    min_blob_length_m: float = 0.0
    min_blob_elongation: float = 3.0
    # Botts' dots (rows of raised markers 0.8-1.3 m apart, no paint between them) reach the
    # binary bird's-eye view as specks in a column, too short for a Hough segment or a
    # window's histogram. Pieces up to `join_along_m` apart along the road (and within a
    # pixel across it) are joined before the boundaries are searched (a closing along the
    # road): a row of dots becomes a dash, a dashed or solid line stays as it was. 0 (the
    # default) joins nothing.
    join_along_m: float = 0.0
    # With `join_min_dots` = N >= 2 only dots are joined (detectors/image_stage.py
    # join_dot_rows): pieces shorter than half of `join_along_m` and narrower than 0.3 m, where
    # N or more of them make a row; every other piece stays as it was. 0 (the default): the
    # whole view is closed.
    join_min_dots: int = 0
    # Fog taken out of the frame row by row before either model binarises it
    # (detectors/defog.py): the fog's colour from the horizon, each row's transmission from
    # how far the road's level there has risen towards it. Off (the default) reads the frame
    # as it is. Measured on the tuning sets in docs/experiments.md (session 35); its rule for
    # the default was not met on the snow tuning scenario (inconclusive; session 36).
    defog: bool = False

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
        if not (math.isfinite(self.min_blob_length_m) and self.min_blob_length_m >= 0):
            raise InvalidValue("min_blob_length_m",
                               f"must be >= 0 and finite, got {self.min_blob_length_m}")
        if not (math.isfinite(self.min_blob_elongation) and self.min_blob_elongation > 0):
            raise InvalidValue("min_blob_elongation",
                               f"must be > 0 and finite, got {self.min_blob_elongation}")
        if not (math.isfinite(self.join_along_m) and self.join_along_m >= 0):
            raise InvalidValue("join_along_m", f"must be >= 0 and finite, got {self.join_along_m}")
        if not (self.join_min_dots == 0 or self.join_min_dots >= 2):
            raise InvalidValue("join_min_dots",
                               f"must be 0 (every piece) or >= 2, got {self.join_min_dots}")


@dataclass(frozen=True)
class LaneRules:
    """What counts as an ego-lane boundary, in metres."""

    # The car's lane-width belief, shared with the estimator (geometry/lane_width.py); not the
    # road's width and not tuned here.
    lane_width_m: float = LANE_WIDTH_PRIOR_M
    width_tolerance_m: float = 0.8  # |measured - lane_width| above this: keep only the better side
    # A boundary's |y| at the near edge, in lane widths, at least this (detectors/
    # lane_lines.py): a line nearer the car than about its half-width lies under its wheels,
    # which a car keeping its lane never has, so it is taken for a sun fleck, a bump's stripe
    # or a crack. 0 = off, the behaviour since session 15 (4bf15c1 chose the pair by lane
    # geometry and left this setting unread until 2026-12-02), under which a car passing over
    # a line is in the lane that holds its centre. Measured 2026-12-02 at 0.25 (0.93 m, inside
    # the body's 0.95 m): the two-model loop on the tuning scenarios inconclusive (failed
    # drives 8 -> 7 of 110), the tuning eval sets worse (their lane changes put a real line
    # under the car): off (docs/experiments.md, session 33).
    min_half_width: float = 0.0
    max_half_width: float = 1.1  # ... and at most this many lane widths
    min_span_m: float = 2.0  # a boundary must cover this much x
    quadratic_span_m: float = 8.0  # fit a parabola only over at least this x span
    max_curvature_1pm: float = 0.05  # |2 c2| above this: a bad fit (R < 20 m)
    max_heading_deg: float = 20.0  # a boundary's direction at the look-ahead, from the car's
    max_extrapolation: float = 1.5  # a short lone boundary reaches this many spans at most
    inlier_m: float = 0.25  # points further from a boundary's fit are refitted without; 0 = off
    # Lane lines run parallel: a line found whose direction (at the near edge of the view)
    # differs from the best-supported lines' by more than this is no lane line (a sliding
    # track that jumped between lines, a vehicle's edge); detectors/lane_lines.py.
    max_divergence_deg: float = 6.0

    def __post_init__(self) -> None:
        if not self.lane_width_m > 0:
            raise InvalidValue("lane_width_m", f"must be > 0, got {self.lane_width_m}")
        if not 0 <= self.min_half_width < self.max_half_width:
            raise InvalidValue("min_half_width",
                               f"must be >= 0 and below max_half_width ({self.max_half_width}), "
                               f"got {self.min_half_width}")
        if not 0 <= self.max_divergence_deg < 90:
            raise InvalidValue("max_divergence_deg",
                               f"must be in [0, 90) degrees, got {self.max_divergence_deg}")


@dataclass(frozen=True)
class RidgeConfig:
    """Paint as a ridge in the bird's-eye view (detectors/ridge.py): a stripe brighter than
    the road bands on both sides of it, averaged along its length."""

    gap_m: float = 0.25  # centre of each road band, this far beside the stripe's centre
    band_m: float = 0.2  # width of each road band
    length_m: float = 1.5  # the along-line average (shorter than a 3 m dash)
    max_heading: float = 0.35  # steepest line (m across per m along, ~19 deg) integrated along
    leans: int = 7  # headings tried between -max_heading and +max_heading
    dark_floor: float = 10.0  # road level (grey) below which the ratio is taken against this
    min_ratio: float = 0.06  # the averaged step, a share of the road level, at least ...
    min_step: float = 3.0  # ... and at least this many grey levels (the noise floor)
    # The pixel's own step (over 3 rows), a share of the road level, at least: the line
    # average runs past a dash's end and leans to reach beside it; paint is where the
    # stripe itself is.
    own_ratio: float = 0.03
    # Ridges over more than this share of the view are texture or noise, not paint: at most
    # 2.8% on any frame of the tuning sets (snow), 4.6% on a frame of uniform noise.
    max_fill: float = 0.04

    def __post_init__(self) -> None:
        for key in ("gap_m", "band_m", "length_m", "dark_floor"):
            if not getattr(self, key) > 0:
                raise InvalidValue(key, f"must be > 0, got {getattr(self, key)}")
        if self.leans < 1 or self.max_heading < 0:
            raise InvalidValue("leans", "leans must be >= 1 and max_heading >= 0")


@dataclass(frozen=True)
class HoughConfig:
    """Model #1: brightness threshold relative to the road beside a ridge, bird's-eye view,
    probabilistic Hough."""

    # A pixel must exceed the road on both sides of it (a paint width away along the row) by
    # `adaptive_ratio` of it: relative to the local light, for paint in shade keeps its ratio
    # to the asphalt (1.5-1.8), not its level; faint sunlit paint is only ~1.2-1.35 of it. A
    # shoulder's edge is bright on one side only, so it is no ridge.
    # "ridge": paint found in the bird's-eye view as a ridge averaged along the line ([ridge]
    # settings, detectors/ridge.py); "image": the per-pixel ridge test below, in the image;
    # "paper": the paper's fixed thresholds (detectors/paper_thresholds.py; paper mode's).
    # "image" stays the default until the closed loop with "ridge" passes its tests: open
    # loop "ridge" scores better (docs/experiments.md#2026-11-29), but with both models on it
    # the default loop's fused-vs-LaneNet verdict on case 3 turned inconclusive, the bench
    # gate missed a 2 cm shift of LaneNet, and snow's two-model loop departs further.
    binarisation: str = "image"
    # The binarisation tried on a frame where `binarisation` finds no valid lane: "ridge"
    # (faint paint on a light road that the per-pixel test misses) or "image"; "": none.
    fallback: str = ""
    adaptive_ratio: float = 0.2  # #44 ridge re-tune (closed loop on the tuning scenarios)
    # ... and by at least this many grey levels: only the noise floor (sensor noise, dark
    # road); #44: was 35, above shaded paint (20-30 DN over the asphalt).
    adaptive_c: float = 10.0
    # ... and be at least this bright: a dark floor only; #44: was 120, above the realistic
    # paint (sunlit ~110, shaded ~58).
    min_grey: int = 20
    rho_px: float = 1.0  # Hough distance resolution, bird's-eye pixels
    theta_deg: float = 1.0  # Hough angle resolution
    votes: int = 12  # accumulator votes a line needs
    min_length_m: float = 1.0  # shortest Hough segment kept
    max_gap_m: float = 1.5  # gaps up to this along a line are bridged into one segment
    max_angle_deg: float = 35.0  # segments further from the driving direction are dropped
    seed_length_m: float = 10.0  # boundaries are seeded from segments starting this near
    cluster_m: float = 0.4  # seeds closer than this (at the near edge) are one boundary
    grow_tolerance_m: float = 0.35  # a segment joins a boundary within this of its fit
    sample_m: float = 0.5  # spacing of the points taken along each segment

    def __post_init__(self) -> None:
        if self.binarisation not in ("ridge", "image", "paper"):
            raise InvalidValue("binarisation", f"must be 'ridge', 'image' or 'paper', got "
                                               f"{self.binarisation!r}")
        if self.fallback not in ("", "ridge", "image") or self.fallback == self.binarisation:
            raise InvalidValue("fallback", f"must be '', 'ridge' or 'image' (and not the "
                                           f"binarisation itself), got {self.fallback!r}")
        if self.adaptive_ratio < 0 or self.adaptive_c < 0:
            raise InvalidValue("adaptive_ratio", "adaptive_ratio and adaptive_c must be >= 0")


@dataclass(frozen=True)
class SlidingWindowConfig:
    """Model #2: Sobel-x + HLS saturation/hue thresholds, histogram, sliding windows."""

    # "edges": the cues read in the bird's-eye view, averaged along lines (detectors/
    # edge_pairs.py, the edge_* settings and the yellow ones); "image": per pixel in the image;
    # "paper": the paper's fixed thresholds (detectors/paper_thresholds.py; paper mode's).
    # "image" stays the default for the reasons given at HoughConfig.binarisation (and the
    # dashcam test's 11.3 cm at one offset, against its 10 cm).
    binarisation: str = "image"
    # The binarisation tried on a frame where `binarisation` finds no valid lane: "edges" or
    # "image"; "": none.
    fallback: str = ""
    edge_half_width_m: float = 0.1  # the rising and falling edges lie this far either side
    edge_length_m: float = 1.5  # the along-line average
    edge_max_heading: float = 0.35  # steepest line averaged along (m across per m along)
    edge_leans: int = 7  # headings tried
    edge_dark_floor: float = 10.0  # lightness below which the ratio is taken against this
    edge_ratio: float = 0.04  # the weaker averaged edge, a share of the road's lightness ...
    edge_min_step: float = 2.0  # ... and at least this (grey levels per column)
    yellow_share: float = 0.6  # share of yellow pixels along a line that makes it paint
    sobel_kernel: int = 3  # Sobel aperture (the "image" binarisation): 1, 3, 5 or 7
    # Shade compensation: lightness is scaled so that the local background (a wide box blur)
    # reads `illumination_target`, by a gain of at most `illumination_max_gain` (1 = off)
    # and at least `illumination_min_gain`. Paint in a building's shadow keeps its contrast
    # ratio to the asphalt, not its level.
    illumination_block_px: int = 61  # box blur side that measures the background, working px
    illumination_target: float = 80.0  # lightness the background is scaled to
    illumination_max_gain: float = 4.0  # most brightening (building shade, dusk)
    # Most dimming; #44: below 1 it dims bright roads too, so the white threshold is a share
    # (105/80) of the local light in sun and shade alike.
    illumination_min_gain: float = 0.5
    sobel_min: float = 25.0  # |d lightness / dx| in grey levels per pixel (Sobel-scaled / 4)
    # Every cue must sit on a ridge this much brighter than its row neighbours a block away;
    # #44: was 10, fewer texture ridges on the normalised lightness.
    min_lightness_gain: float = 15.0
    local_block_px: int = 25  # the ridge's neighbourhood along a row, working px (odd)
    # Normalised HLS lightness at or above: paint-white; #44: was 180, unreachable for paint
    # 40-70 DN above the asphalt.
    white_lightness: int = 105
    white_saturation_max: int = 255  # and saturation at most this (255 = any)
    yellow_hue: tuple[int, int] = (12, 38)  # OpenCV hue (0..180) range of yellow paint
    yellow_saturation: int = 90  # yellow paint's HLS saturation, at least
    yellow_lightness: int = 80  # and its lightness, at least
    n_windows: int = 11  # windows stacked along the view's length per boundary
    margin_m: float = 0.45  # half width of a window
    min_pixels: int = 8  # a window re-centres when it holds this many pixels
    histogram_fraction: float = 0.5  # the near part of the view that the histogram sums
    min_peak_pixels: int = 15  # a histogram peak needs this many (smoothed) pixels
    search_margin_m: float = 0.4  # around the previous frame's fit
    min_fit_pixels: int = 40  # pixels a boundary's fit needs (else it is not found)

    def __post_init__(self) -> None:
        if self.binarisation not in ("edges", "image", "paper"):
            raise InvalidValue("binarisation", f"must be 'edges', 'image' or 'paper', got "
                                               f"{self.binarisation!r}")
        if self.fallback not in ("", "edges", "image") or self.fallback == self.binarisation:
            raise InvalidValue("fallback", f"must be '', 'edges' or 'image' (and not the "
                                           f"binarisation itself), got {self.fallback!r}")
        if self.edge_leans < 1 or min(self.edge_half_width_m, self.edge_length_m,
                                      self.edge_dark_floor) <= 0:
            raise InvalidValue("edge_leans", "edge_leans must be >= 1 and the edge widths, "
                                             "length and floor > 0")
        if not 0.0 < self.illumination_min_gain <= max(1.0, self.illumination_max_gain):
            raise InvalidValue("illumination_min_gain", "must be > 0 and <= the max gain")
        if self.sobel_kernel not in (1, 3, 5, 7):
            raise InvalidValue("sobel_kernel", "must be 1, 3, 5 or 7")
        if self.local_block_px < 3 or self.local_block_px % 2 == 0:
            raise InvalidValue("local_block_px", "must be odd and >= 3")


@dataclass(frozen=True)
class DashcamDefaults:
    """An unknown real camera (`lanekeep detect` without --camera): typical highway dashcam."""

    hfov_deg: float = 60.0  # horizontal field of view of the assumed pinhole
    height_m: float = 1.5  # its mounting height above the road
    horizon_fraction: float = 0.5  # horizon row / image height when it cannot be estimated
    min_horizon_fraction: float = 0.2  # an estimated horizon row / image height, at least ...
    max_horizon_fraction: float = 0.75  # ... and at most this


@dataclass(frozen=True)
class PaperThresholds:
    """The fixed levels of the paper's binarisations (paper mode's `binarisation = "paper"`,
    detectors/paper_thresholds.py; 8-bit levels, OpenCV HLS with hue 0..180)."""

    # White paint: HLS lightness (model #1) and grey (model #2) at least this. The paper gives
    # no value; the authors' code has 200, for AirSim's paint. In this world's light 200 passes
    # no paint (case 1's paint lightness p50 110, case 2's 141; on real TuSimple frames 5.7% of
    # the labelled lanes' pixels reach it). 105 is the level that best separates sunlit paint
    # from asphalt (Youden's J) on a tuning scenario in sun, tune_gentle_s_curve_r700_r500:
    # paint 100% above it, asphalt 0.01%: a fixed threshold set in good light, as the authors
    # set theirs (tools/paper_levels.py; docs/paper_mode.md, 2026-11-29).
    white_level: int = 105
    model1_saturation: int = 80  # model #1's yellow: HLS saturation at least ... (authors' code)
    model1_red: int = 120  # ... with the red channel at least
    model2_sobel_share: float = 30.0 / 255.0  # |Sobel-x| share of the image's largest (Gaskey)
    model2_saturation: int = 90  # model #2: HLS saturation above (Gaskey)
    model2_hue: tuple[int, int] = (10, 25)  # model #2's yellow: hue above the first, at most
    # the second (Gaskey)

    def __post_init__(self) -> None:
        if not 0 <= self.white_level <= 255:
            raise InvalidValue("white_level", f"must be in [0, 255], got {self.white_level}")
        if not 0.0 < self.model2_sobel_share <= 1.0:
            raise InvalidValue("model2_sobel_share", "must be in (0, 1]")


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
    ridge: RidgeConfig = RidgeConfig()
    hough: HoughConfig = HoughConfig()
    sliding_window: SlidingWindowConfig = SlidingWindowConfig()
    dashcam: DashcamDefaults = DashcamDefaults()
    paper: PaperThresholds = PaperThresholds()
    # Raw tables of registered detectors, by name (not part of the strict schema above).
    tables: dict[str, dict] = field(default_factory=dict, metadata={"toml": False})

    @classmethod
    def from_table(cls, data: dict, path: str = "", source: str = "") -> DetectorsConfig:
        """Read by config_io wherever a settings table nests this one (a scenario's
        `[detectors]`): the defaults with `data`'s overrides, as a detectors file is read."""
        return config_from_table(data, path=path, source=source)

    def window_for(self, camera_name: str) -> GroundWindow:
        """The ground window of a camera: by name, real cameras use the dashcam profile."""
        if camera_name in ("front", "rear"):
            return getattr(self.profiles, camera_name)
        return self.profiles.dashcam


def _as_table(config) -> dict:
    """A settings dataclass as the TOML table that would spell it out in full."""
    return {f.name: _as_table(v) if is_dataclass(v := getattr(config, f.name)) else v
            for f in fields(config) if f.metadata.get("toml", True)}


def config_table(config: DetectorsConfig) -> dict:
    """Every setting of `config` as the detectors table that spells it out in full (with the
    registered detectors' own tables): what a record of a run's settings holds."""
    return {**_as_table(config), **{name: dict(t) for name, t in config.tables.items()}}


def _merged(defaults: dict, overrides: dict) -> dict:
    """`defaults` with `overrides` laid over them, table by table: a key a file leaves out
    keeps the default of the table it sits in (`[profiles.rear]` keeps the rear window's
    near edge, not `GroundWindow`'s)."""
    out = dict(defaults)
    for key, value in overrides.items():
        base = out.get(key)
        out[key] = (_merged(base, value) if isinstance(base, dict) and isinstance(value, dict)
                    else value)
    return out


def config_from_table(data: dict, path: str = "", source: str = "") -> DetectorsConfig:
    """The defaults with a detectors table's overrides laid over them (a detectors file's
    contents, or a scenario's `[detectors]` table at dotted `path`). Strict: an unknown key
    raises `ConfigError` naming it."""
    data = dict(data)
    tables = {name: data.pop(name) for name in list(data) if name in _DETECTOR_TABLES}
    data = _merged(_as_table(DetectorsConfig()), data)
    return replace(from_dict(DetectorsConfig, data, path=path, source=source), tables=tables)


def load_config(path: str | Path | None = None) -> DetectorsConfig:
    """The defaults with a detectors TOML file's overrides; None reads the shipped
    detectors/detectors.toml. Strict: an unknown key raises `ConfigError` naming it."""
    if path is None:
        text = resources.files("lanekeep.detectors").joinpath("detectors.toml").read_text()
        source = "detectors.toml"
    else:
        text = Path(path).read_text()
        source = str(path)
    return config_from_table(tomllib.loads(text), source=source)
