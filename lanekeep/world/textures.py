"""Procedural, seeded textures: gravel shoulder, grass, paint (the pavement is in pavement.py).

Texture realism matters to the detectors: a flat surface makes every threshold trivially right,
while real ground has grain and blotches that create false edges. Each texture tiles (its noise
is blurred with wrap-around borders).
"""

from __future__ import annotations

import numpy as np

# Verge albedos (linear 0..1, as the texture stores them): dry grass, olive grass, green.
GRASS_DRY = (0.52, 0.46, 0.32)
GRASS_OLIVE = (0.32, 0.33, 0.19)
GRASS_GREEN = (0.2, 0.29, 0.12)


def periodic_blur(image: np.ndarray, sigma_px: float) -> np.ndarray:
    """Gaussian blur with wrap-around borders (in the Fourier domain, so the result tiles)."""
    fy = np.fft.fftfreq(image.shape[0])[:, None]
    fx = np.fft.rfftfreq(image.shape[1])[None, :]
    gain = np.exp(-2.0 * (np.pi * sigma_px) ** 2 * (fx**2 + fy**2))
    return np.fft.irfft2(np.fft.rfft2(image) * gain, s=image.shape).astype(np.float32)


def tiled_noise(rng: np.random.Generator, size: int | tuple[int, int],
                sigma_px: float) -> np.ndarray:
    """Zero-mean, unit-std noise blurred at a scale, seamless when tiled (square or (h, w))."""
    shape = (size, size) if isinstance(size, int) else size
    noise = rng.standard_normal(shape).astype(np.float32)
    if sigma_px > 0:
        noise = periodic_blur(noise, sigma_px)
    noise -= noise.mean()
    return noise / max(float(noise.std()), 1e-6)


def to_rgb8(grey: np.ndarray, tint: tuple[float, float, float]) -> np.ndarray:
    rgb = np.clip(grey[..., None] * np.asarray(tint, dtype=np.float32), 0.0, 1.0)
    return (rgb * 255.0 + 0.5).astype(np.uint8)


def gravel(rng: np.random.Generator, size: int = 256) -> np.ndarray:
    """Lighter, coarser shoulder surface."""
    grey = 0.45 + 0.09 * tiled_noise(rng, size, 1.0) + 0.04 * tiled_noise(rng, size, 12.0)
    return to_rgb8(grey, (1.0, 0.97, 0.9))


def grass(rng: np.random.Generator, size: int = 256) -> np.ndarray:
    """A roadside verge: dry tan grass, olive and darker green patches, and tufts.

    Real verges beside highways (TuSimple, Udacity) are mostly dry grass and scrub, not lawn:
    low saturation, tan to olive, with a dark gap between every clump of blades. The patch
    map mixes GRASS_DRY, GRASS_OLIVE and GRASS_GREEN; the tuft map (a few centimetres to a
    decimetre on the ground) darkens the gaps between clumps to about a third and lights the
    blade tips, the texture of grass seen from 2-50 m. Draws what the lawn it replaced drew
    (two noise fields), so the textures made after it from the same generator do not move."""
    fine = tiled_noise(rng, size, 0.8)
    coarse = tiled_noise(rng, size, 16.0)
    # Further scales from the same two fields, shifted and transposed (decorrelated enough).
    clumps = periodic_blur(np.roll(fine.T, size // 3, axis=0), 2.5)
    clumps /= max(float(clumps.std()), 1e-6)
    mid = periodic_blur(np.roll(fine, size // 2, axis=1), 6.0)
    mid /= max(float(mid.std()), 1e-6)
    dry = np.clip(0.5 + 0.8 * coarse + 0.35 * mid, 0.0, 1.0)
    green = np.clip(0.5 * (np.roll(coarse.T, size // 5, axis=1) - 0.6), 0.0, 1.0)
    colour = (dry[..., None] * np.asarray(GRASS_DRY, np.float32)
              + (1.0 - dry[..., None]) * np.asarray(GRASS_OLIVE, np.float32))
    colour = (1.0 - green[..., None]) * colour + green[..., None] * np.asarray(GRASS_GREEN,
                                                                               np.float32)
    gaps = 1.0 / (1.0 + np.exp(-2.5 * (clumps + 0.3)))  # 0 in the gaps between tufts
    tufts = 0.35 + 0.75 * gaps + 0.18 * fine  # blades lit at the tips
    rgb = np.clip(colour * tufts[..., None], 0.0, 1.0)
    return (rgb * 255.0 + 0.5).astype(np.uint8)


def paint(rng: np.random.Generator, size: int = 64) -> np.ndarray:
    """Road paint: nearly uniform, slight grain."""
    grey = 0.93 + 0.03 * tiled_noise(rng, size, 0.7)
    return to_rgb8(grey, (1.0, 1.0, 1.0))


def worn_paint(rng: np.random.Generator, size: int = 64) -> np.ndarray:
    """Worn paint: the asphalt shows through in pits and scuffs (dark specks and streaks along
    the line), so faded paint is not just a dimmer version of fresh paint."""
    pits = (tiled_noise(rng, size, 0.8) > 1.0).astype(np.float32)
    scuffs = np.clip(tiled_noise(rng, (size, size), 2.0) - 0.6, 0.0, None)
    grey = 0.9 + 0.05 * tiled_noise(rng, size, 0.7) - 0.45 * pits - 0.25 * scuffs
    return to_rgb8(np.clip(grey, 0.25, 1.0), (1.0, 1.0, 1.0))
