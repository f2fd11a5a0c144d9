"""The two onboard cameras in MuJoCo: their camera models read from the compiled model, rendering.

MuJoCo cameras look along their local -z with +y up and square pixels; the vertical field of
view `fovy` fixes the focal length: fy = (H/2) / tan(fovy/2) = fx. The principal point is the
image centre, (W-1)/2, (H-1)/2 in OpenCV's pixel-centre convention. Real cameras (for
`lanekeep detect`) are built from calibrated intrinsics and a mounting height and pitch.
Simulated cameras' poses are read from the compiled model relative to the body "car", whose
frame is the vehicle ground frame (origin on the ground under the middle of the wheelbase,
x forward, y left, z up), so the projection here and the render always agree.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from lanekeep.core.busy import all_cores_busy
from lanekeep.geometry.lens import Lens, is_distorted
from lanekeep.scenario.camera import CameraConfig
from lanekeep.sensing.frustum import FrustumCuller
from lanekeep.sensing.gl_backend import RendererUnavailable
from lanekeep.sensing.weather import needs_depth
from lanekeep.world.camera_mount import camera_from_model
from lanekeep.world.groups import (
    GROUP_CAR_BODY,
    GROUP_HOOD,
    GROUP_MARKING_LABEL,
    GROUP_RGB_OVERLAY,
    GROUP_UNSEEN,
)


@dataclass(frozen=True)
class RenderSettings:
    """What the renderer draws. The image size, shadows and hood default to the scenario's
    `[camera]` defaults (lanekeep/scenario/camera.py `CameraConfig`, their one definition):
    a rig built without a scenario renders what a default scenario's does."""

    width: int = CameraConfig.width
    height: int = CameraConfig.height
    shadows: bool = CameraConfig.shadows
    # MuJoCo fog. Scenes without fog put it beyond the far plane (world_conditions), where it
    # changes no pixel; turning it off there saves ~5% of a render (41.5 vs 39.4 ms a pair).
    fog: bool = True
    show_hood: bool = CameraConfig.show_hood  # the front camera sees the car's hood (GROUP_HOOD)
    # Read the depth buffer of each colour render (for depth-aware weather; about 3 ms a
    # frame). Episodes turn it on for fog and rain and then do the fog in image space
    # (lanekeep/sensing/weather.py), with MuJoCo's linear fog off.
    depth: bool = False
    # OpenCV lens distortion (k1, k2, p1, p2, k3) per camera name, applied to every render
    # (lanekeep/geometry/lens.py); a camera not named, or all zero: a pinhole.
    distortion: tuple[tuple[str, tuple[float, ...]], ...] = ()
    # Leave out the static geoms wholly outside the camera's view (lanekeep/sensing/frustum.py):
    # the same pixels, fewer vertices for the software renderer. Off only to measure it, and
    # with MuJoCo's shadow maps (a geom out of view may cast a shadow into it).
    cull: bool = True

    @classmethod
    def of(cls, scenario, width: int | None = None, height: int | None = None
           ) -> RenderSettings:
        """The settings a scenario's cameras render with (its size unless given)."""
        depth = needs_depth(scenario.conditions)
        return cls(width or scenario.camera.width, height or scenario.camera.height,
                   scenario.camera.shadows, fog=scenario.conditions.fog > 0.0 and not depth,
                   show_hood=scenario.camera.show_hood, depth=depth,
                   distortion=(("front", tuple(scenario.camera.distortion)),
                               ("rear", tuple(scenario.camera.rear_distortion))))


class CameraRig:
    """One reused `mujoco.Renderer` for both cameras; RGB and segmentation renders.

    The ego car's body and tyres are hidden (group 2) as on AirSim's onboard cameras, except its
    hood (group 4) on the front camera when `show_hood` is set (it hides paint there in the
    segmentation too); the segmentation render hides the translucent shadow geoms so the
    marking masks are exact.
    Call `close()` (or use as a context manager): EGL teardown at interpreter exit is noisy.
    """

    CAMERA_NAMES = ("front", "rear")

    def __init__(self, model: mujoco.MjModel, settings: RenderSettings | None = None) -> None:
        self.model = model
        self.settings = settings or RenderSettings()
        w, h = self.settings.width, self.settings.height
        if w > model.vis.global_.offwidth or h > model.vis.global_.offheight:
            raise ValueError(
                f"render size {w}x{h} exceeds the model's offscreen buffer "
                f"{model.vis.global_.offwidth}x{model.vis.global_.offheight}"
            )
        self.cameras = {n: camera_from_model(model, n, w, h) for n in self.CAMERA_NAMES}
        # With a lens, the delivered images and cameras are the distorted ones (lens.py).
        self.lenses: dict[str, Lens] = {n: Lens(self.cameras[n], d)
                                        for n, d in self.settings.distortion if is_distorted(d)}
        self.cameras.update({n: lens.camera for n, lens in self.lenses.items()})
        try:
            # One renderer (one GL context, the world's textures uploaded once) for both
            # cameras: every render sets its camera, options and flags anew.
            shared = mujoco.Renderer(model, height=h, width=w)
        except Exception as exc:  # noqa: BLE001 - any GL failure means the same thing to a user
            raise RendererUnavailable(str(exc)) from exc
        self._renderers = {n: shared for n in self.CAMERA_NAMES}
        self._rgb_option, self._seg_option = {}, {}
        for name in self.CAMERA_NAMES:
            rgb, seg = mujoco.MjvOption(), mujoco.MjvOption()
            for option in (rgb, seg):
                option.geomgroup[GROUP_CAR_BODY] = 0
                option.geomgroup[GROUP_HOOD] = int(self.settings.show_hood and name == "front")
            rgb.geomgroup[GROUP_RGB_OVERLAY], rgb.geomgroup[GROUP_MARKING_LABEL] = 1, 0
            seg.geomgroup[GROUP_RGB_OVERLAY], seg.geomgroup[GROUP_MARKING_LABEL] = 0, 1
            self._rgb_option[name], self._seg_option[name] = rgb, seg
        self._culler = (FrustumCuller(model, w, h)
                        if self.settings.cull and not self.settings.shadows else None)
        self._depth_raw = np.empty((h, w), np.float32)
        extent = model.stat.extent
        self._znear = np.float32(model.vis.map.znear * extent)
        self._zfar = np.float32(model.vis.map.zfar * extent)
        self._closed = False

    def distortion(self, camera: str) -> np.ndarray | None:
        """A camera's lens coefficients (OpenCV), for its detectors; None for a pinhole."""
        lens = self.lenses.get(camera)
        return None if lens is None else lens.coefficients.copy()

    def _update_scene(self, renderer: mujoco.Renderer, data: mujoco.MjData, camera: str,
                      option: mujoco.MjvOption) -> None:
        """The renderer's scene for `camera`, without the geoms it cannot see: they are moved
        to the group no render draws while MuJoCo collects the scene, then put back."""
        if self._culler is None:
            renderer.update_scene(data, camera=camera, scene_option=option)
            return
        hidden = self._culler.outside(data, camera)
        groups = self.model.geom_group[hidden].copy()
        self.model.geom_group[hidden] = GROUP_UNSEEN
        try:
            renderer.update_scene(data, camera=camera, scene_option=option)
        finally:
            self.model.geom_group[hidden] = groups

    def render_rgb(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """RGB uint8 image (H, W, 3) of one camera."""
        renderer = self._renderers[camera]
        renderer.disable_segmentation_rendering()
        self._update_scene(renderer, data, camera, self._rgb_option[camera])
        renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = self.settings.shadows
        renderer.scene.flags[mujoco.mjtRndFlag.mjRND_FOG] = self.settings.fog
        with all_cores_busy():  # background work waits (lanekeep/core/busy.py)
            rgb = renderer.render()
        lens = self.lenses.get(camera)
        return rgb if lens is None else lens(rgb)

    def render_rgb_depth(self, data: mujoco.MjData, camera: str, step_px: int = 4
                         ) -> tuple[np.ndarray, np.ndarray]:
        """RGB (H, W, 3) and the z-depth in metres of the same pass at every `step_px`-th
        pixel (rows and columns from step_px // 2), read from the depth buffer (~3 ms)."""
        rgb = self.render_rgb(data, camera)
        renderer = self._renderers[camera]
        with all_cores_busy():  # background work waits (lanekeep/core/busy.py)
            mujoco.mjr_readPixels(None, self._depth_raw, renderer._rect, renderer._mjr_context)
        # The buffer is bottom-up and in reversed-Z (as mujoco.Renderer linearises it).
        raw = self._depth_raw[::-1]
        if camera in self.lenses:
            raw = self.lenses[camera](np.ascontiguousarray(raw), nearest=True)
        raw = raw[step_px // 2::step_px, step_px // 2::step_px]
        near, far = self._znear, self._zfar
        c = np.float32(0.5) * (far + near) / (far - near) - np.float32(0.5)
        d = far * near / (far - near)
        return rgb, (d / (raw.astype(np.float64) + c)).astype(np.float32)

    def render_segmentation(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """Geom id per pixel (H, W) int32, -1 where no geom (sky)."""
        renderer = self._renderers[camera]
        renderer.enable_segmentation_rendering()
        try:
            self._update_scene(renderer, data, camera, self._seg_option[camera])
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_FOG] = False  # ids must stay exact
            with all_cores_busy():  # background work waits (lanekeep/core/busy.py)
                seg = renderer.render()
        finally:
            renderer.disable_segmentation_rendering()
        ids = seg[..., 0].astype(np.int32)
        ids[seg[..., 1] != int(mujoco.mjtObj.mjOBJ_GEOM)] = -1
        if camera in self.lenses:  # ids survive float32 exactly; nearest never mixes two
            ids = self.lenses[camera](ids.astype(np.float32), nearest=True).astype(np.int32)
        return ids

    def close(self) -> None:
        """Free the renderers. `mujoco.Renderer.close()` frees its GL objects in whatever
        context is current, which may be another open rig's (their ids coincide): that rig
        then renders with deleted textures. Each renderer's own context is made current first."""
        if not self._closed:
            for renderer in {id(r): r for r in self._renderers.values()}.values():
                if renderer._gl_context is not None:
                    renderer._gl_context.make_current()
                renderer.close()
            self._closed = True

    def __enter__(self) -> CameraRig:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
