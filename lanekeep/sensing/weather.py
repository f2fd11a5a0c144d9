"""Weather and motion between the scene and the lens: fog, falling rain, snowflakes, drops on
the lens, motion blur. They use the render's depth (lanekeep/sensing/cameras.py reads it from the
same
pass as the colour) so that they sit in the scene, not on top of it.

  - Fog: Koschmieder's law on the range of every pixel, I = I0 t + A (1 - t) with
    t = exp(-3 d / V) (V: the meteorological visibility, 5% contrast left), A the airlight (the
    fog colour the world gives the sky's horizon). It replaces MuJoCo's linear fog, which is a
    wall at 0.6 V.
  - Rain: streaks in three depth layers (0.8-2, 2-5, 5-12 m), each hidden where the scene is
    nearer than its layer. A drop's image motion during the exposure is its fall plus the car's
    motion: away from the focus of expansion on the front camera, towards the focus of
    contraction on the rear one, longer the nearer the drop. A streak blends towards the
    airlight (a drop refracts the sky), so it shows on the road and hardly on the sky.
  - Wet road: a screen-space reflection. On the paved surface and in the puddles
    (lanekeep/sensing/road_water.py, where the depth matches the flat ground's; grass and
    gravel are too rough to mirror) the scene above the horizon is mirrored about the horizon
    row (distant objects reflect there on a flat wet surface), blurred vertically (a rough
    water film), and blended with Schlick's Fresnel reflectance of water (R0 = 0.02) at the
    ray's grazing angle, times the share of the surface under a water film: WET_FILM * wet on
    the asphalt, all of it (PUDDLE_FILM) in a puddle.
  - Headlights in fog (dawn, dusk, night; front camera): the fog scatters the beams back to the
    camera, a veil over the lit cone that grows with the fog along the ray: HEADLIGHT_VEIL x
    the beam's strength along the ray x (1 - exp(-3 min(d, HEADLIGHT_REACH_M) / V)). A low
    beam is wide and cut off sharply above its axis: Gaussian in azimuth (HEADLIGHT_SPREAD_DEG)
    and in elevation, narrow above the axis (HEADLIGHT_CUT_DEG) and wide below it.
  - Motion blur: a zoom blur about the focus of expansion (the image flow of forward motion
    grows with the distance from it), scaled by the speed.
  - Lens drops: each a small ball lens that shows a wider, inverted, defocused view of the
    scene around it under a darker rim and a glint; they land, cling for seconds (big ones
    creep down) and go, as a function of the drive's time (lanekeep/sensing/lens_drops.py).
  - Snowflakes in depth layers: far ones small, dim and sharp, near ones large, brighter and
    out of focus (drawn and blurred at a reduced size), each flake of its own brightness.

Every random choice per frame comes from the generator passed in; `Weather` is made once per
camera and episode.
"""

from __future__ import annotations

import functools
import math

import cv2
import numpy as np

from lanekeep.geometry.camera_model import CameraModel
from lanekeep.scenario.conditions import Conditions
from lanekeep.sensing.lens_drops import LensDrops, drop_streams
from lanekeep.sensing.road_water import RoadWater
from lanekeep.world.lighting import fog_visibility_m

DEPTH_STEP_PX = 4  # the depth map is read at a quarter of the image resolution
RAIN_LAYERS_M = ((0.8, 2.0), (2.0, 5.0), (5.0, 12.0))  # near and far edge of each layer
RAIN_STREAKS_PER_LAYER = (350, 550, 700)  # at rain = 1 on a 1280x720 frame
RAIN_FALL_MPS = 7.0  # terminal velocity of a rain drop
EXPOSURE_S = 0.005  # the camera's exposure time: how long a drop's streak is
WATER_R0 = 0.02  # Fresnel reflectance of water at normal incidence
WET_FILM = 0.5  # share of the road under a mirror-like water film at wet = 1
REFLECTION_BLUR = 15  # vertical blur of the reflection at 720 rows (a rough film)
PUDDLE_FILM = 1.0  # a puddle is all water
REFLECT_MIN = 5  # rows where even the deepest film reflects under 5/255 are left alone
# The ego car's low beams (lanekeep/world_lighting.add_car_lights): their axis in the vehicle
# frame, cone, and how far their light reaches into the fog; the veil's strength at full beam.
HEADLIGHT_AXIS_DEG = -2.0  # elevation of the beams' axis
HEADLIGHT_SPREAD_DEG = 18.0  # Gaussian width in azimuth and below the axis
HEADLIGHT_CUT_DEG = 2.0  # ... and above it: the low beam's cut-off line
HEADLIGHT_REACH_M = 40.0
HEADLIGHT_VEIL = 0.25
HEADLIGHT_RGB = (255.0, 247.0, 230.0)
# Lens drops: how much wider than itself the (inverted) view through a drop is, its blur (a
# share of its radius: the lens is focused far beyond it), the light its rim passes, its glint.
DROP_VIEW = 2.5
DROP_BLUR = 0.12
DROP_RIM_SHADE = 0.75
DROP_GLINT_DN = 25.0
# Snowflakes per depth layer: radius (px at 720 rows), count at snow = 1 on a 1280x720 frame,
# opacity range, defocus blur sigma (px at 720 rows) and the size reduction they are drawn at.
SNOW_LAYERS = ((1, 1800, (0.3, 0.7), 0.0, 1), (2, 500, (0.45, 0.9), 0.8, 1),
               (4, 90, (0.5, 0.95), 1.6, 2), (10, 14, (0.25, 0.5), 5.0, 4))
BLUR_SCALE_PER_MPS = 0.0022  # zoom-blur scale per m/s at motion_blur = 1 (9 px at the bottom)


def needs_depth(conditions: Conditions) -> bool:
    """Whether a scenario's weather needs the depth render (fog, rain or a wet road)."""
    return conditions.fog > 0.0 or conditions.rain > 0.0 or conditions.wet > 0.0


@functools.lru_cache(maxsize=64)
def _drop_profile(side: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A lens drop `side` px across: its coverage (soft-edged disc), the light its body
    passes (1 inside, DROP_RIM_SHADE at the rim) and its highlight (DN, upper left), all
    float32 (side, side); read-only, they are cached."""
    c = (np.arange(side, dtype=np.float32) - (side - 1) / 2.0) / (side / 2.0)
    rho = np.hypot(c[None, :], c[:, None])
    edge_px = side / 2.0
    alpha = np.clip((1.0 - rho) / 0.25, 0.0, 1.0)  # out of focus: a soft edge
    alpha = np.minimum(alpha, np.clip((1.0 - rho) * edge_px, 0.0, 1.0))
    shade = 1.0 - (1.0 - DROP_RIM_SHADE) * np.exp(-(((rho - 0.8) / 0.15) ** 2))
    glint = DROP_GLINT_DN * np.exp(-(np.hypot(c[None, :] + 0.35, c[:, None] + 0.4) / 0.15) ** 2)
    arrays = tuple(a.astype(np.float32) for a in (alpha, shade, glint))
    for a in arrays:
        a.flags.writeable = False
    return arrays


def focus_of_expansion(camera: CameraModel, forward: bool) -> np.ndarray:
    """Pixel (u, v) where the car's straight-ahead (or straight-behind) direction projects."""
    uv, _ = camera.project(camera.position_m + [1000.0 if forward else -1000.0, 0.0, 0.0])
    return np.asarray(uv, dtype=float).reshape(2)


class Weather:
    """The weather of one scenario for one camera (`camera`: its model at the frame size)."""

    def __init__(self, conditions: Conditions, camera: CameraModel, airlight_rgb,
                 rng: np.random.Generator, frame_period_s: float = 0.1,
                 start_time_s: float = 0.0, water: RoadWater | None = None) -> None:
        self.conditions = c = conditions
        self.camera = camera
        self.height, self.width = h, w = camera.height, camera.width
        self.scale = h / 720.0
        self.forward = camera.rotation[0, 2] < 0.0  # optical axis (-z) points along +x
        self.foe = focus_of_expansion(camera, self.forward)
        self.airlight = np.asarray(airlight_rgb, dtype=float)
        # Range per unit z-depth at the depth map's pixels (the ray's length to its z).
        v, u = np.mgrid[DEPTH_STEP_PX // 2:h:DEPTH_STEP_PX, DEPTH_STEP_PX // 2:w:DEPTH_STEP_PX]
        self.ray_factor = np.sqrt(1.0 + ((u - camera.cx) / camera.fx) ** 2
                                  + ((v - camera.cy) / camera.fy) ** 2).astype(np.float32)
        self.extinction_per_m = 3.0 / fog_visibility_m(c.fog) if c.fog > 0.0 else 0.0
        air = np.clip(np.round(self.airlight), 0, 255).astype(np.uint8)
        self.air_image = np.empty((h, w, 3), np.uint8)
        self.air_image[:] = air
        veil = 0.35 * c.snow
        self.snow_veil = np.round(np.arange(256) * (1.0 - veil) + 235.0 * veil).astype(np.uint8)
        self.water = water  # where the wet road's water lies (None: on all flat ground)
        self._init_reflection(camera, v, u)
        lit = c.fog > 0.0 and c.time_of_day != "day" and self.forward
        self.beam = self._beam(camera, v, u) if lit else None
        # Lens drops: those at time 0 from `rng`, the later ones from streams of their own
        # (lanekeep/sensing/lens_drops.py); the frames' clock starts at `start_time_s`.
        n_drops = int(round(14 * c.rain))
        r = rng.uniform(8.0, 30.0, n_drops) * self.scale
        first = np.c_[rng.uniform(0, w, n_drops), rng.uniform(0, h, n_drops), r]
        self.lens = LensDrops(first, drop_streams(rng, 0 if self.forward else 1, n_drops), w, h)
        self.frame_period_s, self.start_time_s = frame_period_s, start_time_s
        self.frames = 0  # frames made so far
        self.drops = self.lens.at(start_time_s)  # centre (x, y), radius (px) of the drops

    @property
    def time_s(self) -> float:
        """The drive's time of the next frame (a count of frames: no drift)."""
        return self.start_time_s + self.frames * self.frame_period_s

    @staticmethod
    def _blend(image: np.ndarray, other: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        """image (1 - alpha) + other alpha, alpha uint8 (H, W) in 1/255."""
        a3 = cv2.merge([alpha, alpha, alpha])
        return cv2.add(cv2.multiply(image, 255 - a3, scale=1 / 255),
                       cv2.multiply(other, a3, scale=1 / 255))

    def _full(self, small: np.ndarray, interpolation=cv2.INTER_LINEAR) -> np.ndarray:
        return cv2.resize(small, (self.width, self.height), interpolation=interpolation)

    def _init_reflection(self, camera: CameraModel, v: np.ndarray, u: np.ndarray) -> None:
        """The flat ground's z-depth at the depth map's pixels, the horizon row, the Fresnel
        reflectance per row below it (uint8, 1/255) and how many rows a film can show."""
        xy, valid = camera.pixels_to_ground(np.stack([u, v], -1).astype(float))
        ground = np.concatenate([xy, np.zeros(xy.shape[:-1] + (1,))], -1)
        z = camera.to_opencv_frame(np.where(valid[..., None], ground, 0.0))[..., 2]
        self.ground_z = np.where(valid, z, np.inf).astype(np.float32)
        self.horizon = int(np.clip(round(camera.horizon_row()), 1, self.height - 1))
        rows = np.arange(self.height, dtype=float)
        below = np.arctan(np.maximum(rows - camera.horizon_row(), 0.0) / camera.fy)
        fresnel = WATER_R0 + (1 - WATER_R0) * (1.0 - np.sin(below)) ** 5
        self.fresnel = np.round(255 * np.where(rows >= self.horizon, fresnel, 0.0)
                                ).astype(np.uint8)[:, None]
        self.film = WET_FILM * self.conditions.wet  # the paved surface's share under water
        deepest = max(self.film, PUDDLE_FILM if self.water and self.water.puddles else 0.0)
        self.reflect_rows = int(min(np.count_nonzero(self.fresnel * deepest >= REFLECT_MIN),
                                    self.height - self.horizon))

    @staticmethod
    def _beam(camera: CameraModel, v: np.ndarray, u: np.ndarray) -> np.ndarray:
        """The low beams' strength (0..1) along each depth-map pixel's ray."""
        rays = camera.pixel_rays(np.stack([u, v], -1).astype(float))
        azimuth = np.degrees(np.arctan2(rays[..., 1], rays[..., 0]))
        elevation = np.degrees(np.arctan2(rays[..., 2], np.hypot(rays[..., 0], rays[..., 1])))
        above = elevation - HEADLIGHT_AXIS_DEG
        width = np.where(above > 0.0, HEADLIGHT_CUT_DEG, HEADLIGHT_SPREAD_DEG)
        ahead = rays[..., 0] > 0.0
        return np.where(ahead, np.exp(-(azimuth / HEADLIGHT_SPREAD_DEG) ** 2
                                      - (above / width) ** 2), 0.0).astype(np.float32)

    def headlight_veil(self, image: np.ndarray, depth_m: np.ndarray) -> np.ndarray:
        """The beams' light scattered back by the fog (see the module docstring)."""
        reach = np.minimum(depth_m * self.ray_factor, HEADLIGHT_REACH_M)
        share = HEADLIGHT_VEIL * self.beam * (1.0 - np.exp(-self.extinction_per_m * reach))
        veil = self._full(share)[..., None] * np.asarray(HEADLIGHT_RGB, np.float32)
        return cv2.add(image, np.round(veil).astype(np.uint8))

    def water_film(self, depth_m: np.ndarray, pose) -> np.ndarray:
        """The share of each depth-map pixel under a mirror-smooth water film (uint8, 1/255):
        flat ground (the depth matches the flat ground's) that is paved (`film`) or a puddle
        (PUDDLE_FILM); every flat ground pixel counts as paved without `water` or `pose`."""
        ground = (np.abs(depth_m - self.ground_z) < 0.04 * self.ground_z).astype(np.uint8)
        if self.water is None or pose is None:
            return ground * np.uint8(round(255 * self.film))
        paved, puddles = self.water.masks(self.camera, pose, depth_m.shape, DEPTH_STEP_PX)
        film = cv2.max(cv2.multiply(paved, self.film), cv2.multiply(puddles, PUDDLE_FILM))
        return cv2.multiply(film, ground)

    def wet_reflection(self, image: np.ndarray, depth_m: np.ndarray, pose=None) -> np.ndarray:
        """Mirror the view above the horizon onto the wet road below it, Fresnel-weighted, on
        the paved surface and the puddles (`water_film`) of the car at `pose` (world x, y,
        yaw). Rows further below the horizon than it is from the top mirror the top row."""
        n, top = self.reflect_rows, self.horizon
        if n < 2:
            return image
        film = self._full(self.water_film(depth_m, pose), cv2.INTER_LINEAR)[top:top + n]
        source = np.maximum(top - 1 - np.arange(n), 0)
        mirror = image[source] if n > top else image[top - n:top][::-1]
        k = max(3, int(REFLECTION_BLUR * self.scale) | 1)
        mirror = cv2.blur(mirror, (3, k))
        alpha = cv2.multiply(film, np.broadcast_to(self.fresnel[top:top + n], film.shape),
                             scale=1 / 255)
        out = image.copy()
        out[top:top + n] = self._blend(image[top:top + n], mirror, alpha)
        return out

    def range_m(self, depth_m: np.ndarray) -> np.ndarray:
        """Full-resolution distance of every pixel from the quarter-resolution z-depth."""
        return self._full(depth_m * self.ray_factor)

    # -- effects ------------------------------------------------------------------------------
    def fog_alpha(self, depth_m: np.ndarray) -> np.ndarray:
        """Koschmieder: the airlight's share 1 - exp(-3 d / V) of every pixel (uint8, 1/255)."""
        transmit = np.exp(-self.extinction_per_m * depth_m * self.ray_factor)
        return self._full(np.round(255.0 * (1.0 - transmit)).astype(np.uint8))

    def motion_blur(self, image: np.ndarray, speed_mps: float) -> np.ndarray:
        """Zoom blur about the focus of expansion: the frame and two exposures scaled 1 + k/2
        and 1 + k, the scaled ones made at half resolution (they are blurred anyway)."""
        k = BLUR_SCALE_PER_MPS * self.conditions.motion_blur * abs(speed_mps)
        if k * math.hypot(self.width, self.height) / 2 < 1.5:
            return image
        w2, h2 = self.width // 2, self.height // 2
        half = cv2.resize(image, (w2, h2), interpolation=cv2.INTER_AREA)
        fx, fy = self.foe / 2.0
        taps = []
        for s in (1.0 + k / 2.0, 1.0 + k):
            m = np.array([[s, 0.0, fx * (1 - s)], [0.0, s, fy * (1 - s)]])
            taps.append(cv2.warpAffine(half, m, (w2, h2), borderMode=cv2.BORDER_REPLICATE))
        scaled = self._full(cv2.addWeighted(taps[0], 0.5, taps[1], 0.5, 0.0))
        return cv2.addWeighted(image, 1.0 / 3.0, scaled, 2.0 / 3.0, 0.0)

    def rain_alpha(self, depth_m: np.ndarray, rng: np.random.Generator,
                   speed_mps: float) -> np.ndarray:
        """Streaks in depth layers, hidden behind nearer scene: their share of the airlight
        (uint8, 1/255). A streak is drawn when the scene lies beyond its layer at both its
        ends and its middle (the depth map's pixels there): one test per streak instead of a
        full-frame mask per layer; a streak may cross a pole thinner than itself."""
        amount = self.conditions.rain
        h, w = self.height, self.width
        f = self.camera.fy
        sign = 1.0 if self.forward else -1.0  # away from / towards the focus
        alpha = np.zeros((h, w), np.uint8)
        dh, dw = depth_m.shape
        for (near, far), count in zip(RAIN_LAYERS_M, RAIN_STREAKS_PER_LAYER, strict=True):
            n = int(count * amount * (w * h) / (1280 * 720))
            z = rng.uniform(near, far, n)
            p0 = np.c_[rng.uniform(0, w, n), rng.uniform(0, h, n)]
            velocity = sign * (p0 - self.foe) * abs(speed_mps)
            velocity[:, 1] += f * RAIN_FALL_MPS
            p1 = p0 + velocity * (EXPOSURE_S / z)[:, None]
            visible = np.ones(n, bool)
            for t in (0.0, 0.5, 1.0):
                q = p0 + t * (p1 - p0)
                col = np.clip((q[:, 0] // DEPTH_STEP_PX).astype(int), 0, dw - 1)
                row = np.clip((q[:, 1] // DEPTH_STEP_PX).astype(int), 0, dh - 1)
                visible &= depth_m[row, col] > near  # the scene lies beyond the layer
            lines = np.stack([p0, p1], 1)[visible].round().astype(np.int32)
            bright = int(round(255 * (0.15 + 0.25 * amount) * 1.8 / (1.0 + near)))
            cv2.polylines(alpha, list(lines), False, bright, 1, cv2.LINE_AA)
        return cv2.GaussianBlur(alpha, (3, 5), 0)

    def lens_drops(self, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Water drops on the lens, each a small lens itself: it shows the scene around it,
        DROP_VIEW times wider than the drop, turned upside down (a ball lens inverts),
        out of focus, under a darker rim (the drop's edge bends light away) with a small
        highlight; the scene outside is untouched. Work is done only around each drop."""
        n = len(self.lens.slots)
        if n == 0:
            return image
        wobble = rng.uniform(0.0, 1.5, n) / 1.5  # the airflow's shiver this frame
        self.drops = self.lens.at(self.time_s, wobble)
        out = image.copy()
        for x, y, r in self.drops:
            side = 2 * int(math.ceil(r)) + 1
            x0, y0 = int(round(x)) - side // 2, int(round(y)) - side // 2
            cx0, cy0 = max(0, x0), max(0, y0)
            cx1, cy1 = min(self.width, x0 + side), min(self.height, y0 + side)
            if cx1 <= cx0 or cy1 <= cy0:
                continue
            view_px = int(round(DROP_VIEW * side))
            view = cv2.getRectSubPix(image, (view_px, view_px), (float(x), float(y)))
            view = cv2.flip(cv2.resize(view, (side, side), interpolation=cv2.INTER_AREA), -1)
            view = cv2.GaussianBlur(view, (0, 0), max(0.8, DROP_BLUR * r))
            alpha, shade, glint = _drop_profile(side)
            lens = view.astype(np.float32) * shade[..., None] + glint[..., None]
            region = (slice(cy0 - y0, cy1 - y0), slice(cx0 - x0, cx1 - x0))
            a = alpha[region][..., None]
            behind = out[cy0:cy1, cx0:cx1].astype(np.float32)
            out[cy0:cy1, cx0:cx1] = np.clip(behind + a * (lens[region] - behind), 0, 255)
        return out

    def snow(self, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Flakes in depth layers (SNOW_LAYERS): each flake of its own brightness, near ones
        larger and out of focus, drawn and blurred at 1/shrink of the size and enlarged."""
        amount = self.conditions.snow
        h, w = self.height, self.width
        layer = np.zeros((h, w), np.uint8)
        for radius, count, (lo, hi), sigma, shrink in SNOW_LAYERS:
            n = int(count * amount * (w * h) / (1280 * 720))
            hs, ws = h // shrink, w // shrink
            dots = np.zeros((hs, ws), np.uint8)
            dots[rng.integers(0, hs, n), rng.integers(0, ws, n)] = np.round(
                255 * rng.uniform(lo, hi, n)).astype(np.uint8)
            rad = max(1, int(round(radius * self.scale / shrink)))
            kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * rad + 1, 2 * rad + 1))
            flakes = cv2.dilate(dots, kernel)  # grey dilation: each flake keeps its level
            if sigma > 0.0:
                flakes = cv2.GaussianBlur(flakes, (0, 0), sigma * self.scale / shrink)
            if shrink > 1:
                flakes = cv2.resize(flakes, (w, h), interpolation=cv2.INTER_LINEAR)
            layer = cv2.max(layer, flakes)
        out = self._blend(image, np.full_like(image, 245), cv2.GaussianBlur(layer, (3, 3), 0))
        return cv2.LUT(out, self.snow_veil)  # falling snow whitens the whole view

    def __call__(self, image: np.ndarray, depth_m: np.ndarray | None,
                 rng: np.random.Generator, speed_mps: float = 0.0, pose=None) -> np.ndarray:
        """The weather on one RGB uint8 frame; `depth_m` is the z-depth at every
        DEPTH_STEP_PX-th pixel (needed when `needs_depth`), `pose` the car's world (x, y,
        yaw) (where the wet road's water lies). Returns the input when no weather."""
        c = self.conditions
        out = image
        if c.motion_blur > 0.0:
            out = self.motion_blur(out, speed_mps)
        if c.wet > 0.0:
            out = self.wet_reflection(out, depth_m, pose)
        if c.fog > 0.0 or c.rain > 0.0:  # both veil the scene with the airlight: one blend
            alpha = self.fog_alpha(depth_m) if c.fog > 0.0 else None
            if c.rain > 0.0:
                streaks = self.rain_alpha(depth_m, rng, speed_mps)
                # the streaks' share of what the fog leaves: a + s (1 - a)
                alpha = streaks if alpha is None else cv2.add(
                    alpha, cv2.multiply(streaks, 255 - alpha, scale=1 / 255))
            out = self._blend(out, self.air_image, alpha)
        if self.beam is not None:
            out = self.headlight_veil(out, depth_m)
        if c.snow > 0.0:
            out = self.snow(out, rng)
        if c.rain > 0.0:
            out = self.lens_drops(out, rng)
        self.frames += 1
        return out
