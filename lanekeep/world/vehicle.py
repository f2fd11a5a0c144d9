"""The car in the MuJoCo model: named state accessors and the steer/throttle interface.

The paper (001 §2.4) drives the car with a steering command in [-1, 1] and a throttle; this
module maps those to MuJoCo actuators: per-wheel Ackermann steering angles for the two front
position servos, torque on the two rear drive motors, and wheel dampers as brakes.

Vehicle ground frame (used everywhere in lanekeep): origin on the ground under the middle of
the wheelbase (the body "car"'s origin), x forward, y left, z up.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from lanekeep.geometry.car import CarGeometry

STEER_ACTUATORS = ("steer_front_left", "steer_front_right")
DRIVE_ACTUATORS = ("drive_rear_left", "drive_rear_right")
BRAKE_ACTUATORS = (
    "brake_front_left",
    "brake_front_right",
    "brake_rear_left",
    "brake_rear_right",
)
FRONT_STEER_JOINTS = ("front_left_steer", "front_right_steer")
SPIN_JOINTS = ("front_left_spin", "front_right_spin", "rear_left_spin", "rear_right_spin")


def ackermann_angles(bicycle_angle_rad: float, geometry: CarGeometry) -> tuple[float, float]:
    """Left and right road-wheel angles whose axes meet on the rear-axle line.

    tan(d_left) = L tan(d) / (L - t/2 tan(d)),  tan(d_right) = L tan(d) / (L + t/2 tan(d)).
    """
    tan_d = math.tan(bicycle_angle_rad)
    wheelbase, half_track = geometry.wheelbase_m, geometry.track_m / 2.0
    left = math.atan(wheelbase * tan_d / (wheelbase - half_track * tan_d))
    right = math.atan(wheelbase * tan_d / (wheelbase + half_track * tan_d))
    return left, right


def kinematic_turn_radius(bicycle_angle_rad: float, geometry: CarGeometry) -> float:
    """Radius (m) of the path of the rear-axle centre for a rolling car without slip."""
    return geometry.wheelbase_m / math.tan(bicycle_angle_rad)


class Car:
    """Named accessors and actuation for the car of mjcf/car.xml; ids resolved once."""

    def __init__(
        self, model: mujoco.MjModel, data: mujoco.MjData, geometry: CarGeometry | None = None
    ) -> None:
        self.model = model
        self.data = data
        self.geometry = geometry or CarGeometry()
        self._body_id = model.body("car").id
        root = model.joint("car_root")
        self._qpos_adr = int(root.qposadr[0])
        self._qvel_adr = int(root.dofadr[0])
        self._steer_ids = [model.actuator(n).id for n in STEER_ACTUATORS]
        self._drive_ids = [model.actuator(n).id for n in DRIVE_ACTUATORS]
        self._brake_ids = [model.actuator(n).id for n in BRAKE_ACTUATORS]
        self._steer_qpos = [int(model.joint(n).qposadr[0]) for n in FRONT_STEER_JOINTS]
        self._spin_dof = [int(model.joint(n).dofadr[0]) for n in SPIN_JOINTS]
        self.steer_command = 0.0
        self.throttle_command = 0.0

    # -- state -------------------------------------------------------------------------------
    def pose(self) -> tuple[float, float, float]:
        """(x, y, yaw) of the vehicle reference point in the world, metres and radians."""
        x, y = self.data.xpos[self._body_id][:2]
        rot = self.data.xmat[self._body_id].reshape(3, 3)
        return float(x), float(y), float(math.atan2(rot[1, 0], rot[0, 0]))

    def rotation(self) -> np.ndarray:
        """Body-to-world rotation matrix (3x3)."""
        return self.data.xmat[self._body_id].reshape(3, 3).copy()

    def velocity_body(self) -> np.ndarray:
        """Linear velocity of the reference point in the body frame (m/s)."""
        world_vel = self.data.qvel[self._qvel_adr : self._qvel_adr + 3]
        return self.rotation().T @ world_vel

    def acceleration_body(self) -> np.ndarray:
        """Linear acceleration of the reference point in the body frame (m/s^2), no gravity.

        The free joint's linear qacc, as MuJoCo computed it in the last physics step, is the
        derivative of its world-frame linear qvel. On flat ground the tyres' normal forces
        cancel gravity, so this is the kinematic acceleration, not an accelerometer's specific
        force (which would read +9.81 m/s^2 up).
        """
        world_acc = self.data.qacc[self._qvel_adr : self._qvel_adr + 3]
        return self.rotation().T @ world_acc

    def speed_mps(self) -> float:
        """Forward speed (m/s), negative when reversing."""
        return float(self.velocity_body()[0])

    def lateral_speed_mps(self) -> float:
        """Sideways speed in the body frame (m/s, + = left): the sideslip of a turn."""
        return float(self.velocity_body()[1])

    def yaw_rate_rps(self) -> float:
        """Yaw rate (rad/s, + = left); the free joint's angular velocity is in the body frame."""
        return float(self.data.qvel[self._qvel_adr + 5])

    def steer_angle_rad(self) -> float:
        """Bicycle-equivalent road-wheel angle from the two front steer joints."""
        left, right = (float(self.data.qpos[a]) for a in self._steer_qpos)
        # Average of cotangents gives the bicycle wheel of an exact Ackermann pair.
        tans = [math.tan(left), math.tan(right)]
        if abs(tans[0]) < 1e-9 or abs(tans[1]) < 1e-9:
            return 0.5 * (left + right)
        return math.atan(2.0 / (1.0 / tans[0] + 1.0 / tans[1]))

    # -- commands ----------------------------------------------------------------------------
    def apply(self, steer: float, throttle: float) -> None:
        """Set actuator controls from steer in [-1, 1] (+ = left) and throttle in [-1, 1].

        Throttle above zero drives the rear wheels; below zero it brakes all four wheels.
        Commands outside [-1, 1] (or NaN) are clipped (NaN counts as 0) so that a faulty
        controller cannot push the model into an invalid state.
        """
        steer = 0.0 if not math.isfinite(steer) else min(max(steer, -1.0), 1.0)
        throttle = 0.0 if not math.isfinite(throttle) else min(max(throttle, -1.0), 1.0)
        self.steer_command, self.throttle_command = steer, throttle
        left, right = ackermann_angles(steer * self.geometry.max_steer_rad, self.geometry)
        self.data.ctrl[self._steer_ids[0]] = left
        self.data.ctrl[self._steer_ids[1]] = right
        drive, brake = max(throttle, 0.0), max(-throttle, 0.0)
        for i in self._drive_ids:
            self.data.ctrl[i] = drive
        for i in self._brake_ids:
            self.data.ctrl[i] = brake

    def place(self, x: float, y: float, yaw: float, speed_mps: float = 0.0) -> None:
        """Put the car at a ground pose with a forward speed, wheels spinning to match."""
        adr = self._qpos_adr
        self.data.qpos[adr : adr + 3] = (x, y, 0.0)
        self.data.qpos[adr + 3 : adr + 7] = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        vel = self._qvel_adr
        self.data.qvel[vel : vel + 6] = 0.0
        self.data.qvel[vel : vel + 3] = (speed_mps * math.cos(yaw), speed_mps * math.sin(yaw), 0.0)
        for d in self._spin_dof:
            self.data.qvel[d] = speed_mps / self.geometry.wheel_radius_m
        mujoco.mj_forward(self.model, self.data)
