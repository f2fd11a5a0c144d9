"""Procedural, seeded textures: asphalt with grain, gravel shoulder, grass.

Texture realism matters to the detectors: a flat grey road makes every threshold trivially
right, while real asphalt has grain, darker tar patches and lighter wear that create false
edges. Each texture tiles (its noise is blurred with wrap-around borders).
"""

from __future__ import annotations

import numpy as np


def _periodic_blur(image: np.ndarray, sigma_px: float) -> np.ndarray:
    """Gaussian blur with wrap-around borders (in the Fourier domain, so the result tiles)."""
    fy = np.fft.fftfreq(image.shape[0])[:, None]
    fx = np.fft.rfftfreq(image.shape[1])[None, :]
    gain = np.exp(-2.0 * (np.pi * sigma_px) ** 2 * (fx**2 + fy**2))
    return np.fft.irfft2(np.fft.rfft2(image) * gain, s=image.shape).astype(np.float32)


def _tiled_noise(rng: np.random.Generator, size: int, sigma_px: float) -> np.ndarray:
    """Zero-mean, unit-std noise blurred at a scale, seamless when tiled."""
    noise = rng.standard_normal((size, size)).astype(np.float32)
    if sigma_px > 0:
        noise = _periodic_blur(noise, sigma_px)
    noise -= noise.mean()
    return noise / max(float(noise.std()), 1e-6)


def _to_rgb8(grey: np.ndarray, tint: tuple[float, float, float]) -> np.ndarray:
    rgb = np.clip(grey[..., None] * np.asarray(tint, dtype=np.float32), 0.0, 1.0)
    return (rgb * 255.0 + 0.5).astype(np.uint8)


def asphalt(rng: np.random.Generator, size: int = 512, base: float = 0.33) -> np.ndarray:
    """Asphalt RGB (size, size, 3) uint8: fine aggregate grain, blotches, a few tar seams."""
    grain = 0.06 * _tiled_noise(rng, size, 0.6)
    speckle = (rng.random((size, size)) > 0.985).astype(np.float32) * 0.12
    blotch = 0.035 * _tiled_noise(rng, size, 24.0)
    grey = base + grain + speckle + blotch
    # Tar seams: thin dark meandering lines along the direction of travel.
    seams = np.zeros((size, size), np.float32)
    for _ in range(2):
        x = rng.uniform(0, size)
        wobble = np.cumsum(rng.normal(0, 0.6, size))
        cols = (x + wobble - np.linspace(0, wobble[-1], size)).astype(int) % size
        seams[np.arange(size), cols] = 1.0
    seams = _periodic_blur(seams, 1.2)
    grey -= 0.35 * seams / max(float(seams.max()), 1e-6) * 0.25
    return _to_rgb8(grey, (1.0, 1.0, 1.02))


def gravel(rng: np.random.Generator, size: int = 256) -> np.ndarray:
    """Lighter, coarser shoulder surface."""
    grey = 0.45 + 0.09 * _tiled_noise(rng, size, 1.0) + 0.04 * _tiled_noise(rng, size, 12.0)
    return _to_rgb8(grey, (1.0, 0.97, 0.9))


def grass(rng: np.random.Generator, size: int = 256) -> np.ndarray:
    """Green verge with blades and patches."""
    grey = 0.5 + 0.15 * _tiled_noise(rng, size, 0.8) + 0.12 * _tiled_noise(rng, size, 16.0)
    return _to_rgb8(grey, (0.42, 0.62, 0.26))


def paint(rng: np.random.Generator, size: int = 64) -> np.ndarray:
    """Road paint: nearly uniform, slight grain."""
    grey = 0.93 + 0.03 * _tiled_noise(rng, size, 0.7)
    return _to_rgb8(grey, (1.0, 1.0, 1.0))
