"""The confidence bands tools/measure_detector_noise.py prints: a band whose detections scatter
more gets a larger factor of R, and its share of wrong lines is counted."""

from __future__ import annotations

import numpy as np
import pytest

from lanekeep.tuning.detector_noise import Detections, Fit, confidence_bands, toml_bands


def _detections(seed: int = 0) -> Detections:
    """Confidences 0..1; the coefficient errors' spread falls as the confidence rises (4x in
    std from the lowest fifth to the highest), and a tenth of the lowest fifth is 1 m off."""
    rng = np.random.default_rng(seed)
    confidence = rng.uniform(0.0, 1.0, 4000)
    std = np.array([0.04, 0.01, 0.0005]) * (2.0 - 1.5 * confidence)[:, None]
    errors = rng.normal(size=(4000, 3)) * std
    wrong = (confidence < 0.2) & (rng.uniform(size=4000) < 0.1)
    errors[wrong, 0] += 1.0
    return Detections(list(errors), list(confidence))


def test_noisier_bands_get_larger_factors_and_their_wrong_lines_are_counted():
    found = _detections()
    bands = confidence_bands(found, Fit.of(np.array(found.errors)))
    assert len(bands) == 5 and sum(b.count for b in bands) == 4000
    assert [b.low for b in bands[1:]] == pytest.approx([0.2, 0.4, 0.6, 0.8], abs=0.02)
    scales = [b.scale for b in bands]
    assert all(a > b for a, b in zip(scales, scales[1:], strict=False))  # falls band by band
    assert scales[0] > 1.0 > scales[-1]
    assert bands[0].gross_share == pytest.approx(0.1, abs=0.03)
    assert all(b.gross_share < 0.02 for b in bands[1:])  # only the Gaussian tails
    text = toml_bands({"hough": bands})
    assert text.startswith("[confidence_noise_by_detector]") and "hough = { edges = [" in text


def test_too_few_detections_for_a_band_are_named():
    found = _detections()
    few = Detections(found.errors[:40], found.confidences[:40])
    with pytest.raises(ValueError, match="holds only"):
        confidence_bands(few, Fit.of(np.array(found.errors)))
