"""The world as dm_control sees it: a `dm_control.mujoco.Physics` over a built world's own
MuJoCo model and data (shared, not copied), with named accessors for the car, as dm_control's
suite writes one per task (`cartpole.Physics.cart_position()`).

Built on an existing world rather than from XML because the world is compiled from an MjSpec
(lanekeep/world/build.py); dm_control takes the raw data through `wrapper.MjData(data)`.
`legacy_step = False`: a step is MuJoCo's own `mj_step` n times, exactly what `World.step`
does, so the two step the same bits.
"""

from __future__ import annotations

import numpy as np
from dm_control import mujoco as dm_mujoco
from dm_control.mujoco.wrapper import MjData

from lanekeep.world.build import World, physics_steps
from lanekeep.world.vehicle import FRONT_STEER_JOINTS, SPIN_JOINTS


class LaneKeepPhysics(dm_mujoco.Physics):
    """Named access to the car's state in a lanekeep world."""

    legacy_step = False

    @classmethod
    def of(cls, world: World) -> LaneKeepPhysics:
        """The physics of `world` (the same MjData: what one steps, the other sees)."""
        return cls(MjData(world.data))

    def car_position(self) -> np.ndarray:
        """The car's body origin (middle of the wheelbase, on the ground) in the world, m."""
        return self.named.data.xpos["car"].copy()

    def car_yaw_rad(self) -> float:
        rot = self.named.data.xmat["car"].reshape(3, 3)
        return float(np.arctan2(rot[1, 0], rot[0, 0]))

    def car_speed_mps(self) -> float:
        """Forward speed, m/s: the free joint's world-frame linear velocity along the car's
        heading (negative when reversing)."""
        rot = self.named.data.xmat["car"].reshape(3, 3)
        return float(rot[:, 0] @ self.named.data.qvel["car_root"][:3])

    def steer_angles_rad(self) -> np.ndarray:
        """The front wheels' steering joint angles (left, right), rad, + = left."""
        return self.named.data.qpos[list(FRONT_STEER_JOINTS)].copy()

    def wheel_speeds_rps(self) -> np.ndarray:
        """The four wheels' spin rates, rad/s, in SPIN_JOINTS' order."""
        return self.named.data.qvel[list(SPIN_JOINTS)].copy()

    def sub_steps(self, period_s: float) -> int:
        """Physics steps per control period (a whole number, or ValueError)."""
        return physics_steps(period_s, float(self.model.opt.timestep))
