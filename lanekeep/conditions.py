"""Image-space effects that MuJoCo does not render: rain, lens drops, snow, motion blur, noise.

Order, as light reaches the sensor: motion blur of the scene during the exposure, falling rain or
snow in front of the camera, water drops on the lens, then the sensor: low-light gain and noise
(Gaussian read noise plus shot noise whose variance grows with the signal), quantised to uint8.

`ImageEffects` is made once per camera and episode: it precomputes kernels and a noise bank and
keeps the lens drops (they stay on the lens and slide down slowly). Every random choice per frame
comes from the `numpy.random.Generator` passed in, so a seed gives bit-identical frames.
`apply(image, conditions, rng)` is the one-shot form. Each effect costs about 1.5-8.5 ms on a
1280x720 frame (rain with lens drops 6, snow 4, noise 8, motion blur 1.5, night gain and noise 8.5).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from lanekeep.scenario import Conditions

NOISE_BANK_FRAMES = 2  # the noise bank holds this many frames of Gaussian noise
READ_NOISE_DN = 8.0  # read-noise standard deviation at noise = 1 (digital numbers, 0..255)
SHOT_GAIN_DN = 1.2  # shot-noise variance per DN of signal at noise = 1
NIGHT_GAIN = {"day": 1.0, "dawn": 1.3, "dusk": 1.4, "night": 1.8}  # auto-exposure gain
NIGHT_NOISE = {"day": 0.0, "dawn": 0.15, "dusk": 0.2, "night": 0.35}  # extra noise from the gain
RAIN_ANGLE_RAD = 0.25  # streak slant from vertical
BLUR_PX_AT_15MPS = 9.0  # vertical motion-blur length at 15 m/s, motion_blur = 1, 720 rows


def _lut(values: np.ndarray) -> np.ndarray:
    return np.clip(values, 0, 255).astype(np.uint8)


class ImageEffects:
    """The image effects of one scenario for one camera of size (height, width)."""

    def __init__(self, conditions: Conditions, height: int, width: int,
                 rng: np.random.Generator) -> None:
        self.conditions = conditions
        self.height, self.width = height, width
        self.scale = height / 720.0
        c = conditions
        gain = NIGHT_GAIN[c.time_of_day]
        self.noise_level = min(1.0, c.noise + NIGHT_NOISE[c.time_of_day])
        # Tone curve (gain, then the whitening of snow and the mist of rain) as one uint8 LUT.
        x = np.arange(256, dtype=np.float64) * gain
        haze = 0.35 * c.snow + 0.12 * c.rain
        x = x * (1.0 - haze) + 235.0 * haze
        self.tone = None if gain == 1.0 and haze == 0.0 else _lut(np.round(x))
        if self.noise_level > 0.0:
            bank_rows = NOISE_BANK_FRAMES * height
            self.noise_bank = rng.standard_normal((bank_rows, width * 3), dtype=np.float32)
            sd = np.sqrt(READ_NOISE_DN**2 + SHOT_GAIN_DN * np.arange(256)) * self.noise_level
            self.noise_sd4 = _lut(np.round(4.0 * sd))  # quarter-DN steps, <= 255 (sd <= 19 DN)
        # Lens drops: centre (x, y), radius in pixels; they stay and slide down.
        n_drops = int(round(14 * c.rain))
        r = rng.uniform(8.0, 30.0, n_drops) * self.scale
        self.drops = np.c_[rng.uniform(0, width, n_drops), rng.uniform(0, height, n_drops), r]

    # -- per-frame effects ---------------------------------------------------------------------
    def motion_blur(self, image: np.ndarray, speed_mps: float) -> np.ndarray:
        """Vertical box blur (road texture streams down the image), length proportional to speed."""
        length = int(round(BLUR_PX_AT_15MPS * self.scale * self.conditions.motion_blur
                           * abs(speed_mps) / 15.0))
        if length < 2:
            return image
        return cv2.blur(image, (1, length))

    def rain(self, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Slanted, motion-blurred bright streaks of falling drops."""
        amount = self.conditions.rain
        h, w = self.height, self.width
        n = int(1400 * amount * (w * h) / (1280 * 720))
        length = rng.uniform(30.0, 90.0, n) * self.scale
        x0 = rng.uniform(-0.2 * w, w, n)
        y0 = rng.uniform(-0.1 * h, h, n)
        dx, dy = length * math.sin(RAIN_ANGLE_RAD), length * math.cos(RAIN_ANGLE_RAD)
        lines = np.stack([np.c_[x0, y0], np.c_[x0 + dx, y0 + dy]], 1).round().astype(np.int32)
        layer = np.zeros((h, w), np.uint8)
        bright = int(40 + 40 * amount)
        cv2.polylines(layer, list(lines), False, bright, 1, cv2.LINE_AA)
        layer = cv2.GaussianBlur(layer, (3, 5), 0)
        return cv2.add(image, cv2.merge([layer, layer, layer]))

    def lens_drops(self, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Water drops on the lens: soft discs showing a blurred, brightened view."""
        if len(self.drops) == 0:
            return image
        self.drops[:, 1] += rng.uniform(0.0, 1.5, len(self.drops)) * self.scale  # slide down
        gone = self.drops[:, 1] - self.drops[:, 2] > self.height
        self.drops[gone, 1] = -self.drops[gone, 2]
        small = cv2.resize(image, (self.width // 8, self.height // 8), interpolation=cv2.INTER_AREA)
        small = cv2.blur(small, (3, 3))
        blurred = cv2.resize(small, (self.width, self.height), interpolation=cv2.INTER_LINEAR)
        blurred = cv2.convertScaleAbs(blurred, alpha=1.1, beta=12)
        mask = np.zeros((self.height // 4, self.width // 4), np.uint8)
        for x, y, r in self.drops:
            cv2.circle(mask, (int(x / 4), int(y / 4)), max(1, int(r / 4)), 255, -1, cv2.LINE_AA)
        mask = cv2.resize(cv2.blur(mask, (3, 3)), (self.width, self.height))
        alpha = cv2.merge([mask, mask, mask])
        return cv2.add(cv2.multiply(image, 255 - alpha, scale=1 / 255),
                       cv2.multiply(blurred, alpha, scale=1 / 255))

    def snow(self, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Flakes of three sizes, soft-edged (near ones larger and blurrier)."""
        amount = self.conditions.snow
        h, w = self.height, self.width
        layer = np.zeros((h, w), np.uint8)
        for radius, count in ((1, 1800), (2, 500), (4, 90)):
            n = int(count * amount * (w * h) / (1280 * 720))
            rad = max(1, int(round(radius * self.scale)))
            dots = np.zeros((h, w), np.uint8)
            dots[rng.integers(0, h, n), rng.integers(0, w, n)] = 255
            kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * rad + 1, 2 * rad + 1))
            layer = cv2.max(layer, cv2.dilate(dots, kernel))
        layer = cv2.GaussianBlur(layer, (5, 5), 0)
        alpha = cv2.merge([layer, layer, layer])
        white = np.full_like(image, 245)
        return cv2.add(cv2.multiply(image, 255 - alpha, scale=1 / 255),
                       cv2.multiply(white, alpha, scale=1 / 255))

    def sensor(self, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Low-light gain and tone, then read + shot noise from the noise bank."""
        if self.tone is not None:
            image = cv2.LUT(image, self.tone)
        if self.noise_level <= 0.0:
            return image
        h = self.height
        start = int(rng.integers(0, self.noise_bank.shape[0] - h + 1))
        noise = self.noise_bank[start : start + h].reshape(h, self.width, 3)
        scaled = cv2.multiply(noise, cv2.LUT(image, self.noise_sd4), scale=0.25, dtype=cv2.CV_32F)
        return cv2.add(image, scaled, dtype=cv2.CV_8U)  # saturates and rounds

    def __call__(self, image: np.ndarray, rng: np.random.Generator,
                 speed_mps: float = 0.0) -> np.ndarray:
        """All effects of the conditions on one RGB uint8 frame (H, W, 3); returns a new array."""
        c = self.conditions
        if image.shape != (self.height, self.width, 3) or image.dtype != np.uint8:
            raise ValueError(f"expected uint8 ({self.height}, {self.width}, 3), got "
                             f"{image.dtype} {image.shape}")
        out = image
        if c.motion_blur > 0.0:
            out = self.motion_blur(out, speed_mps)
        if c.rain > 0.0:
            out = self.rain(out, rng)
        if c.snow > 0.0:
            out = self.snow(out, rng)
        if c.rain > 0.0:
            out = self.lens_drops(out, rng)
        out = self.sensor(out, rng)
        return out if out is not image else image.copy()


def apply(image: np.ndarray, conditions: Conditions, rng: np.random.Generator,
          speed_mps: float = 0.0) -> np.ndarray:
    """One-shot form of ImageEffects (new lens drops each call): image -> image."""
    h, w = image.shape[:2]
    return ImageEffects(conditions, h, w, rng)(image, rng, speed_mps)
