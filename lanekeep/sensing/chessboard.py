"""Chessboards rendered by the simulator's own cameras, for calibration checks.

A flat, emissive chessboard (a textured quad on a mocap body) is placed in front of an
onboard camera at a set of seeded poses; OpenCV's calibration on those renders must recover
the intrinsics that MuJoCo's `fovy` implies. Emissive so that lighting cannot blur corners.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from lanekeep.geometry.camera_model import CameraModel
from lanekeep.mjcf import SCENE_XML
from lanekeep.scenario.camera import CameraConfig
from lanekeep.sensing.cameras import CameraRig, RenderSettings


@dataclass(frozen=True)
class Board:
    """A chessboard with `cols` x `rows` inner corners (OpenCV's pattern size)."""

    cols: int = 9
    rows: int = 6
    square_m: float = 0.12
    margin_squares: int = 1
    px_per_square: int = 32

    def object_points(self) -> np.ndarray:
        """Inner-corner positions (rows*cols, 3) on the board plane, OpenCV's order."""
        grid = np.mgrid[0 : self.cols, 0 : self.rows].T.reshape(-1, 2)
        pts = np.zeros((self.cols * self.rows, 3), np.float32)
        pts[:, :2] = grid * self.square_m
        return pts

    def texture(self) -> np.ndarray:
        """RGB image of the board: (cols+1) x (rows+1) squares with a white margin."""
        nx, ny, m, p = self.cols + 1, self.rows + 1, self.margin_squares, self.px_per_square
        cells = (np.add.outer(np.arange(ny), np.arange(nx)) % 2 == 0).astype(np.uint8)
        img = np.kron(1 - cells, np.ones((p, p), np.uint8)) * 255
        img = np.pad(img, m * p, constant_values=255)
        return np.repeat(img[..., None], 3, axis=2)

    @property
    def size_m(self) -> tuple[float, float]:
        return (
            (self.cols + 1 + 2 * self.margin_squares) * self.square_m,
            (self.rows + 1 + 2 * self.margin_squares) * self.square_m,
        )


def _board_spec(board: Board, width: int, height: int) -> mujoco.MjSpec:
    spec = mujoco.MjSpec.from_file(str(SCENE_XML))
    spec.visual.global_.offwidth = max(width, 1280)
    spec.visual.global_.offheight = max(height, 720)
    rgb = board.texture()
    tex = spec.add_texture(
        name="chessboard", type=mujoco.mjtTexture.mjTEXTURE_2D,
        width=rgb.shape[1], height=rgb.shape[0], nchannel=3,
    )
    tex.data = rgb.tobytes()
    mat = spec.add_material(name="chessboard", emission=1.0, specular=0.0)
    mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "chessboard"
    w, h = board.size_m
    # Quad in the body's xy plane, normal +z; texture v runs along -y so the image is upright.
    verts = [0, 0, 0, w, 0, 0, w, -h, 0, 0, -h, 0]
    spec.add_mesh(
        name="chessboard", uservert=verts, userface=[0, 2, 1, 0, 3, 2],
        usertexcoord=[0, 0, 1, 0, 1, 1, 0, 1],
        inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL,
    )
    body = spec.worldbody.add_body(name="chessboard", mocap=True)
    body.explicitinertial = True
    body.mass = 1.0
    body.inertia = [0.1, 0.1, 0.1]
    body.add_geom(
        name="chessboard", type=mujoco.mjtGeom.mjGEOM_MESH, meshname="chessboard",
        material="chessboard", contype=0, conaffinity=0, density=0.0,
    )
    return spec


def _look_at_quat(normal_toward: np.ndarray, roll: float) -> np.ndarray:
    """Quaternion whose +z axis points along `normal_toward`, rolled about it."""
    z = normal_toward / np.linalg.norm(normal_toward)
    helper = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    c, s = math.cos(roll), math.sin(roll)
    x, y = c * x + s * y, -s * x + c * y
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.stack([x, y, z], axis=1).ravel())
    return quat


def render_chessboards(
    n_views: int = 12,
    camera: str = "front",
    width: int = CameraConfig.width,
    height: int = CameraConfig.height,
    seed: int = 0,
    board: Board | None = None,
) -> tuple[list[np.ndarray], CameraModel]:
    """Renders of a chessboard at `n_views` seeded poses in view of `camera`.

    Returns the RGB images and the camera model (its K is what calibration should recover).
    """
    board = board or Board()
    model = _board_spec(board, width, height).compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rng = np.random.default_rng(seed)
    images = []
    with CameraRig(model, RenderSettings(width, height)) as rig:
        cam = rig.cameras[camera]
        w, h = board.size_m
        for _ in range(n_views):
            # A point on the optical axis, shifted across the image, 2.5-4.5 m away.
            dist = rng.uniform(2.5, 4.5)
            u = rng.uniform(0.3, 0.7) * width
            v = rng.uniform(0.3, 0.7) * height
            ray = cam.pixel_rays(np.array([u, v]))
            ray /= np.linalg.norm(ray)
            centre_vehicle = cam.position_m + dist * ray
            tilt = rng.normal(0.0, 0.35, size=3)
            normal = -ray + 0.6 * np.cross(ray, tilt)
            quat = _look_at_quat(normal, rng.uniform(-0.4, 0.4))
            rot = np.zeros(9)
            mujoco.mju_quat2Mat(rot, quat)
            rot = rot.reshape(3, 3)
            # The board's origin is its top-left corner; centre it on the chosen point.
            origin = centre_vehicle - rot @ np.array([w / 2.0, -h / 2.0, 0.0])
            data.mocap_pos[0] = origin  # the car sits at the world origin, so frames coincide
            data.mocap_quat[0] = quat
            mujoco.mj_forward(model, data)
            images.append(rig.render_rgb(data, camera))
    return images, cam


def find_corners(image: np.ndarray, board: Board | None = None) -> np.ndarray | None:
    """Sub-pixel inner corners (N, 1, 2) float32, or None if the board is not found."""
    import cv2

    board = board or Board()
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    found, corners = cv2.findChessboardCorners(grey, (board.cols, board.rows))
    if not found:
        return None
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 40, 1e-3)
    return cv2.cornerSubPix(grey, corners, (7, 7), (-1, -1), criteria)
