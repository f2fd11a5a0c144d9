"""Other vehicles built from MuJoCo primitives: cars, vans and trucks with wheels, wheel arches,
windows, lights, bumpers and mirrors, as plain data that lanekeep/world/traffic.py adds to a
mocap body (nothing is downloaded; a cabin is the convex hull of 8 points, a MuJoCo mesh).

Frame of every part: the vehicle's, origin on the ground (z = 0) under its middle, x forward,
y left, z up. Orientations are quaternions, never Euler angles: the world is compiled with
mjcf/car.xml's `angle="degree"`, where radians silently became 1.8 m posts through the cabins.
The kind follows from the `VehicleSpec` dimensions (`kind_of`): longer than 7 m is a truck (cab,
box body, a tandem, tri-axle beyond 13 m), taller than 1.9 m a van, anything else a car.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from lanekeep.scenario.conditions import VehicleSpec

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]

IDENTITY: Quat = (1.0, 0.0, 0.0, 0.0)
# A cylinder's axis is its local z: turn it onto the vehicle's y (-90 deg about x).
ACROSS: Quat = (math.cos(math.pi / 4), -math.sin(math.pi / 4), 0.0, 0.0)

TRUCK_MIN_LENGTH_M = 7.0
VAN_MIN_HEIGHT_M = 1.9
PROUD_M = 0.01  # panes and lights stand off their faces: no z-fighting at 100 m (~3 mm)
BODY_INSET_M = 0.06  # the body ends this far inside the vehicle's length; bumpers reach it
BUMPER_M = 0.14  # bumper depth
BEVEL_M = 0.06  # the body's top edges are stepped in by this: reads as rounded at a distance


@dataclass(frozen=True)
class Part:
    """One geom of a vehicle, in the vehicle's frame; `role` picks its material."""

    name: str  # suffix of the geom name: cond_vehicle_{i}_{name}
    shape: str  # "box", "cylinder" or "hull" (convex hull of `points`)
    role: str  # paint, trailer, glass, tyre, hub, trim, underbody, taillight, headlight, plate
    pos: Vec3 = (0.0, 0.0, 0.0)
    size: Vec3 = (0.0, 0.0, 0.0)  # box: half sizes; cylinder: (radius, half length, 0)
    quat: Quat = IDENTITY
    points: tuple[Vec3, ...] = ()

    def corners(self) -> np.ndarray:
        """Points (n, 3) whose convex hull holds the part: what its shadow is cast from."""
        if self.shape == "hull":
            return np.array(self.points, dtype=float)
        half = np.array(self.size if self.shape == "box"
                        else (self.size[0], self.size[0], self.size[1]))
        signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)])
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, np.array(self.quat, dtype=float))
        return np.array(self.pos) + (signs * half) @ rot.reshape(3, 3).T


@dataclass(frozen=True)
class CarStyle:
    """Proportions of a car or van; shares are of the vehicle's length (L) or height (H)."""

    wheel_radius_m: float
    wheel_width_m: float
    sill_m: float  # underside of the body between the wheels
    rear_overhang_z_m: float  # underside behind the rear wheels
    front_overhang_z_m: float
    belt: float  # belt line (window bottoms), share of H
    front_axle: float  # behind the front end, share of L
    rear_axle: float  # ahead of the rear end, share of L
    hood: float  # windshield base behind the front end, share of L
    deck: float  # rear window base ahead of the rear end, share of L
    windshield_run: float  # horizontal run of the windshield, share of L
    rear_run: float  # of the rear window
    cabin_width: float  # greenhouse width at the belt, share of the width
    tumblehome: float  # roof width over greenhouse width at the belt
    side_glass_m: float | None = None  # side windows behind the A-pillar; None: all along
    rear_glass: float = 1.0  # glazed share (from the top) of the rear face
    rear_doors: bool = False  # a seam down the middle of the rear


@dataclass(frozen=True)
class TruckStyle:
    """Proportions of a rigid truck: a cab at the front, a box body on a ladder frame."""

    wheel_radius_m: float = 0.5
    wheel_width_m: float = 0.3  # front axle
    dual_width_m: float = 0.5  # twin tyres on the rear axles
    cab_length_m: float = 2.3
    cab_height: float = 0.86  # share of H
    cab_belt_m: float = 1.55  # window bottoms
    cab_sill_m: float = 0.6
    glass_height_m: float = 1.0  # windshield and door windows
    box_floor_m: float = 1.15  # underside of the box, above the wheels
    gap_m: float = 0.2  # between cab and box
    front_axle_m: float = 1.35  # behind the front end
    rear_axle_m: float = 2.2  # last axle ahead of the rear end
    axle_spacing_m: float = 1.3  # within a tandem
    tri_axle_min_length_m: float = 13.0  # longer trucks get a third rear axle


CAR = CarStyle(wheel_radius_m=0.33, wheel_width_m=0.22, sill_m=0.2, rear_overhang_z_m=0.34,
               front_overhang_z_m=0.27, belt=0.57,
               front_axle=0.19, rear_axle=0.22, hood=0.28, deck=0.2, windshield_run=0.17,
               rear_run=0.12, cabin_width=0.9, tumblehome=0.88)
VAN = CarStyle(wheel_radius_m=0.36, wheel_width_m=0.24, sill_m=0.26, rear_overhang_z_m=0.42,
               front_overhang_z_m=0.33, belt=0.42,
               front_axle=0.16, rear_axle=0.2, hood=0.17, deck=0.0, windshield_run=0.1,
               rear_run=0.0, cabin_width=0.96, tumblehome=0.96, side_glass_m=1.0,
               rear_glass=0.45, rear_doors=True)
TRUCK = TruckStyle()


def kind_of(v: VehicleSpec) -> str:
    """"truck", "van" or "car", from the dimensions alone (VehicleSpec has no kind)."""
    if v.length_m > TRUCK_MIN_LENGTH_M:
        return "truck"
    return "van" if v.height_m > VAN_MIN_HEIGHT_M else "car"


def vehicle_parts(v: VehicleSpec) -> list[Part]:
    """All geoms of one vehicle, in its frame (see the module docstring)."""
    kind = kind_of(v)
    if kind == "truck":
        return _truck(v.length_m, 0.5 * v.width_m, v.height_m, TRUCK)
    return _car(v.length_m, 0.5 * v.width_m, v.height_m, CAR if kind == "car" else VAN)


# -- primitives ---------------------------------------------------------------------------------
def box(name: str, role: str, lo: Vec3, hi: Vec3) -> Part:
    """Axis-aligned box between two corners."""
    lo_a, hi_a = np.array(lo, float), np.array(hi, float)
    hi_a = np.maximum(hi_a, lo_a + 1e-3)
    centre, half = 0.5 * (lo_a + hi_a), 0.5 * (hi_a - lo_a)
    return Part(name, "box", role, _vec(centre), _vec(half))


def _vec(a: np.ndarray) -> Vec3:
    return (float(a[0]), float(a[1]), float(a[2]))


def wheels(axles_x: list[float], track_half: float, radius: float, width: float,
           first: int = 0) -> list[Part]:
    """Tyres (touching z = 0) and hub caps, two per axle; `track_half` to the tyre centres."""
    parts = []
    k = first
    for x in axles_x:
        for side in (1.0, -1.0):
            pos = (x, side * track_half, radius)
            # a 16-sided prism, not a MuJoCo cylinder (~1000 triangles: 4-6 tyres made each
            # vehicle cost 1.6 ms of a CPU render of both cameras)
            parts.append(hub(f"wheel_{k}", pos, radius, 0.5 * width, sides=16, role="tyre"))
            parts.append(hub(f"hub_{k}", pos, 0.55 * radius, 0.5 * width + 0.006))
            k += 1
    return parts


def hub(name: str, centre: Vec3, radius: float, half_width: float, sides: int = 12,
        role: str = "hub") -> Part:
    """Hub caps on both faces of a tyre: a 12-sided prism across the vehicle (a hull mesh of
    ~40 triangles: a MuJoCo cylinder has ~1000 and the hubs cost 1 ms a 720p CPU render)."""
    ang = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    x, z = centre[0] + radius * np.cos(ang), centre[2] + radius * np.sin(ang)
    return Part(name, "hull", role, points=tuple(
        (float(a), centre[1] + s * half_width, float(b)) for a, b in zip(x, z, strict=True)
        for s in (-1.0, 1.0)))


def pane(name: str, role: str, p0: tuple[float, float], p1: tuple[float, float],
         half_width: float, outward: float) -> Part:
    """Thin box on a sloped face running from p0 to p1 in the x-z plane, standing off it
    (outward = +1: the face looks forward, -1: backward)."""
    a, b = np.array(p0, float), np.array(p1, float)
    length = float(np.linalg.norm(b - a))
    u = (b - a) / length
    normal = outward * np.array([u[1], -u[0]])  # the box's local x: (u_z, -u_x), outward
    centre = 0.5 * (a + b) + normal * (PROUD_M - 0.005)
    phi = math.atan2(u[0], u[1])  # about y: local z onto u
    return Part(name, "box", role, (float(centre[0]), 0.0, float(centre[1])),
                (0.005, half_width, 0.5 * length), (math.cos(phi / 2), 0.0, math.sin(phi / 2), 0.0))


# -- assemblies ---------------------------------------------------------------------------------
def lower_body(x0: float, x1: float, hw: float, z0: float, z1: float, arches_x: list[float],
               radius: float, core_hw: float,
               overhang_z0: tuple[float, float] | None = None) -> list[Part]:
    """The body below the windows, with a wheel arch over each axle: full-width skins between
    the arches, a strip over them, a dark narrow core behind the arches, a bevel on top.
    Beyond the outer arches the underside may rise to `overhang_z0` (rear, front): the
    departure and approach angles that let a camera behind a car see its tyres."""
    arch_half, arch_top = radius + 0.07, 2.0 * radius + 0.06
    top = z1 - BEVEL_M
    rear_z0, front_z0 = overhang_z0 or (z0, z0)
    core_x0 = max(x0 + 0.05, min(arches_x) - arch_half - 0.02)
    core_x1 = min(x1 - 0.05, max(arches_x) + arch_half + 0.02)
    parts = [box("underbody", "underbody", (core_x0, -core_hw, z0), (core_x1, core_hw, top))]
    edges = [x0]
    for ax in sorted(arches_x):
        edges += [max(x0, ax - arch_half), min(x1, ax + arch_half)]
    edges.append(x1)
    segments = list(zip(edges[::2], edges[1::2], strict=True))
    for j, (a, b) in enumerate(segments):
        bottom = rear_z0 if j == 0 else front_z0 if j == len(segments) - 1 else z0
        if b - a > 0.02:
            parts.append(box(f"body_{j}", "paint", (a, -hw, bottom), (b, hw, top)))
    if arch_top < top:
        parts.append(box("body_over_arches", "paint", (x0, -hw, arch_top), (x1, hw, top)))
    parts.append(box("body_shoulder", "paint", (x0 + BEVEL_M, -hw + BEVEL_M, top),
                     (x1 - BEVEL_M, hw - BEVEL_M, z1)))
    return parts


@dataclass(frozen=True)
class Greenhouse:
    """The cabin above the belt line: front and rear faces may slope (x at base and top)."""

    front_base: float
    front_top: float
    rear_base: float
    rear_top: float
    z0: float
    z1: float
    hw_base: float
    hw_top: float
    side_glass_m: float | None = None
    glass_height_m: float | None = None  # glazed height above the belt; None: all of it
    rear_glass: float = 1.0


def greenhouse(g: Greenhouse) -> list[Part]:
    """Painted cabin hull with dark panes: windshield, rear window, side windows (one hull
    standing off both sides) and, for long side glass, B-pillars."""
    pts = tuple((x, s * hw, z) for x, z, hw in ((g.front_base, g.z0, g.hw_base),
                                               (g.front_top, g.z1, g.hw_top),
                                               (g.rear_base, g.z0, g.hw_base),
                                               (g.rear_top, g.z1, g.hw_top)) for s in (-1, 1))
    parts = [Part("cabin", "hull", "paint", points=pts)]
    height = g.z1 - g.z0
    lo, hi = 0.05, min(height - 0.06, g.glass_height_m or height)
    pillar = 0.09
    glass_hw = min(g.hw_base, g.hw_top) - pillar

    def along(base: float, top: float, z: float) -> float:
        return base + (top - base) * (z - g.z0) / height

    front = ((g.front_base, g.z0), (g.front_top, g.z1))
    parts.append(_face_pane("window_front", front, lo, hi, height, glass_hw, 1.0))
    if g.rear_glass > 0.0:
        rear = ((g.rear_base, g.z0), (g.rear_top, g.z1))
        rear_lo = max(lo, height - 0.06 - g.rear_glass * (height - 0.11))
        parts.append(_face_pane("window_rear", rear, rear_lo, height - 0.06, height, glass_hw,
                                -1.0))
    side = []
    for z in (g.z0 + lo, g.z0 + hi):
        x_front = along(g.front_base, g.front_top, z) - pillar
        x_rear = along(g.rear_base, g.rear_top, z) + 1.6 * pillar
        if g.side_glass_m is not None:
            x_rear = max(x_rear, along(g.front_base, g.front_top, g.z0 + hi) - pillar
                         - g.side_glass_m)
        y = along(g.hw_base, g.hw_top, z) + PROUD_M
        side += [(x, s * y, z) for x in (x_front, x_rear) for s in (-1, 1)]
    parts.append(Part("window_sides", "hull", "glass", points=tuple(side)))
    if g.side_glass_m is None and g.front_top - g.rear_top > 0.8:
        parts += _b_pillars(g, lo, hi, along)
    return parts


def _face_pane(name: str, face: tuple, lo: float, hi: float, height: float, half_width: float,
               outward: float) -> Part:
    """Pane on a cabin face between heights lo and hi above the belt."""
    (xb, zb), (xt, zt) = face
    p0 = (xb + (xt - xb) * lo / height, zb + lo)
    p1 = (xb + (xt - xb) * hi / height, zb + hi)
    return pane(name, "glass", p0, p1, half_width, outward)


def _b_pillars(g: Greenhouse, lo: float, hi: float, along) -> list[Part]:
    """Painted posts between the door windows, leaning in with the tumblehome."""
    x = 0.5 * (along(g.front_base, g.front_top, g.z0 + hi) + along(g.rear_base, g.rear_top,
                                                                   g.z0 + hi))
    lean = math.atan2(g.hw_base - g.hw_top, g.z1 - g.z0)
    z = g.z0 + 0.5 * (lo + hi)
    y = along(g.hw_base, g.hw_top, z) + PROUD_M + 0.004
    size = (0.05, 0.008, 0.5 * (hi - lo) + 0.01)
    return [Part(f"pillar_{j}", "box", "paint", (x, s * y, z), size,
                 (math.cos(s * lean / 2), math.sin(s * lean / 2), 0.0, 0.0))
            for j, s in enumerate((1.0, -1.0))]


def lights_and_bumpers(x_rear: float, x_front: float, hw: float,
                       bumper_z: tuple[tuple[float, float], tuple[float, float]],
                       lamp_z: float) -> list[Part]:
    """Bumpers (out to the vehicle's ends, BODY_INSET_M beyond the body), number plates, tail
    and head lights standing off the body's end faces."""
    (r0, r1), (f0, f1) = bumper_z
    rm, fm = 0.5 * (r0 + r1), 0.5 * (f0 + f1)
    back, ahead = x_rear - BODY_INSET_M, x_front + BODY_INSET_M
    parts = [box("bumper_rear", "trim", (back, -hw + 0.03, r0), (back + BUMPER_M, hw - 0.03, r1)),
             box("bumper_front", "trim", (ahead - BUMPER_M, -hw + 0.03, f0),
                 (ahead, hw - 0.03, f1)),
             box("plate_rear", "plate", (back - PROUD_M, -0.26, rm - 0.06),
                 (back, 0.26, rm + 0.06)),
             box("plate_front", "plate", (ahead, -0.26, fm - 0.06),
                 (ahead + PROUD_M, 0.26, fm + 0.06))]
    for j, s in enumerate((1.0, -1.0)):
        y0, y1 = sorted((s * (hw - 0.34), s * (hw - 0.06)))
        parts.append(box(f"taillight_{j}", "taillight", (x_rear - 2 * PROUD_M, y0, lamp_z - 0.06),
                         (x_rear + 0.005, y1, lamp_z + 0.06)))
        parts.append(box(f"headlight_{j}", "headlight", (x_front - 0.005, y0, lamp_z - 0.05),
                         (x_front + 2 * PROUD_M, y1, lamp_z + 0.05)))
    return parts


def mirrors(x: float, hw: float, z: float, size: Vec3, role: str = "paint") -> list[Part]:
    """Door mirrors standing out of the sides."""
    return [Part(f"mirror_{j}", "box", role, (x, s * (hw + size[1]), z), size)
            for j, s in enumerate((1.0, -1.0))]


def _car(L: float, hw: float, H: float, st: CarStyle) -> list[Part]:  # noqa: N803
    r = min(st.wheel_radius_m, 0.25 * H, 0.09 * L)
    ww = min(st.wheel_width_m, 0.15 * hw * 2)
    sill = min(st.sill_m, 0.6 * r)
    belt = float(np.clip(st.belt * H, sill + 0.2, H - 0.25))
    x0, x1 = -0.5 * L + BODY_INSET_M, 0.5 * L - BODY_INSET_M
    axles = [0.5 * L - st.front_axle * L, -0.5 * L + st.rear_axle * L]
    parts = wheels(axles, hw - 0.5 * ww - 0.02, r, ww)
    lamp_z = belt - BEVEL_M - 0.08
    ends = tuple(max(sill, min(z, lamp_z - 0.3))
                 for z in (st.rear_overhang_z_m, st.front_overhang_z_m))
    parts += lower_body(x0, x1, hw, sill, belt, axles, r, hw - ww - 0.06, ends)
    hw_base = st.cabin_width * hw
    front_base = x1 - st.hood * L + 0.06
    rear_base = x0 + st.deck * L
    parts += greenhouse(Greenhouse(
        front_base=front_base, front_top=front_base - st.windshield_run * L,
        rear_base=rear_base, rear_top=rear_base + st.rear_run * L, z0=belt, z1=H,
        hw_base=hw_base, hw_top=st.tumblehome * hw_base, side_glass_m=st.side_glass_m,
        rear_glass=st.rear_glass))
    parts += lights_and_bumpers(x0, x1, hw, tuple((z - 0.02, z + 0.22) for z in ends), lamp_z)
    parts += mirrors(front_base - 0.08, hw, belt + 0.08, (0.05, 0.07, 0.05))
    if st.rear_doors:
        parts.append(box("door_seam", "trim", (x0 - 0.004, -0.008, ends[0] + 0.05),
                         (x0 + 0.004, 0.008, H - 0.05)))
    return parts


def truck_axles(L: float, st: TruckStyle) -> list[float]:  # noqa: N803
    """Front axle, then the rear group (a tandem; three axles on long trucks)."""
    n = 3 if L > st.tri_axle_min_length_m else 2
    last = -0.5 * L + st.rear_axle_m
    return [0.5 * L - st.front_axle_m] + [last + k * st.axle_spacing_m for k in range(n)]


def _truck(L: float, hw: float, H: float, st: TruckStyle) -> list[Part]:  # noqa: N803
    r = min(st.wheel_radius_m, 0.2 * H)
    axles = truck_axles(L, st)
    parts = wheels(axles[:1], hw - 0.5 * st.wheel_width_m - 0.03, r, st.wheel_width_m)
    parts += wheels(axles[1:], hw - 0.5 * st.dual_width_m - 0.03, r, st.dual_width_m, first=2)
    x_front = 0.5 * L - BODY_INSET_M
    cab_rear = 0.5 * L - st.cab_length_m
    cab_top = max(st.cab_height * H, st.cab_belt_m + 0.6)
    box_floor = min(st.box_floor_m, 0.5 * H)
    parts += lower_body(cab_rear, x_front, hw, st.cab_sill_m, st.cab_belt_m, axles[:1], r,
                        hw - st.wheel_width_m - 0.08)
    parts += greenhouse(Greenhouse(
        front_base=x_front - 0.04, front_top=x_front - 0.3, rear_base=cab_rear,
        rear_top=cab_rear, z0=st.cab_belt_m, z1=cab_top, hw_base=hw - 0.03, hw_top=hw - 0.08,
        side_glass_m=1.0, glass_height_m=st.glass_height_m, rear_glass=0.0))
    box_rear = -0.5 * L + BODY_INSET_M
    parts.append(box("cargo", "trailer", (box_rear, -hw, box_floor),
                     (cab_rear - st.gap_m, hw, H)))
    parts.append(box("cargo_rail", "trim", (box_rear, -hw - 0.01, box_floor),
                     (cab_rear - st.gap_m, hw + 0.01, box_floor + 0.14)))
    parts.append(box("door_seam", "trim", (box_rear - 0.006, -0.01, box_floor + 0.14),
                     (box_rear, 0.01, H - 0.05)))
    frame_hw = hw - st.dual_width_m - 0.1
    parts.append(box("frame", "underbody", (box_rear + 0.1, -frame_hw, 0.7),
                     (cab_rear + 0.3, frame_hw, box_floor)))
    parts += _truck_guards(axles, hw, r)
    lamp_z = st.cab_sill_m + 0.45
    parts += lights_and_bumpers(box_rear, x_front, hw, ((0.4, 0.75), (0.4, 0.75)), lamp_z)
    parts += mirrors(x_front - 0.35, hw + 0.05, st.cab_belt_m + 0.35, (0.04, 0.06, 0.25), "trim")
    return [_lower_rear_lights(p, box_floor) for p in parts]


def _truck_guards(axles: list[float], hw: float, r: float) -> list[Part]:
    """Side guards between the front wheels and the rear group (the rear bumper is the
    underrun bar)."""
    a, b = axles[0] - r - 0.15, min(axles[1:]) + r + 0.15
    return [box("guard_left", "trim", (b, hw - 0.04, 0.55), (a, hw, 0.7)),
            box("guard_right", "trim", (b, -hw, 0.55), (a, -hw + 0.04, 0.7))]


def _lower_rear_lights(p: Part, box_floor: float) -> Part:
    """A truck's tail lights sit on the box's bottom edge, not on a car's belt line."""
    if not p.name.startswith("taillight"):
        return p
    return Part(p.name, p.shape, p.role, (p.pos[0], p.pos[1], box_floor + 0.1), p.size)
