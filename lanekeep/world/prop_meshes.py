"""Mesh pieces of the roadside props: boxes, vertical prisms, ellipsoids and profiles extruded
along the road, as `Ribbon` arrays (vertices, faces, texcoords) to be merged into few geoms.

Every face has its own vertices, so MuJoCo's per-vertex normals are the face normals (flat
shading, sharp box edges) and each face carries its own texture coordinates. Faces wind
counter-clockwise seen from outside: their normals point outwards (lit, not culled).
Texture coordinates are in metres divided by `uv_m`, the texture's tile size.
"""

from __future__ import annotations

import math

import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon, sample_s

# The 6 faces of a unit box as corner indices (bit 0: x, bit 1: y, bit 2: z), CCW from outside.
_BOX_FACES = ((0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (0, 1, 3, 2), (4, 6, 7, 5))


def _quads(quads: np.ndarray, uvs: np.ndarray) -> Ribbon:
    """Quads (n, 4, 3) with texcoords (n, 4, 2) as two triangles each."""
    n = len(quads)
    base = 4 * np.arange(n)[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]]).astype(np.int32)
    return Ribbon(quads.reshape(-1, 3), faces, uvs.reshape(-1, 2))


def _orient(quads: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """Quads (n, 4, 3) wound so that their normals point away from `inside` ((3,) or (n, 3))."""
    normal = np.cross(quads[:, 1] - quads[:, 0], quads[:, 2] - quads[:, 0])
    flip = np.einsum("nd,nd->n", normal, quads.mean(1) - inside) < 0.0
    quads = quads.copy()
    quads[flip] = quads[flip][:, ::-1]
    return quads


def _face_uv(quads: np.ndarray, uv_m: float) -> np.ndarray:
    """Texcoords of quads: horizontal run along the face (m) and height (m), over uv_m.

    A vertical face maps width to u and z to v (windows stand upright on a facade); a
    horizontal face maps its x, y."""
    edge = quads[:, 1] - quads[:, 0]
    out = np.zeros((*quads.shape[:2], 2))
    flat = np.abs(edge[:, 2]) > 1e-9  # first edge vertical: use the second for the run
    run_dir = np.where(flat[:, None], quads[:, 3] - quads[:, 0], edge)
    run_dir[:, 2] = 0.0
    length = np.linalg.norm(run_dir, axis=1, keepdims=True)
    vertical = length[:, 0] > 1e-9
    run_dir = np.where(vertical[:, None], run_dir / np.maximum(length, 1e-9), 0.0)
    out[..., 0] = np.einsum("nkd,nd->nk", quads - quads[:, :1], run_dir)
    out[..., 1] = quads[..., 2]
    horizontal = ~vertical | (np.ptp(quads[..., 2], axis=1) < 1e-9)
    out[horizontal] = quads[horizontal][..., :2]
    return out / uv_m


def box(centre: np.ndarray, heading: float, half: tuple[float, float, float],
        uv_m: float = 1.0, bottom: bool = True) -> Ribbon:
    """An upright box: centre (3,), turned `heading` about z, half sizes (along, across, up)."""
    c, s = math.cos(heading), math.sin(heading)
    bits = np.array([[(k >> b) & 1 for b in range(3)] for k in range(8)], float) * 2.0 - 1.0
    local = bits * np.asarray(half)
    corners = np.c_[c * local[:, 0] - s * local[:, 1], s * local[:, 0] + c * local[:, 1],
                    local[:, 2]] + np.asarray(centre, float)
    faces = _BOX_FACES if bottom else _BOX_FACES[:4] + _BOX_FACES[5:]
    quads = _orient(corners[np.array(faces)], np.asarray(centre, float))
    return _quads(quads, _face_uv(quads, uv_m))


def prism(base: np.ndarray, height_m: float, radius_m: float, sides: int = 6) -> Ribbon:
    """A vertical prism (a pole) standing on base (3,), no caps."""
    ang = np.linspace(0.0, 2 * np.pi, sides + 1)
    ring = np.c_[radius_m * np.cos(ang), radius_m * np.sin(ang), np.zeros(sides + 1)] + base
    top = ring + [0.0, 0.0, height_m]
    quads = np.stack([ring[:-1], ring[1:], top[1:], top[:-1]], 1)
    quads = _orient(quads, np.asarray(base, float) + [0.0, 0.0, 0.5 * height_m])
    return _quads(quads, _face_uv(quads, 1.0))


def ellipsoid(centre: np.ndarray, radii: tuple[float, float, float], n_lon: int = 6,
              n_lat: int = 4) -> Ribbon:
    """A low-poly ellipsoid (a crown of leaves), vertices shared (smooth shading, as a crown
    of leaves scatters light); texcoords wrap twice around and once over it."""
    centre = np.asarray(centre, float)
    lon = np.linspace(0.0, 2 * np.pi, n_lon + 1)
    lat = np.linspace(-0.5 * np.pi, 0.5 * np.pi, n_lat + 1)
    lo, la = np.meshgrid(lon, lat)
    unit = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1)
    verts = (unit * np.asarray(radii) + centre).reshape(-1, 3)
    uv = np.stack([lo / np.pi, la / np.pi + 0.5], -1).reshape(-1, 2)
    idx = np.arange(verts.shape[0]).reshape(n_lat + 1, n_lon + 1)
    # CCW seen from outside: east along a parallel, then north. The quads touching a pole
    # are triangles: their other half has zero area (no pixels, but vertex work), so it goes.
    q = np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], -1)
    lower, upper = q[..., [0, 1, 2]], q[..., [0, 2, 3]]
    faces = np.concatenate([lower[1:].reshape(-1, 3), upper[:-1].reshape(-1, 3)])
    return Ribbon(verts, faces.astype(np.int32), uv)


def extrude(road: Road, s0: float, s1: float, profile: np.ndarray, uv_m: float = 1.0,
            max_step_m: float = 6.0, slice_m: float = 12.0) -> tuple[Ribbon, list[np.ndarray]]:
    """A closed cross-section profile (k, 2) of (r, z) swept along the road from s0 to s1.

    Vertices are shared along the road (smooth there) but not across profile corners (sharp
    edges). Returns the mesh (each face turned away from the profile's centroid) and, per
    stretch of about `slice_m`, the 3D points of that piece of the body (for its shadow; on a
    curve of radius 600 m a 12 m piece's hull strays 3 cm from the curved body).
    """
    s = sample_s(road, s0, s1, max_step_m)
    n, k = len(s), len(profile)
    xy = road.position(np.repeat(s, k), np.tile(profile[:, 0], n)).reshape(n, k, 2)
    pts = np.concatenate([xy, np.broadcast_to(profile[:, 1], (n, k))[..., None]], -1)
    j = np.arange(k)
    jn = (j + 1) % k
    verts = np.stack([pts[:, j], pts[:, jn]], 2)  # (n, k, 2, 3): both ends of each edge
    depth = np.abs(profile[:, 0] - profile[:, 0].min())
    uv = np.zeros((n, k, 2, 2))
    uv[..., 0] = s[:, None, None]
    uv[..., 1] = verts[..., 2] + np.stack([depth[j], depth[jn]], 1)
    centre = np.r_[road.position(s[0], float(profile[:, 0].mean())), profile[:, 1].mean()]
    a, b = pts[0, j], pts[0, jn]
    normal = np.cross(b - a, pts[1, j] - a)
    flip = np.einsum("kd,kd->k", normal, 0.5 * (a + b) - centre) < 0.0
    idx = np.arange(n * k * 2).reshape(n, k, 2)
    q = np.stack([idx[:-1, :, 0], idx[:-1, :, 1], idx[1:, :, 1], idx[1:, :, 0]], -1)
    q[:, flip] = q[:, flip][..., ::-1]
    q = q.reshape(-1, 4)
    faces = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]).astype(np.int32)
    mesh = Ribbon(verts.reshape(-1, 3), faces, uv.reshape(-1, 2) / uv_m)
    cuts = np.unique(np.r_[np.searchsorted(s, np.arange(s0, s1, slice_m)), n - 1])
    slices = [pts[i0:i1 + 1].reshape(-1, 3) for i0, i1 in zip(cuts[:-1], cuts[1:], strict=True)]
    return mesh, slices


def hill_ring(centre_xy: np.ndarray, apron_m: float, radius_m: float, width_m: float,
              heights_m: np.ndarray) -> Ribbon:
    """A closed ring of hills around centre_xy: crest heights per angle (n,), wrapping.

    Each angle has an apron from `apron_m` (inside the ground plane, rising 0.5 m, so no sky
    shows between the plane's edge and the hills), a foot at `radius_m`, a crest and an outer
    foot; the ground plane's far edge disappears behind the hills."""
    n = len(heights_m)
    ang = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    d = np.stack([np.cos(ang), np.sin(ang)], 1)
    rows = [(apron_m, 0.0, 0.0), (radius_m, 0.0, 0.5), (radius_m + 0.45 * width_m, 1.0, 0.5),
            (radius_m + width_m, 0.6, 0.5)]
    ring = [np.c_[centre_xy + rad * d, f * heights_m + z] for rad, f, z in rows]
    quads = []
    for a, b in zip(ring[:-1], ring[1:], strict=True):
        nxt = np.roll(np.arange(n), -1)
        quads.append(np.stack([a, a[nxt], b[nxt], b], 1))
    quads = np.concatenate(quads)
    quads = _orient(quads, quads.mean(1) - [0.0, 0.0, 1.0])  # facing up
    return _quads(quads, quads[..., :2] / 40.0)


def tree_belt(centre_xy: np.ndarray, radii_m: np.ndarray, heights_m: np.ndarray,
              keep: np.ndarray, uv_m: float = 6.0, ragged: np.ndarray | None = None) -> Ribbon:
    """A belt of woodland around centre_xy, seen from inside: per angle step (n,) a vertical
    face from the ground to heights_m at radii_m, only where `keep`; faces turn inwards.

    `ragged` (n, k) splits each face into k columns whose top corners rise and fall by these
    shares of the height (the crowns of a wood's edge, not a hedge's straight top)."""
    n = len(radii_m)
    k = 1 if ragged is None else ragged.shape[1]
    ang = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    foot = centre_xy + radii_m[:, None] * np.stack([np.cos(ang), np.sin(ang)], 1)
    nxt = np.roll(np.arange(n), -1)
    i = np.flatnonzero(keep)
    f = np.arange(k + 1) / k  # column edges along a face
    a = foot[i][:, None] + f[None, :, None] * (foot[nxt[i]] - foot[i])[:, None]  # (m, k+1, 2)
    top = heights_m[i][:, None] + f[None] * (heights_m[nxt[i]] - heights_m[i])[:, None]
    if ragged is not None:
        bump = np.c_[ragged[i], ragged[nxt[i], :1]]  # a face ends where the next one starts
        top = top * (1.0 + bump)
    m = len(i)
    p0, p1 = a[:, :-1].reshape(-1, 2), a[:, 1:].reshape(-1, 2)
    t0, t1 = top[:, :-1].reshape(-1), top[:, 1:].reshape(-1)
    zero = np.zeros(m * k)
    quads = np.stack([np.c_[p0, zero], np.c_[p1, zero], np.c_[p1, t1], np.c_[p0, t0]], 1)
    run = np.hypot(*(p1 - p0).T)
    uv = np.zeros((m * k, 4, 2))
    uv[:, :, 0] = (np.cumsum(run) - run)[:, None] + np.array([0.0, 1.0, 1.0, 0.0]) * run[:, None]
    uv[:, :, 1] = quads[..., 2]
    # The first triangle's normal points outwards here (foot a, foot b, top b): reverse all.
    return _quads(quads[:, ::-1], uv[:, ::-1] / uv_m)


def cone(base: np.ndarray, height_m: float, radius_m: float, sides: int = 7) -> Ribbon:
    """An upright cone (a conifer's tier) on base (3,), with its underside: flat shaded,
    texcoords in metres around the side and up."""
    base = np.asarray(base, float)
    ang = np.linspace(0.0, 2 * np.pi, sides + 1)
    ring = np.c_[radius_m * np.cos(ang), radius_m * np.sin(ang), np.zeros(sides + 1)] + base
    apex = base + [0.0, 0.0, height_m]
    side = np.stack([ring[:-1], ring[1:], np.broadcast_to(apex, (sides, 3))], 1)
    under = np.stack([ring[1:], ring[:-1], np.broadcast_to(base, (sides, 3))], 1)
    tris = np.concatenate([side, under])  # CCW from outside: side up and out, underside down
    run = radius_m * ang
    uv_side = np.stack([np.c_[run[:-1], np.zeros(sides)], np.c_[run[1:], np.zeros(sides)],
                        np.c_[0.5 * (run[:-1] + run[1:]), np.full(sides, height_m)]], 1)
    uv = np.concatenate([uv_side, tris[sides:, :, :2] - base[:2]])
    faces = np.arange(3 * len(tris), dtype=np.int32).reshape(-1, 3)
    return Ribbon(tris.reshape(-1, 3), faces, uv.reshape(-1, 2) / 2.0)
