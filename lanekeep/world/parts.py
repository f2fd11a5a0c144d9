"""Building blocks of the MuJoCo world that the road and the conditions both use (a leaf:
it imports nothing of the world builders, so lanekeep.world.build and lanekeep.world.conditions can
both import it without importing each other)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from lanekeep.geometry.road_mesh import Ribbon

if TYPE_CHECKING:
    from lanekeep.world.traffic_flow import TrafficPlan

# Heights of the visual layers above the contact plane (m); 1 cm apart avoids z-fighting with
# the depth-buffer resolution at 100 m (about 3 mm with znear 0.2 m).
ROAD_Z_M = 0.01
MARKING_Z_M = 0.02
OVERLAY_Z_M = 0.03  # shadows, puddles (conditions)


@dataclass(frozen=True)
class WorldLayout:
    """Sizes of what lies beside the lanes."""

    shoulder_m: float = 1.5  # asphalt beyond the outer edge line
    gravel_m: float = 1.2  # gravel strip beyond the asphalt
    tile_m: float = 4.0  # texture period of the gravel and of overlays on the road
    pavement_period_m: float = 9.0  # pavement texture period along the road (2 concrete slabs)
    texture_px: int = 1024  # pavement texture rows (along the road); half as many columns
    paint_brightness_levels: int = 4  # worn paint is quantised into this many materials
    # The road continues straight this far before s = 0 and after its end (Road.position
    # extrapolates there), so the rear camera at the start does not see the asphalt end.
    lead_m: float = 60.0


def add_texture(spec: mujoco.MjSpec, name: str, rgb: np.ndarray) -> None:
    tex = spec.add_texture(
        name=name,
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        width=rgb.shape[1],
        height=rgb.shape[0],
        nchannel=3,
    )
    tex.data = np.ascontiguousarray(rgb).tobytes()


def add_material(spec: mujoco.MjSpec, name: str, texture: str | None, **attrs) -> None:
    mat = spec.add_material(name=name, **attrs)
    if texture is not None:
        mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = texture


def add_mesh_geom(
    spec: mujoco.MjSpec, name: str, mesh: Ribbon, material: str, group: int
) -> None:
    spec.add_mesh(
        name=name,
        uservert=mesh.vertices.astype(np.float32).ravel().tolist(),
        userface=mesh.faces.ravel().tolist(),
        usertexcoord=mesh.texcoords.astype(np.float32).ravel().tolist(),
        inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL,
    )
    spec.worldbody.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname=name,
        material=material,
        contype=0,
        conaffinity=0,
        group=group,
    )


def yaw_quat(yaw: float) -> list[float]:
    """MuJoCo quaternion (w, x, y, z) of a rotation by `yaw` about z."""
    return [math.cos(yaw / 2.0), 0.0, 0.0, math.sin(yaw / 2.0)]


@dataclass
class VehicleTrack:
    """A moving occluder: mocap body `name` at Frenet (s_m + speed_mps * t, r_m)."""

    name: str
    s_m: float
    r_m: float
    speed_mps: float
    mocap_id: int = -1  # resolved on first use


@dataclass
class ConditionsInfo:
    """What add_conditions put in the world, for the episode, the tests and the reports."""

    shadow_polygons: list[np.ndarray] = field(default_factory=list)  # world XY (n, 2) each
    caster_names: list[str] = field(default_factory=list)
    bump_geoms: list[str] = field(default_factory=list)  # collision geoms of the speed bumps
    puddle_polygons: list[np.ndarray] = field(default_factory=list)
    vehicles: list[VehicleTrack] = field(default_factory=list)
    fog_visibility_m: float = math.inf
    headlights: bool = False
    street_lamps_xy: np.ndarray | None = None  # lit lamp heads, world XY (n, 2), at night
    traffic_plan: TrafficPlan | None = None  # the other vehicles and how they drive

    def shaded(self, xy: np.ndarray) -> np.ndarray:
        """Whether world points (..., 2) lie in any cast shadow."""
        xy = np.asarray(xy, dtype=float)
        flat = xy.reshape(-1, 2)
        out = np.zeros(len(flat), bool)
        for poly in self.shadow_polygons:
            # Only the points in the polygon's bounding box are tested: a world has hundreds
            # of shadows (every tree's), each covering a few of the points.
            lo, hi = poly.min(axis=0), poly.max(axis=0)
            near = np.flatnonzero(np.all((flat >= lo) & (flat <= hi), axis=1) & ~out)
            if len(near):
                out[near] = inside_convex(poly, flat[near])
        return out.reshape(xy.shape[:-1])


def inside_convex(poly: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Points inside a counter-clockwise convex polygon."""
    edges = np.roll(poly, -1, axis=0) - poly
    rel = xy[..., None, :] - poly
    cross = edges[:, 0] * rel[..., 1] - edges[:, 1] * rel[..., 0]
    return np.all(cross >= 0.0, axis=-1)
