"""Which painted pixels a camera can actually see: the segmentation's paint, thinned by fog and
darkness, so that the recorded marking masks (the ground truth people and learned detectors
compare with) do not label paint that no camera could show.

A paint pixel counts as visible when both hold:

  1. Fog (Koschmieder): over its range d the paint's luminance step against the road around it,
     dL = L_paint - L_road, is attenuated to dL t, t = exp(-3 d / V), while the road behind it
     turns into L_road t + A (1 - t) (A the airlight). The paint is visible while the apparent
     contrast |dL| t / (L_road t + A (1 - t)) >= CONTRAST_THRESHOLD = 0.05, the threshold that
     defines the meteorological visibility V itself (CIE). Clear air: t = 1.
  2. Light: the step, as the camera delivers it (times the exposure gain), is at least
     MIN_STEP_DN = 6 digital numbers, about three times the camera's noise in the dark (so
     paint beyond the headlights' reach at night, a 1-2 DN step in the render, is not visible).

L_paint and L_road are read from the bare render (no fog, no effects, grey = channel mean) of
the same pose; L_road is the mean of the non-paint pixels in a window ROAD_WINDOW_FRACTION of
the image width around each pixel.
"""

from __future__ import annotations

import cv2
import numpy as np

CONTRAST_THRESHOLD = 0.05  # CIE threshold contrast of the meteorological visibility
MIN_STEP_DN = 6.0  # the smallest luminance step a camera shows above its noise in the dark
ROAD_WINDOW_FRACTION = 1.0 / 40.0  # the road around a paint pixel: a window this wide


def visible_paint(paint: np.ndarray, bare_rgb: np.ndarray, range_m: np.ndarray | None,
                  extinction_per_m: float, airlight_dn: float, gain: float = 1.0
                  ) -> np.ndarray:
    """Boolean (H, W): the pixels of `paint` (bool, from the segmentation) that are visible.

    `bare_rgb`: the render without fog or effects; `range_m`: every pixel's distance (None
    when there is no fog); `extinction_per_m`: 3 / V (0 = clear air); `airlight_dn`: the fog's
    grey level; `gain`: the camera's exposure gain.
    """
    grey = bare_rgb.astype(np.float32).mean(axis=2)
    road = (~paint).astype(np.float32)
    k = max(3, int(round(paint.shape[1] * ROAD_WINDOW_FRACTION)) | 1)
    road_sum = cv2.boxFilter(grey * road, -1, (k, k), normalize=False)
    road_count = cv2.boxFilter(road, -1, (k, k), normalize=False)
    road_level = road_sum / np.maximum(road_count, 1.0)
    step = grey - road_level
    if range_m is None or extinction_per_m <= 0.0:
        transmit = np.ones_like(grey)
    else:
        transmit = np.exp(-extinction_per_m * range_m).astype(np.float32)
    background = road_level * transmit + airlight_dn * (1.0 - transmit)
    apparent = np.abs(step) * transmit
    contrast_ok = apparent >= CONTRAST_THRESHOLD * np.maximum(background, 1.0)
    light_ok = apparent * gain >= MIN_STEP_DN
    return paint & contrast_ok & light_ok
