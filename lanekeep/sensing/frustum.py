"""Which static geoms lie wholly outside a camera's view, so a render can leave them out.

Why: Mesa's llvmpipe transforms every vertex of every geom it is given on the CPU, seen or
not, and the roadside's trees are most of a world's triangles (lanekeep/world/props.py cuts
them into cells so that the ones behind or beside the camera can be skipped). A geom whose
bounding box lies wholly outside the view frustum puts no fragment in the image: MuJoCo's
shadow maps are off in every render that culls (shadows are overlays), so leaving it out
changes no pixel. The test is conservative (a box is culled only when it lies wholly beyond
one of the frustum's planes); the far plane is not used.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np


class FrustumCuller:
    """The world body's geoms as oriented boxes (their compiled AABBs), tested against a
    camera's pyramid of view. Planes (infinite boxes) are never culled."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int) -> None:
        self.model = model
        self.aspect = width / height
        on_world = (model.geom_bodyid == 0) & (model.geom_type != mujoco.mjtGeom.mjGEOM_PLANE)
        self.ids = np.flatnonzero(on_world)
        axes = np.empty((len(self.ids), 9))
        for row, g in enumerate(self.ids):  # the world body's frame is the world's
            mujoco.mju_quat2Mat(axes[row], model.geom_quat[g])
        self._axes = axes.reshape(-1, 3, 3)
        aabb = model.geom_aabb[self.ids]
        self._centres = model.geom_pos[self.ids] + np.einsum("nij,nj->ni", self._axes, aabb[:, :3])
        self._half = aabb[:, 3:]

    def outside(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """Ids of the geoms that `camera`'s render cannot show (wholly beyond a side plane
        of its frustum or behind it)."""
        cam = self.model.camera(camera).id
        origin = data.cam_xpos[cam]
        rotation = data.cam_xmat[cam].reshape(3, 3)  # camera axes (x right, y up, -z ahead)
        ty = math.tan(math.radians(self.model.cam_fovy[cam]) / 2.0)
        tx = ty * self.aspect
        # Outward normals in the camera's frame: a point p is inside when n . p <= 0.
        normals = np.array([[1.0, 0.0, tx], [-1.0, 0.0, tx], [0.0, 1.0, ty], [0.0, -1.0, ty],
                            [0.0, 0.0, 1.0]])
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        normals = normals @ rotation.T  # to the world frame
        distance = (self._centres - origin) @ normals.T  # (n geoms, 5 planes)
        # A box's reach along a normal: sum over its axes of |n . axis| * half length.
        reach = np.einsum("npj,nj->np", np.abs(np.einsum("pk,nkj->npj", normals, self._axes)),
                          self._half)
        return self.ids[(distance > reach).any(axis=1)]
