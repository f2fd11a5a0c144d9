"""The image stage both classical models share: crop, scale, rain streaks, noise, warp.

`binary_bird_eye(frame, ...)` takes a camera frame to the binary bird's-eye view a model looks
for boundaries in, with each model's own binarisation passed in; or says why the frame's
binary image is noise rather than paint. The part before the binarisation (`RegionOfInterest`)
is the same for both models on the same frame, so they share it (`RoiMemo`).
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

from lanekeep.detectors.birds_eye import BirdsEye
from lanekeep.detectors.defog import estimate_fog
from lanekeep.detectors.vehicle_mask import VehicleFilter
from lanekeep.geometry.camera_model import CameraModel


def check_frame(frame: np.ndarray, camera: CameraModel) -> None:
    """Raise ValueError unless `frame` is an RGB uint8 image of the camera's size."""
    expected = (camera.height, camera.width, 3)
    if not isinstance(frame, np.ndarray) or frame.shape != expected:
        shape = getattr(frame, "shape", type(frame).__name__)
        raise ValueError(f"expected an RGB frame of shape {expected} for camera "
                         f"{camera.name!r}, got {shape}")
    if frame.dtype != np.uint8:
        raise ValueError(f"expected a uint8 frame, got {frame.dtype}")


def crop_and_scale(frame: np.ndarray, top: int, scale: float) -> np.ndarray:
    """The region of interest (rows from `top` down) at the working resolution."""
    roi = frame[top:]
    if scale == 1.0:
        return roi
    h, w = roi.shape[:2]
    size = (max(1, int(round(w * scale))), max(1, int(round(h * scale))))
    return cv2.resize(roi, size, interpolation=cv2.INTER_AREA)


def remove_streaks(mask: np.ndarray, min_rows: int, max_tilt_deg: float,
                   max_width: int = 5) -> np.ndarray:
    """The binary ROI without rain streaks: thin runs within `max_tilt_deg` of vertical.

    Falling rain renders as near-vertical bright lines. Lane paint is never that steep in the
    image: a boundary leans from vertical by atan(|y| / camera height), over 25 deg even 0.7 m
    from the car, so a line-shaped opening tilted a few degrees either way finds the streaks
    and nothing else. Streaks are also thin (2-4 px at 720 rows after the binarisation's
    dilation): anything wider than `max_width` is kept, for near paint is thick enough to hold
    tall runs of its own. `min_rows` and `max_width` are working-resolution pixels; see
    `streak_pixels` for their scaling with the camera's size.
    """
    if min_rows <= 0:
        return mask
    streaks = np.zeros_like(mask)
    for kernel in _streak_kernels(min_rows, max_tilt_deg):
        streaks |= cv2.morphologyEx(mask, cv2.MORPH_OPEN, kernel)
    thick = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((1, max_width + 1), np.uint8))
    streaks = cv2.bitwise_and(streaks, cv2.bitwise_not(thick))
    streaks = cv2.dilate(streaks, np.ones((1, 3), np.uint8))
    streaks = cv2.bitwise_and(streaks, cv2.bitwise_not(thick))
    return cv2.bitwise_and(mask, cv2.bitwise_not(streaks))


@functools.lru_cache(maxsize=8)
def _streak_kernels(min_rows: int, max_tilt_deg: float) -> tuple[np.ndarray, ...]:
    """Line kernels `min_rows` tall at five tilts within +-`max_tilt_deg` (built once)."""
    kernels = []
    for tilt in np.linspace(-max_tilt_deg, max_tilt_deg, 5):
        dx = int(round(np.tan(np.radians(tilt)) * (min_rows - 1)))
        kernel = np.zeros((min_rows, abs(dx) + 1), np.uint8)
        cols = np.linspace(0, dx, min_rows).round().astype(int) - min(dx, 0)
        kernel[np.arange(min_rows), cols] = 1
        kernels.append(kernel)
    return tuple(kernels)

STREAK_REFERENCE_ROWS = 720  # streak sizes are given in pixels of a camera this tall

STREAK_MAX_WIDTH_PX = 10  # at the reference size: wider runs are paint, not rain


def streak_pixels(preprocess, frame_rows: int) -> tuple[int, int]:
    """Minimum streak length and maximum streak width in working pixels for this frame size.

    Both are given in full-resolution pixels of a 720-row camera; rain (and paint) shrink with
    the image and the working scale, so both scale with `frame_rows / 720 * scale`. Below 3 rows
    a "streak" is any speck, so the filter switches off; the width never falls below 1 px.
    """
    ratio = _working_ratio(preprocess, frame_rows)
    min_rows = int(round(preprocess.streak_min_rows * ratio))
    max_width = max(1, int(round(STREAK_MAX_WIDTH_PX * ratio)))
    return (min_rows if min_rows >= 3 else 0), max_width


def destreak_pixels(preprocess, frame_rows: int) -> int:
    """Width in working pixels below which a bright feature along a row is taken for rain."""
    return int(round(preprocess.destreak_width_px * _working_ratio(preprocess, frame_rows)))


def _working_ratio(preprocess, frame_rows: int) -> float:
    """Working pixels per full-resolution pixel of a 720-row camera, for this frame."""
    return frame_rows / STREAK_REFERENCE_ROWS * preprocess.scale


def open_along_rows(image: np.ndarray, width_px: int) -> np.ndarray:
    """The image without bright features narrower than `width_px` along a row (grey opening).

    Rain streaks are near vertical, so a row crosses them in 1-2 working pixels. Lane paint
    leans at least ~45 deg from vertical in a forward camera (its image line runs to the
    vanishing point from a boundary 1.5-2 m beside a camera 1.5 m high), so a row crosses even
    the far, thin paint over more pixels than its width: it survives an opening that the
    streaks do not. Width < 2 leaves the image as it is.
    """
    if width_px < 2:
        return image
    return cv2.morphologyEx(image, cv2.MORPH_OPEN, np.ones((1, width_px), np.uint8))


def reject_noise(mask: np.ndarray, max_fill: float, min_coherence: float) -> str:
    """Why a binary ROI looks like noise rather than paint ('' when it does not)."""
    filled = cv2.countNonZero(mask)
    fill = filled / mask.size
    if fill > max_fill:
        return f"binary image too full ({fill:.0%}): noise"
    if filled and min_coherence > 0.0:  # a share is never below 0: no opening to test
        coherence = cv2.countNonZero(_open_2x2(mask)) / filled
        if coherence < min_coherence:
            return f"binary image is speckle ({coherence:.0%} survives an opening): noise"
    return ""


def drop_speckle(mask: np.ndarray, min_coherence: float) -> tuple[np.ndarray, str]:
    """A binary ROI without its speckle, or why nothing coherent is left.

    Grainy asphalt under a shade gain, or sensor noise, binarises into isolated pixels. When
    fewer than `min_coherence` of the pixels survive a 2x2 opening the speckle dominates: the
    opened mask (the coherent strokes: paint, edges) goes on instead of the whole frame being
    rejected, as a shaded road with clear paint was; a frame with nothing coherent is noise.
    """
    filled = cv2.countNonZero(mask)
    if filled == 0 or min_coherence <= 0.0:
        return mask, ""
    opened = _open_2x2(mask)  # one opening for the test and the result
    kept = cv2.countNonZero(opened)
    if kept / filled >= min_coherence:
        return mask, ""
    if kept == 0:
        return mask, "binary image is all speckle: noise"
    return opened, ""


def drop_blobs(bev: np.ndarray, m_per_row: float, m_per_col: float, min_length_m: float,
               min_elongation: float) -> np.ndarray:
    """The binary bird's-eye view without its blobs: each 8-connected piece shorter than
    `min_length_m` along its own principal axis and less than `min_elongation` times as long
    as it is wide (sun flecks; detectors/config.py Preprocess); lengths as `piece_axes`."""
    if min_length_m <= 0.0:
        return bev
    count, labels = cv2.connectedComponents(bev, connectivity=8)
    if count <= 1:
        return bev
    major, minor = piece_axes(bev, labels, count, m_per_row, m_per_col)
    keep = (major >= min_length_m) | (major >= min_elongation * minor)
    keep[0] = False  # the background
    if keep[1:].all():
        return bev
    return np.where(keep[labels], np.uint8(255), np.uint8(0))


def piece_axes(bev: np.ndarray, labels: np.ndarray, count: int, m_per_row: float,
               m_per_col: float) -> tuple[np.ndarray, np.ndarray]:
    """Each labelled piece's length and width (m): those of the rectangle with the piece's
    second moments (a stripe L x W has variances L^2 / 12 and W^2 / 12 along its axes), so
    that a line keeps its length whichever way it runs across the view (a sharp turn's lines
    cross the columns). Index 0 is the background's (meaningless)."""
    rows, cols = np.nonzero(bev)
    label = labels[rows, cols]
    y = cols * m_per_col  # across the road
    x = rows * m_per_row  # along it
    n = np.bincount(label, minlength=count).astype(np.float64)
    n[n == 0] = 1.0  # the background has no pixels here
    mx, my = np.bincount(label, x, count) / n, np.bincount(label, y, count) / n
    # A pixel is a cell, not a point: its own extent adds 1/12 of its size squared.
    sxx = np.bincount(label, x * x, count) / n - mx * mx + m_per_row**2 / 12.0
    syy = np.bincount(label, y * y, count) / n - my * my + m_per_col**2 / 12.0
    sxy = np.bincount(label, x * y, count) / n - mx * my
    half_trace, det = 0.5 * (sxx + syy), sxx * syy - sxy * sxy
    spread = np.sqrt(np.maximum(half_trace * half_trace - det, 0.0))
    major = np.sqrt(12.0 * (half_trace + spread))
    minor = np.sqrt(12.0 * np.maximum(half_trace - spread, 0.0))
    return major, minor


def join_along_road(bev: np.ndarray, m_per_row: float, length_m: float) -> np.ndarray:
    """The binary bird's-eye view with pieces up to `length_m` apart along the road joined:
    a closing by a kernel `length_m` long and 3 pixels wide, so that specks in one column, or
    drifting a pixel across it from one to the next (a line that leans or bends in the
    view), become one stroke. Anything already continuous is unchanged."""
    rows = int(round(length_m / m_per_row))
    if rows < 2:
        return bev
    kernel = np.ones((rows + 1, 3), np.uint8)
    # OpenCV's default border: nothing outside the view is added, and nothing at its edge is
    # eroded away (a constant 0 would cut every line short by half the kernel at the edges).
    return cv2.morphologyEx(bev, cv2.MORPH_CLOSE, kernel)


def join_dot_rows(bev: np.ndarray, m_per_row: float, m_per_col: float, length_m: float,
                  min_dots: int) -> np.ndarray:
    """The binary bird's-eye view with its rows of dots joined, and nothing else changed.

    A dot is an 8-connected piece shorter along the road than half of `length_m` and narrower
    than DOT_MAX_WIDTH_M. The dots alone are closed along the road as `join_along_road` closes
    the whole view; a joined stroke is added only where it holds `min_dots` dots or more and is
    itself no wider than DOT_MAX_WIDTH_M (`piece_axes`). A row of raised markers becomes a
    stroke; a lone speck (a crack, a fleck of shade) is not stretched, a field of specks
    (gravel, a shoulder's texture) is not made a band, and dashes, solid lines and whatever
    lies near them stay as they were."""
    rows = int(round(length_m / m_per_row))
    if rows < 2:
        return bev
    count, labels, stats, _ = cv2.connectedComponentsWithStats(bev, connectivity=8)
    if count <= min_dots:  # the background and fewer than min_dots pieces: no row
        return bev
    dot = ((stats[:, cv2.CC_STAT_HEIGHT] * m_per_row < 0.5 * length_m)
           & (stats[:, cv2.CC_STAT_WIDTH] * m_per_col < DOT_MAX_WIDTH_M))
    dot[0] = False  # the background
    if dot.sum() < min_dots:
        return bev
    dots = np.where(dot[labels], np.uint8(255), np.uint8(0))
    joined = join_along_road(dots, m_per_row, length_m)
    strokes, stroke_of = cv2.connectedComponents(joined, connectivity=8)
    # Each dot's stroke, read at one of its own pixels (a centroid may fall outside a piece).
    rows_px, cols_px = np.nonzero(dots)
    first = np.full(count, -1, np.int64)
    first[labels[rows_px, cols_px][::-1]] = np.arange(len(rows_px))[::-1]
    members = stroke_of[rows_px[first[dot]], cols_px[first[dot]]]
    rows_of_dots = np.bincount(members, minlength=strokes) >= min_dots
    rows_of_dots &= piece_axes(joined, stroke_of, strokes, m_per_row, m_per_col)[1] \
        <= DOT_MAX_WIDTH_M
    rows_of_dots[0] = False
    if not rows_of_dots.any():
        return bev
    return np.maximum(bev, np.where(rows_of_dots[stroke_of], np.uint8(255), np.uint8(0)))


# A raised marker is about 10 cm across; in the bird's-eye view a far one spreads over a few
# columns. Wider pieces (a blotch, a vehicle's edge) are not dots.
DOT_MAX_WIDTH_M = 0.3


def _open_2x2(mask: np.ndarray) -> np.ndarray:
    """The mask's 2x2 opening: what survives of it is coherent strokes, not speckle."""
    return cv2.morphologyEx(mask, cv2.MORPH_OPEN, _KERNEL_2X2)


_KERNEL_2X2 = np.ones((2, 2), np.uint8)


@dataclass(frozen=True)
class RegionOfInterest:
    """A frame's region of interest as both models binarise it: the rows below the ground
    window's far edge at the working scale with rain opened away (`rgb`), its grey levels,
    and where no paint can be (`covered`: what other vehicles cover or stands beside
    vehicle-dark; None when that cue is off). Shared between models: read-only."""

    rgb: np.ndarray
    grey: np.ndarray
    covered: np.ndarray | None

    def hide(self, mask: np.ndarray) -> np.ndarray:
        """A binary ROI without the pixels where no paint can be."""
        if self.covered is None:
            return mask
        out = mask.copy()
        out[self.covered] = 0
        return out


def region_of_interest(frame: np.ndarray, view: BirdsEye, preprocess,
                       vehicles: VehicleFilter | None = None,
                       camera: CameraModel | None = None) -> RegionOfInterest:
    """Crop, scale and destreak a frame, and find what vehicles cover in it (the part of the
    image stage that does not depend on the model); with `preprocess.defog` (and the
    frame's `camera`) the fog is taken out first (detectors/defog.py)."""
    rgb = crop_and_scale(frame, view.crop_top, preprocess.scale)
    if preprocess.defog and camera is not None:
        fog = estimate_fog(frame, camera)
        if fog is not None:
            rgb = fog.clear(rgb, view.crop_top, preprocess.scale)
    rgb = open_along_rows(rgb, destreak_pixels(preprocess, frame.shape[0]))
    grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    covered = None if vehicles is None else vehicles.covered(grey)
    for array in (rgb, grey, covered):
        if array is not None:
            array.flags.writeable = False  # this array object only, never the frame itself
    return RegionOfInterest(rgb, grey, covered)


class RoiMemo:
    """The region of interest of the latest frames, computed once for the models that read
    the same frame with the same image stage (hough and sliding_window on the front camera,
    each step).

    A region is reused only for the same frame object (a frame is kept alive while it is
    remembered, so its identity cannot pass to another), with the same shape and image stage
    settings (crop row, `Preprocess`, the vehicle cue's per-row geometry), and only while the
    rows it reads still hold the pixels it was made from (a copy is compared, so a frame
    changed in place is computed afresh). Thread-safe: the models may run on two threads at
    once (lanekeep/driver/detection.py); one that asks while another computes the same region
    waits for it rather than computing it again. `slots` bounds the frames kept.
    """

    def __init__(self, slots: int = 4) -> None:
        self._slots = slots
        self._lock = threading.Lock()
        self._entries: list[_MemoEntry] = []  # most recent first

    def get(self, frame: np.ndarray, view: BirdsEye, preprocess,
            vehicles: VehicleFilter | None = None,
            camera: CameraModel | None = None) -> RegionOfInterest:
        """`region_of_interest(frame, view, preprocess, vehicles, camera)`, computed once per
        frame."""
        key = (frame.shape, view.crop_top, preprocess,
               None if vehicles is None else (vehicles.preprocess, vehicles.px_per_m.tobytes()),
               _camera_key(camera) if preprocess.defog else None)
        with self._lock:
            entry = next((e for e in self._entries if e.frame is frame and e.key == key), None)
            if entry is None:
                entry = _MemoEntry(frame, key)
                self._entries.insert(0, entry)
                del self._entries[self._slots:]
        with entry.lock:
            source = frame[view.crop_top:]  # the only rows a region reads
            if entry.roi is None or not _same_pixels(entry.pixels, source):
                pixels = source.copy()
                roi = region_of_interest(frame, view, preprocess, vehicles, camera)
                entry.pixels, entry.roi = pixels, roi  # together: a failure leaves neither
            return entry.roi


class _MemoEntry:
    """One remembered frame: its key, a copy of the rows its region read, the region."""

    def __init__(self, frame: np.ndarray, key: tuple) -> None:
        self.frame, self.key = frame, key
        self.lock = threading.Lock()
        self.pixels: np.ndarray | None = None
        self.roi: RegionOfInterest | None = None


def _camera_key(camera: CameraModel | None) -> tuple | None:
    """What of a camera the region of interest depends on (its fog's rows and distances)."""
    if camera is None:
        return None
    return (camera.width, camera.height, camera.K.tobytes(), camera.position_m.tobytes(),
            camera.rotation.tobytes())


def _same_pixels(a: np.ndarray, b: np.ndarray) -> bool:
    """Exactly equal arrays (uint8 frames: a max |difference| of 0, one SIMD pass)."""
    return a.shape == b.shape and cv2.norm(a, b, cv2.NORM_INF) == 0.0


SHARED_ROIS = RoiMemo()  # the classical models' memo (ClassicalDetector.detect)


def warped_roi(frame: np.ndarray, camera: CameraModel, view: BirdsEye, preprocess,
               vehicles: VehicleFilter | None = None, memo: RoiMemo | None = None
               ) -> tuple[RegionOfInterest, np.ndarray]:
    """A frame's region of interest (as `binary_bird_eye` makes it: crop, scale, rain opened
    away, what vehicles cover) and the bird's-eye pixels where the road is seen: inside the
    image and not covered by a vehicle. For the models that find paint in the bird's-eye
    view itself, where a line runs along the rows and can be averaged along its length."""
    check_frame(frame, camera)
    roi = (region_of_interest(frame, view, preprocess, vehicles, camera) if memo is None
           else memo.get(frame, view, preprocess, vehicles, camera))
    seen = view.warp(np.full(roi.grey.shape, 255, np.uint8)) == 255
    if roi.covered is not None:
        seen &= view.warp(roi.covered.view(np.uint8) * np.uint8(255)) == 0
    blind = int(round(view.window.blind_m / view.window.m_per_row))
    if blind > 0:
        seen[-blind:] = False  # the rows nearest the car: the hood's edge (GroundWindow)
    return roi, seen


def grain_noise(roi: RegionOfInterest, preprocess) -> str:
    """Why the region of interest is sensor noise rather than a road ('' when it is not):
    its grain above `preprocess.max_grain` (detectors/ridge.py's `grain`)."""
    from lanekeep.detectors.ridge import grain

    speckle = grain(roi.grey)
    if speckle > preprocess.max_grain:
        return f"image is speckle (grain {speckle:.2f} > {preprocess.max_grain:g}): noise"
    return ""


def binary_bird_eye(frame: np.ndarray, camera: CameraModel, view: BirdsEye, preprocess,
                    binarise: Callable[[RegionOfInterest], np.ndarray],
                    vehicles: VehicleFilter | None = None, memo: RoiMemo | None = None
                    ) -> tuple[np.ndarray | None, str]:
    """A frame's binary bird's-eye view (0/255), or None and why its binary image is noise.

    The image stage both models share; `binarise` is each model's own thresholding of the
    region of interest. `vehicles` (detectors/vehicle_mask.py) drops what other vehicles cover
    and runs wider than paint. `memo` (None: compute here) shares the region of interest with
    the other models that read the same frame.
    """
    check_frame(frame, camera)
    roi = (region_of_interest(frame, view, preprocess, vehicles, camera) if memo is None
           else memo.get(frame, view, preprocess, vehicles, camera))
    mask = roi.hide(binarise(roi))
    # Fill first (a flooded mask is noise whatever it holds); the speckle test after the rain
    # streaks are gone, for a 1-px streak fails the opening just as sensor noise does.
    noise = reject_noise(mask, preprocess.max_fill, 0.0)
    if noise:
        return None, noise
    min_rows, max_width = streak_pixels(preprocess, frame.shape[0])
    mask = remove_streaks(mask, min_rows, preprocess.streak_max_tilt_deg, max_width)
    mask, noise = drop_speckle(mask, preprocess.min_coherence)
    if noise:
        return None, noise
    _, bev = cv2.threshold(view.warp(mask), 127, 255, cv2.THRESH_BINARY)  # 0/255: >= 128
    return (bev if vehicles is None else vehicles.narrow(bev)), ""
