"""Lane paint that stays a line in the distance: paint drawn as a filtered texture.

Why: beyond ~30 m a 0.15 m line is less than a pixel across, and rasterised geometry (one
sample per pixel; MuJoCo's multisampling costs 2.5x a frame on a CPU) hits or misses it pixel
by pixel, so a solid line breaks into dots that change from frame to frame. For the RGB render
each strip of fresh paint is instead a ribbon SPREAD times its width, textured opaque paint in
its middle and transparent beside it. The texture's v coordinate is the same all along the
road, so MuJoCo's isotropic mip-mapping (the level follows the larger footprint, here the one
across the line) filters only across the line: a distant line fades to a faint continuous one
instead of breaking up. The thin geometry stays, for the segmentation render only, so the
marking masks are as exact as before (lanekeep/sensing/cameras.py hides each from the other render).

What MuJoCo's translucent pass does to it (mjr_render, stated where it matters):
  - translucent geoms are drawn twice (front to back, then back to front, depth writes off),
    so a filtered alpha a shows as 1 - (1 - a)^2: where a line is far thinner than a pixel it
    looks up to twice as bright as its true coverage (still far closer than hit-or-miss);
  - translucent geoms receive no shadow map (camera shadow maps are off by default; the world's
    shadows are translucent overlays);
  - the order within each pass follows distance minus bounding radius. Overlays on the road
    (shadows, puddles, snow) must be drawn after the paint, or a shadow would not darken the
    paint it falls on: `draw_overlays_last` gives each overlay mesh a tiny buried triangle far
    away, which makes it the nearest by that measure (drawn first, and last in the second
    pass). Paint under an overlay is still darkened once, not twice: a shadow that leaves 0.4
    of the light on asphalt would leave sqrt(0.4) = 0.63 on a ribbon, so paint inside a static
    cast shadow is drawn as geometry instead (world._add_markings); under moving vehicles'
    shadows the ribbons keep that error.
"""

from __future__ import annotations

import mujoco
import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon, ribbon

SPREAD = 4.0  # ribbon width / paint width: room for the mip levels to spread the line into
TEXELS = 64  # across the ribbon
PAINT_ALPHA = 0.99  # material alpha: below 0.995 puts the geom in MuJoCo's translucent pass
LIFT_M = 0.002  # above the thin paint geometry
FAR_M = 5000.0  # the ordering triangle's distance: beyond any bounding radius of the road
FAR_DEPTH_M = 50.0  # ... and this far under the ground, where no camera sees it
FAR_SIZE_M = 1e-4  # its size: no area to speak of (a moving overlay's inertia stays as it was)


def profile_rgba(texels: int = TEXELS, spread: float = SPREAD) -> np.ndarray:
    """(4, texels, 4) uint8: white paint, alpha 255 across the middle 1/spread, 0 beside it;
    the texel that the paint's edge cuts gets the share it covers (a box-filtered edge)."""
    edges = np.linspace(0.0, 1.0, texels + 1)
    lo, hi = 0.5 - 0.5 / spread, 0.5 + 0.5 / spread
    cover = np.clip(np.minimum(edges[1:], hi) - np.maximum(edges[:-1], lo), 0.0, None)
    alpha = np.round(255.0 * cover * texels).astype(np.uint8)
    out = np.full((4, texels, 4), 255, np.uint8)
    out[:, :, 3] = alpha
    return out


def add_paint_texture(spec: mujoco.MjSpec, name: str) -> None:
    rgba = profile_rgba()
    tex = spec.add_texture(name=name, type=mujoco.mjtTexture.mjTEXTURE_2D,
                           width=rgba.shape[1], height=rgba.shape[0], nchannel=4)
    tex.data = np.ascontiguousarray(rgba).tobytes()


def filtered_strip(road: Road, s_start_m: float, s_end_m: float, r_m: float, width_m: float,
                   z_m: float) -> Ribbon:
    """The RGB ribbon of one paint strip: SPREAD x width_m wide, u across it from 0 to 1,
    v constant (no footprint along the road, so the mip level follows the footprint across)."""
    half = 0.5 * width_m * SPREAD
    strip = ribbon(road, s_start_m, s_end_m, r_m - half, r_m + half, z_m + LIFT_M,
                   tile_m=1.0, max_step_m=1.0)
    uv = np.empty_like(strip.texcoords)
    uv[0::2, 0], uv[1::2, 0], uv[:, 1] = 0.0, 1.0, 0.5
    return Ribbon(strip.vertices, strip.faces, uv)


def draw_overlays_last(spec: mujoco.MjSpec, group: int, skip: set[str]) -> int:
    """Give every mesh geom of `group` (but those named in `skip`) a far, buried, tiny triangle
    so that MuJoCo draws it after the paint (see the module docstring); returns how many."""
    meshes = {m.name: m for m in spec.meshes}
    skip, done = set(skip), 0
    for geom in spec.geoms:
        if geom.group != group or geom.type != mujoco.mjtGeom.mjGEOM_MESH or geom.name in skip:
            continue
        mesh = meshes.get(geom.meshname)
        if mesh is None or mesh.name in skip:
            continue
        verts = list(mesh.uservert)
        n = len(verts) // 3
        far = [FAR_M, 0.0, -FAR_DEPTH_M, FAR_M + FAR_SIZE_M, 0.0, -FAR_DEPTH_M,
               FAR_M, FAR_SIZE_M, -FAR_DEPTH_M]
        mesh.uservert = verts + far
        mesh.userface = list(mesh.userface) + [n, n + 1, n + 2]
        if len(mesh.usertexcoord):
            mesh.usertexcoord = list(mesh.usertexcoord) + [0.0] * 6
        if len(mesh.usernormal):
            mesh.usernormal = list(mesh.usernormal) + [0.0, 0.0, 1.0] * 3
        skip.add(mesh.name)  # a mesh shared by several geoms gets one triangle
        done += 1
    return done
