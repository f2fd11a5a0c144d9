"""The sky: a seeded skybox texture with a hazy horizon band and clouds, made once per world.

MuJoCo draws a skybox cube map at infinity. Every texel's colour is a function of its world
direction (so the six faces meet without seams): a gradient from the zenith colour to a pale,
hazy band at the horizon (the air's haze is brightest where the line of sight through it is
longest), and clouds from a tileable noise field projected onto a cloud deck at a fixed
height, so they shrink towards the horizon as real ones do, and fade into the haze there.
Fair weather gets scattered white cumulus with grey bases; an overcast (rain, snow) a closed
grey deck whose texture is only a mottling of its brightness. At night no sun lights the
clouds: they are lit from below by the towns' glow (the warm band at the horizon), so they show
only as faintly lighter patches against the near-black zenith and darker ones against the glow
(blended in as the time of day's light fades, NIGHT_LIGHT). Below the horizon (seen only past
the end of the ground) the texture is the horizon colour.

The clouds are drawn from the scenario's seed and a key of its name (`sky_generator`): with the
seed alone, the shipped scenarios that share a seed (clear_curve, clear_straight, s_bend and
sharp_turn all have seed 0) had one and the same cloud map. The same file and seed still draw
the same sky in any process (lanekeep/scenario/streams.py's name_key, a SHA-256 of the name).

The texture is SKY_FACE_PX square per face; with the noise made at CLOUD_NOISE_PX and sampled
with cv2.remap, building it costs ~30 ms once per world.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

from lanekeep.scenario.streams import name_key

SKY_FACE_PX = 256  # texels per cube face edge
SKY_SEED = 0x5C1  # the sky's own generator: [scenario seed, name key, this]
CLOUD_NOISE_PX = 256  # the tileable cloud field's size
CLOUD_OCTAVES = (4, 8, 16, 32, 64)  # cells across the field per octave
CLOUD_DECK_SCALE = 0.35  # field tiles per unit of (horizontal / vertical) ray length
HAZE_ELEVATION = 0.12  # the hazy band's height (sine of the elevation)
CLOUD_HAZE_ELEVATION = 0.08  # clouds fade into the haze below about this elevation
FAIR_CLOUD_RGB = (0.96, 0.96, 0.97)  # sunlit cumulus top, at day; its base is greyer
CLOUD_BASE_SHADE = 0.78  # the base's brightness relative to the top
NIGHT_LIGHT = 0.3  # below this much of a day's light the clouds are lit by the glow only
NIGHT_CLOUD_GLOW = 0.22  # a night cloud's brightness relative to the glow at the horizon


def sky_generator(seed: int, name: str) -> np.random.Generator:
    """The sky's generator for the scenario `name` on `seed`: its own stream (SKY_SEED), with
    the name folded in so that scenarios sharing a seed do not share a sky."""
    return np.random.default_rng([seed, name_key(name), SKY_SEED])


@functools.lru_cache(maxsize=2)
def cube_directions(face_px: int) -> np.ndarray:
    """World unit direction (x, y, z up) of every texel of MuJoCo's skybox, faces stacked as
    the texture stores them: (6 face_px, face_px, 3). MuJoCo's cube faces are OpenGL's
    (+X, -X, +Y, -Y, +Z, -Z) with the texture's Y along the world's z and its Z along -y."""
    c = (np.arange(face_px, dtype=np.float32) + 0.5) / face_px * 2.0 - 1.0
    t, s = np.meshgrid(c, c, indexing="ij")
    one = np.ones_like(s)
    faces = [(one, -t, -s), (-one, -t, s), (s, one, t), (s, -one, -t), (s, -t, one),
             (-s, -t, -one)]
    gl = np.concatenate([np.stack(f, -1) for f in faces], 0)
    gl /= np.linalg.norm(gl, axis=-1, keepdims=True)
    out = np.stack([gl[..., 0], -gl[..., 2], gl[..., 1]], -1)
    out.flags.writeable = False  # cached: shared by every world
    return out


def cloud_field(rng: np.random.Generator, size: int = CLOUD_NOISE_PX) -> np.ndarray:
    """Tileable fractal noise in 0..1 (size, size) float32: octaves of random grids enlarged
    with wrapped bicubic interpolation, each half the amplitude of the one before."""
    field = np.zeros((size, size), np.float32)
    total = 0.0
    for i, cells in enumerate(CLOUD_OCTAVES):
        grid = np.pad(rng.random((cells, cells), dtype=np.float32), 2, mode="wrap")
        scale = size // cells  # wrap: enlarge the grid with 2 cells of its other side around
        big = cv2.resize(grid, ((cells + 4) * scale,) * 2, interpolation=cv2.INTER_CUBIC)
        amplitude = 0.5**i
        field += amplitude * big[2 * scale:2 * scale + size, 2 * scale:2 * scale + size]
        total += amplitude
    field /= total
    lo, hi = np.percentile(field, (1, 99))
    return np.clip((field - lo) / (hi - lo), 0.0, 1.0)


def _sample(field: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """`field` at the points (x, y), bilinear and wrapped: (N, 1) float32 (cv2.remap's maps
    must have fewer than 32767 rows, so the points go in rows of 1024)."""
    n, cols = len(x), 1024
    pad = -n % cols
    maps = [np.pad(a, (0, pad)).reshape(-1, cols).astype(np.float32) for a in (x, y)]
    out = cv2.remap(field, maps[0], maps[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)
    return out.reshape(-1)[:n, None]


def sky_texture(zenith, horizon, clouds: float, overcast: float,
                rng: np.random.Generator, face_px: int = SKY_FACE_PX) -> np.ndarray:
    """The skybox texture, uint8 (6 face_px, face_px, 3): colours 0..1 in, see the module
    docstring. `clouds`: share of the sky under cloud; `overcast`: 0 cumulus .. 1 grey deck."""
    d = cube_directions(face_px)
    above = d[..., 2] > 0.0
    d = d[above]  # only the texels above the horizon are computed
    up = d[:, 2]
    zenith, horizon = np.asarray(zenith, np.float32), np.asarray(horizon, np.float32)
    haze = np.exp(-up / np.float32(HAZE_ELEVATION))[:, None]  # 1 at the horizon, 0 high up
    clear = 1.0 - haze
    sky = horizon + (zenith - horizon) * (clear * np.sqrt(clear))  # (1 - haze)^1.5
    # The cloud deck: the ray's horizontal reach over its height, in field tiles.
    reach = np.float32(CLOUD_DECK_SCALE * CLOUD_NOISE_PX) / (up + np.float32(0.04))
    n = CLOUD_NOISE_PX
    density_field = cloud_field(rng)
    x, y = d[:, 0] * reach % n, d[:, 1] * reach % n
    density = _sample(density_field, x, y)
    shade = _sample(density_field, (x + n / 2) % n, (y + n / 3) % n)  # uncorrelated with it
    # Cover: the noise above the quantile that leaves `clouds` of the sky clouded, soft-edged.
    threshold = float(np.quantile(density_field, 1.0 - clouds)) if clouds < 1.0 else -1.0
    amount = np.clip((density - threshold) / 0.18, 0.0, 1.0)
    amount *= 1.0 - np.exp(-up[:, None] / np.float32(CLOUD_HAZE_ELEVATION))  # into the haze
    brightness = np.mean(horizon) / np.mean((0.84, 0.87, 0.90))  # the time of day's light
    top = np.asarray(FAIR_CLOUD_RGB, np.float32) * np.float32(brightness)
    fair = top * (CLOUD_BASE_SHADE + (1.0 - CLOUD_BASE_SHADE) * shade)
    deck = sky * (0.88 + 0.24 * density)  # an overcast's mottled grey
    cloud_rgb = (1.0 - overcast) * fair + overcast * deck
    day = np.float32(min(1.0, brightness / NIGHT_LIGHT))
    if day < 1.0:  # lit from below by the glow: faint, warm, mottled
        glow = horizon * np.float32(NIGHT_CLOUD_GLOW) * (0.75 + 0.5 * shade)
        cloud_rgb = day * cloud_rgb + (1.0 - day) * glow
    out = np.empty(above.shape + (3,), np.uint8)
    out[:] = np.clip(np.round(255.0 * horizon), 0, 255).astype(np.uint8)
    out[above] = np.clip(255.0 * (sky + amount * (cloud_rgb - sky)) + 0.5, 0, 255)
    return out
