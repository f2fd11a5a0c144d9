"""The camera's own image chain after the light reaches it: vignetting, auto-exposure, sensor
noise, tone curve, glare, point spread and optional JPEG; what every real camera does, so all but
the JPEG is on by default (each step off at 0 in CameraConfig).

Order, as a camera works: the lens darkens the corners (vignetting, falloff 1 - k r^2 with r
the radius relative to the corner), the sensor integrates with the exposure the auto-exposure
set and adds its read noise (before the gain, so the gain amplifies it: night frames are
noisier), the ISP maps the signal through gain and an S-shaped tone curve (black level crushed,
midtones lifted a little: `tone_curve`); then the optics' and the demosaic's softness: a mild
glare (bloom) spreads light from near-saturated areas (a bright sky over the treeline, lamps at
night) onto their darker surroundings, and a small Gaussian point spread (`lens_blur_px`) makes
a hard edge rise over 2-3 px as on a real photo instead of the renderer's 1 px stair step
(applied after the noise, as demosaicing is: it also correlates the noise, as on real frames);
last, when `jpeg_quality` is set, the frame is JPEG-compressed as a dashcam stores it (its 4:2:0
chroma subsampling is then the camera's chromatic softness). Off by default: an ADAS camera
hands perception uncompressed frames, and the round trip costs more than the rest together.

The glare is computed at 1/16 of the size (it is smooth): the frame's excess over
BLOOM_THRESHOLD, area-averaged, blurred; only where that glow exceeds the averaged excess
itself is light added (enlarged to the frame), so a uniformly bright sky keeps its level and
its glow falls on the darker things next to it. The optics cost ~1.5 ms and the JPEG round
trip ~3-4 ms on a 1280x720 frame (2 CPU cores; see the issue #44 note).

Auto-exposure is causal: frame k is exposed with the gain set from the metering of frames
0..k-1, filtered in log-gain with a time constant; the first frame starts settled on its own
metering. It meters the road: the mean of the lower half of the frame (subsampled), aiming at a
sunlit clear-day road's level (EXPOSURE_TARGET_DN), so day scenes keep a gain of 1 and dusk
and night are brightened, up to MAX_GAIN (never darkened: see MIN_GAIN). Highlight protection
only limits brightening: the gain keeps the brightest 1% of the frame (a headlit road at
night, a sunlit sky) at or below HIGHLIGHT_DN, so a lit road is not blown out (night gain ~2)
and a shaded road under a bright sky is not pushed to a gain above 1 (it stays dark grey, about
a quarter of the sunlit road's luma, as on real frames).

Noise is signal-independent read noise (default 1 DN; Conditions.noise adds up to 8 DN), with
no separate shot-noise term: per-pixel signal-dependent noise costs four more full-frame passes.
Cost on a 1280x720 frame is four uint8 OpenCV passes (~1.6 ms): a multiply for the vignetting,
a saturating add and a saturating subtract of noise from a precomputed bank (two frames, read at
a random row; see `CameraSensor.__init__`), a LUT for gain and tone. Every pass sees the frame
as one plane of H x 3W bytes (OpenCV's one-channel LUT is twice as fast as its three-channel
one), and all but the first write into the frame the first one made.
"""

from __future__ import annotations

import functools
import math

import cv2
import numpy as np

NOISE_BANK_FRAMES = 2  # the noise bank holds this many frames of noise
READ_NOISE_DN_AT_1 = 8.0  # extra read noise at Conditions.noise = 1 (digital numbers)
EXPOSURE_TARGET_DN = 105.0  # road metering of a well-exposed frame (sunlit clear-day road)
# Exposure range relative to the render's (a sunlit day's): brightening up to +12 dB; no
# darkening, since no scene is lit more than the sunlit day, and a metering above the target
# comes from the fog's or snow's veil: darkening a fog frame to the target (gain ~0.75) cost the
# closed loop on `fog` (car lateral RMS 4 -> 22 cm, max 71 cm; 4 cm without the darkening).
MIN_GAIN, MAX_GAIN = 1.0, 4.0
HIGHLIGHT_DN = 160.0  # brightening stops where the frame's 99th percentile reaches this
# Tone curve: a midtone lift (t + lift t^2 (1 - t)^power: +5 DN at a sunlit road's 77 DN, none
# at black or white) and a black crush (- crush t exp(-t / scale): the black level a camera's
# ISP subtracts, slope 0.6 at black), so deep shade stays deep as on real dashcam frames.
TOE_LIFT, TOE_POWER = 2.2, 6.0
BLACK_CRUSH, BLACK_SCALE = 0.4, 0.08
METER_STEP_PX = 8  # metering reads every 8th pixel in both directions
BLOOM_HALVINGS = 4  # the glare is computed at 1/16 of the frame's size
BLOOM_THRESHOLD = (200.0, 200.0, 200.0, 0.0)  # display level (DN) above which a pixel glares
BLOOM_SIGMA = 0.02  # the glare's Gaussian width, a share of the frame's width
BLOOM_GAIN = 2.0  # the glare's excess gain at bloom = 1


def tone_curve(t: np.ndarray) -> np.ndarray:
    """Display value (0..1) of a normalised signal t (0..1): an S-curve as a camera's ISP
    applies, its toe crushing deep shadows (8 DN -> 6, 20 -> 19, 38 -> 40) and its middle
    lifting the midtones a little (77 -> 82, 105 -> 109); monotonic (slope 1 - BLACK_CRUSH at
    black, so a gained-up 8-bit night sky does not band).

    Real dashcam frames crush blacks (their darkest 1% at 7-8 DN, a fifth of TuSimple's frame
    below 40 DN); the toe this replaced lifted them (12 DN -> 20, 38 -> 53), which left no
    pixel of ours below ~15 DN and shaded road at 0.35-0.4 of the sunlit road's luma where
    the shade's physics (lanekeep/world/shade.py) and real frames give ~0.26."""
    lift = TOE_LIFT * t**2 * (1.0 - t) ** TOE_POWER
    return t + lift - BLACK_CRUSH * t * np.exp(-t / BLACK_SCALE)


@functools.lru_cache(maxsize=256)
def _tone_lut(gain: float) -> np.ndarray:
    """Gain + tone curve as one uint8 LUT. Built from the rounded gain it is cached under, so a
    frame does not depend on which gains came before; bounded, so an hour of exposure changes
    (tools/soak) does not grow memory. Read-only: it is shared."""
    t = np.clip(np.arange(256) * gain / 255.0, 0.0, 1.0)
    lut = np.clip(np.round(255.0 * tone_curve(t)), 0, 255).astype(np.uint8)
    lut.flags.writeable = False
    return lut


def psf_taps(sigma_px: float) -> int:
    """Taps of the point spread's Gaussian: 2 round(1.5 sigma) + 1 (3 for the default)."""
    return 2 * max(1, round(1.5 * sigma_px)) + 1


def vignetting_map(height: int, width: int, strength: float) -> np.ndarray:
    """uint8 (H, W, 3) transmission of the lens, 255 at the centre, 255 (1 - strength) at the
    corners, falling with the squared radius."""
    v, u = np.mgrid[0:height, 0:width].astype(np.float32)
    r2 = ((u - (width - 1) / 2) ** 2 + (v - (height - 1) / 2) ** 2) / (
        ((width - 1) / 2) ** 2 + ((height - 1) / 2) ** 2)
    falloff = np.round(255.0 * (1.0 - strength * r2)).astype(np.uint8)
    return cv2.merge([falloff, falloff, falloff])


class CameraSensor:
    """The image chain of one camera for one episode (it keeps the auto-exposure state).

    `camera` is the scenario's CameraConfig; `extra_noise` is Conditions.noise (a worse sensor,
    0..1); `frame_period_s` the time between frames (the auto-exposure's clock).
    """

    def __init__(self, camera, extra_noise: float, height: int, width: int,
                 frame_period_s: float, rng: np.random.Generator) -> None:
        self.height, self.width = height, width
        self.auto_exposure = camera.auto_exposure
        self.jpeg_quality = camera.jpeg_quality
        self.psf_sigma = camera.lens_blur_px
        self.bloom_gain = BLOOM_GAIN * camera.bloom
        self.bloom_sigma = BLOOM_SIGMA * width / 2**BLOOM_HALVINGS  # at the small size
        # Read noise in the sensor's DN before the gain (an int8 bank): the camera's own and a
        # noisier sensor's extra (Conditions.noise); the gain and the tone curve shape it.
        read_dn = math.hypot(camera.read_noise_dn, READ_NOISE_DN_AT_1 * extra_noise)
        # The bank as its positive and negative parts, uint8 planes (2H, 3W): a saturating add
        # of signed noise is a saturating add of the one and a saturating subtract of the
        # other (a pixel has at most one of them), two uint8 passes where one add of int8 to
        # uint8 widens both to int16 and costs more than both. The same frames as one bank.
        self.read_bank: tuple[np.ndarray, np.ndarray] | None = None
        if read_dn > 0.0:
            z = rng.standard_normal((NOISE_BANK_FRAMES * height, width * 3), dtype=np.float32)
            bank = np.clip(np.round(z * read_dn), -127, 127).astype(np.int8)
            self.read_bank = (np.maximum(bank, 0).astype(np.uint8),
                              np.maximum(-bank, 0).astype(np.uint8))
        self.alpha = 1.0 - math.exp(-frame_period_s / camera.exposure_time_constant_s)
        self.vignette = (vignetting_map(height, width, camera.vignetting).reshape(height, -1)
                         if camera.vignetting > 0.0 else None)  # one plane, as the frame's
        self.log_gain: float | None = None  # None until the first frame is metered

    @property
    def gain(self) -> float:
        return 1.0 if self.log_gain is None else math.exp(self.log_gain)

    def _meter(self, image: np.ndarray) -> tuple[float, float]:
        """Mean brightness of the lower half (the road) and the 99th percentile of the frame
        (DN, before the gain)."""
        step = METER_STEP_PX
        sample = image[step // 2::step, step // 2::step]
        road = sample[sample.shape[0] // 2:]
        flat = sample.reshape(-1)
        k = int(0.99 * (flat.size - 1))
        top = np.partition(flat, k)[k]
        return max(float(road.mean()), 1.0), max(float(top), 1.0)

    def _tone_for(self, gain: float) -> np.ndarray:
        """Gain + tone curve as one uint8 LUT, for the gain rounded to 1e-4."""
        return _tone_lut(round(gain, 4))

    def _update_exposure(self, metering_dn: tuple[float, float]) -> None:
        mean, top = metering_dn
        gain = min(EXPOSURE_TARGET_DN / mean, max(HIGHLIGHT_DN / top, 1.0))
        target = math.log(min(max(gain, MIN_GAIN), MAX_GAIN))
        if self.log_gain is None:
            self.log_gain = target
        else:
            self.log_gain += self.alpha * (target - self.log_gain)

    def bloom(self, frame: np.ndarray) -> np.ndarray:
        """The glare of the near-saturated areas added to `frame` (in place; see the module
        docstring). A frame with nothing above the threshold is returned as it is."""
        small = cv2.subtract(frame, BLOOM_THRESHOLD)  # the excess (saturating)
        for _ in range(BLOOM_HALVINGS):  # a bilinear halving is a 2x2 mean: 4 make 16x16
            small = cv2.resize(small, (max(1, small.shape[1] // 2), max(1, small.shape[0] // 2)),
                               interpolation=cv2.INTER_LINEAR)
        if not small.any():
            return frame
        small = cv2.convertScaleAbs(small, alpha=self.bloom_gain)
        glow = cv2.GaussianBlur(small, (0, 0), self.bloom_sigma)
        halo = cv2.resize(cv2.subtract(glow, small), (self.width, self.height),
                          interpolation=cv2.INTER_LINEAR)
        return cv2.add(frame, halo, dst=frame)

    def jpeg(self, frame: np.ndarray) -> np.ndarray:
        """`frame` compressed and decompressed as a dashcam stores it."""
        _, data = cv2.imencode(".jpg", cv2.cvtColor(frame, cv2.COLOR_RGB2BGR),
                               [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
        return cv2.cvtColor(cv2.imdecode(data, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)

    def __call__(self, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """One RGB uint8 frame through the chain; returns a new array."""
        h, w = self.height, self.width
        plane = image.reshape(h, w * 3)  # the frame as one plane (a view)
        out = None  # the new frame, once a pass has made it; later passes write into it
        if self.vignette is not None:
            out = cv2.multiply(plane, self.vignette, scale=1.0 / 255.0)
        lit = (plane if out is None else out).reshape(h, w, 3)
        if self.auto_exposure and self.log_gain is None:
            self._update_exposure(self._meter(lit))  # the first frame starts settled
        metering = self._meter(lit) if self.auto_exposure else (0.0, 0.0)
        tone = self._tone_for(self.gain)
        if self.read_bank is not None:
            positive, negative = self.read_bank
            start = int(rng.integers(0, positive.shape[0] - h + 1))
            out = cv2.add(plane if out is None else out, positive[start:start + h], dst=out)
            cv2.subtract(out, negative[start:start + h], dst=out)  # both saturate
        out = cv2.LUT(plane if out is None else out, tone, dst=out).reshape(h, w, 3)
        if self.bloom_gain > 0.0:
            out = self.bloom(out)
        if self.psf_sigma > 0.0:
            taps = psf_taps(self.psf_sigma)
            out = cv2.GaussianBlur(out, (taps, taps), self.psf_sigma, dst=out)
        if self.jpeg_quality > 0:
            out = self.jpeg(out)
        if self.auto_exposure:
            self._update_exposure(metering)  # sets the next frame's exposure
        return out  # a new array: the first pass made it
