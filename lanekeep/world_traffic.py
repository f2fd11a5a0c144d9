"""Other vehicles: mocap bodies moved along their lanes each control step, and how much of
the paint they hide from a camera."""


from __future__ import annotations

import math

import mujoco

from lanekeep.cameras import GROUP_WORLD
from lanekeep.road import Road
from lanekeep.scenario import VehicleSpec
from lanekeep.world_parts import (
    ConditionsInfo,
    VehicleTrack,
    yaw_quat,
)


def add_vehicle(spec: mujoco.MjSpec, road: Road, v: VehicleSpec, index: int) -> VehicleTrack:
    if not 0 <= v.lane < road.n_lanes:
        raise ValueError(
            f"conditions.vehicles[{index}].lane = {v.lane} not in 0..{road.n_lanes - 1}"
        )
    r = road.lane_center_r(v.lane) + v.offset_m
    name = f"cond_vehicle_{index}"
    x, y = road.position(v.s_m, r)
    yaw = float(road.heading_at(v.s_m)) + (math.pi if v.speed_mps < 0 else 0.0)
    body = spec.worldbody.add_body(name=name, mocap=True, pos=[x, y, 0.0], quat=yaw_quat(yaw))
    L, W, H = v.length_m, v.width_m, v.height_m  # noqa: N806
    clearance = 0.25
    lower = 0.55 * (H - clearance)
    paint = [*v.colour, 1.0]
    body.add_geom(name=f"{name}_body", type=mujoco.mjtGeom.mjGEOM_BOX, group=GROUP_WORLD,
                  pos=[0, 0, clearance + 0.5 * lower], size=[0.5 * L, 0.5 * W, 0.5 * lower],
                  rgba=paint, contype=0, conaffinity=0, mass=1.0)
    cabin = H - clearance - lower
    body.add_geom(name=f"{name}_cabin", type=mujoco.mjtGeom.mjGEOM_BOX, group=GROUP_WORLD,
                  pos=[-0.08 * L, 0, clearance + lower + 0.5 * cabin],
                  size=[0.3 * L, 0.46 * W, 0.5 * cabin],
                  rgba=[0.5 * c for c in v.colour] + [1.0], contype=0, conaffinity=0, mass=1.0)
    for j, ax in enumerate((0.32 * L, -0.32 * L)):
        body.add_geom(name=f"{name}_axle_{j}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                      group=GROUP_WORLD, pos=[ax, 0, 0.34], euler=[math.pi / 2, 0, 0],
                      size=[0.34, 0.5 * W - 0.02, 0], rgba=[0.05, 0.05, 0.05, 1.0],
                      contype=0, conaffinity=0, mass=1.0)
    return VehicleTrack(name, v.s_m, r, v.speed_mps)


def update_dynamic(world, t_s: float) -> None:
    """Move the other vehicles to their poses at sim time t_s (call every control step).

    Sets the mocap poses and runs mj_kinematics, so a render straight after sees them.
    """
    info: ConditionsInfo | None = getattr(world, "conditions", None)
    if info is None or not info.vehicles:
        return
    road, data = world.road, world.data
    for v in info.vehicles:
        if v.mocap_id < 0:
            v.mocap_id = int(world.model.body(v.name).mocapid[0])
        s = v.s_m + v.speed_mps * t_s
        data.mocap_pos[v.mocap_id, :2] = road.position(s, v.r_m)
        yaw = float(road.heading_at(s)) + (math.pi if v.speed_mps < 0 else 0.0)
        data.mocap_quat[v.mocap_id] = yaw_quat(yaw)
    mujoco.mj_kinematics(world.model, data)


def occluded_marking_share(world, rig, camera: str = "front") -> float:
    """Share of the marking pixels that the other vehicles hide in one camera (0..1).

    Renders the segmentation twice, with the vehicles in place and with them lowered 1 km
    under the ground; NaN when no marking is in view.
    """
    info: ConditionsInfo | None = getattr(world, "conditions", None)
    seen = int(world.marking_mask(rig.render_segmentation(world.data, camera)).sum())
    if info is None or not info.vehicles:
        return 0.0
    ids = [v.mocap_id if v.mocap_id >= 0 else int(world.model.body(v.name).mocapid[0])
           for v in info.vehicles]
    saved = world.data.mocap_pos.copy()
    try:
        world.data.mocap_pos[ids, 2] -= 1000.0
        mujoco.mj_kinematics(world.model, world.data)
        total = int(world.marking_mask(rig.render_segmentation(world.data, camera)).sum())
    finally:
        world.data.mocap_pos[:] = saved
        mujoco.mj_kinematics(world.model, world.data)
    return math.nan if total == 0 else 1.0 - seen / total
