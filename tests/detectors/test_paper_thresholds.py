"""The paper's fixed-threshold binarisations (detectors/paper_thresholds.py): absolute levels,
so sunlit paint passes and the same paint in shade does not, whatever the road beside it."""

from __future__ import annotations

import cv2
import numpy as np

from lanekeep.detectors.config import PaperThresholds
from lanekeep.detectors.paper_thresholds import model1_paint, model2_paint

AUTHORS = PaperThresholds(white_level=200)  # the authors' code's level, for AirSim's paint


def _road(level: int, stripes: dict[int, tuple[int, int, int]]) -> np.ndarray:
    """A 60x200 RGB road of grey `level` with 6 px wide vertical stripes at given columns."""
    rgb = np.full((60, 200, 3), level, np.uint8)
    for col, colour in stripes.items():
        rgb[:, col:col + 6] = colour
    return rgb


def test_model1_takes_sunlit_white_and_yellow_paint_and_loses_shaded_paint():
    """This world's level (105): sunlit paint (L ~118 on asphalt ~82) passes, the same paint
    at 0.4x the light (~47 on ~33) does not, nor the asphalt; the authors' 200 passes neither."""
    sunlit, shaded = (118, 118, 118), (47, 47, 47)
    yellow = (220, 180, 40)
    frame = _road(82, {30: sunlit, 100: shaded, 160: yellow})
    frame[:, 90:120] = np.where(frame[:, 90:120] == 82, 33, frame[:, 90:120])  # shade
    mask = model1_paint(frame)
    assert mask[:, 30:36].all() and mask[:, 160:166].all()
    assert not mask[:, 100:106].any()
    assert not mask[:, :25].any() and not mask[:, 90:100].any()
    authors = model1_paint(frame, AUTHORS)
    assert not authors[:, 30:36].any() and authors[:, 160:166].all()  # only the yellow


def test_model2_takes_the_frames_strongest_edges_and_saturated_colour():
    """Sobel-x is a share of the frame's largest: a faint stripe's edges pass on a frame with
    nothing stronger; a 4 DN step beside a white stripe does not; yellow always passes."""
    alone = model2_paint(_road(80, {100: (100, 100, 100)}))
    assert alone[:, 98:102].any() and alone[:, 104:108].any()  # its two edges
    beside_white = model2_paint(_road(80, {100: (84, 84, 84), 30: (240, 240, 240)}))
    assert beside_white[:, 30:36].all()
    assert not beside_white[:, 96:110].any()
    hls_yellow = cv2.cvtColor(np.uint8([[[220, 180, 40]]]), cv2.COLOR_RGB2HLS)[0, 0]
    assert 10 < hls_yellow[0] <= 25
    assert model2_paint(_road(80, {60: (220, 180, 40)}))[:, 61:65].all()


def test_a_flat_frame_is_no_paint():
    flat = np.full((40, 80, 3), 90, np.uint8)
    assert not model1_paint(flat).any() and not model2_paint(flat).any()
