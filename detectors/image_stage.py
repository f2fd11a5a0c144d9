"""The image stage both classical models share: crop, scale, rain streaks, noise, warp.

`binary_bird_eye(frame, ...)` takes a camera frame to the binary bird's-eye view a model looks
for boundaries in, with each model's own binarisation passed in; or says why the frame's
binary image is noise rather than paint.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

from lanekeep.detectors.birds_eye import BirdsEye
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


def _open_2x2(mask: np.ndarray) -> np.ndarray:
    """The mask's 2x2 opening: what survives of it is coherent strokes, not speckle."""
    return cv2.morphologyEx(mask, cv2.MORPH_OPEN, _KERNEL_2X2)


_KERNEL_2X2 = np.ones((2, 2), np.uint8)


def binary_bird_eye(frame: np.ndarray, camera: CameraModel, view: BirdsEye, preprocess,
                    binarise, vehicles: VehicleFilter | None = None
                    ) -> tuple[np.ndarray | None, str]:
    """A frame's binary bird's-eye view (0/255), or None and why its binary image is noise.

    The image stage both models share; `binarise` is each model's own thresholding of the ROI.
    `vehicles` (detectors/vehicle_mask.py) drops what other vehicles cover and runs wider
    than paint.
    """
    check_frame(frame, camera)
    roi = crop_and_scale(frame, view.crop_top, preprocess.scale)
    roi = open_along_rows(roi, destreak_pixels(preprocess, frame.shape[0]))
    mask = binarise(roi)
    if vehicles is not None:
        mask = vehicles.hide_vehicles(mask, roi)
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
