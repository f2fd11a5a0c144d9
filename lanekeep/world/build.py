"""Builds the MuJoCo world of a scenario with `mujoco.MjSpec`: the car, road, markings, sky.

The car comes from mjcf/car.xml; everything else is added procedurally:
  - the road surface: one textured mesh per road segment (asphalt or concrete with joints,
    cracks, patches, tyre marks, tar lines, seams and sections of another surface:
    lanekeep/world/pavement.py),
    gravel shoulders, and a grass ground plane that also carries the tyre contacts;
  - lane markings: one mesh geom per boundary, road segment and paint brightness, so that the
    segmentation render gives exact per-boundary masks (`World.marking_boundary[geom_id]`);
    fresh paint strips are drawn in the RGB render as filtered ribbons instead
    (lanekeep/world/paint.py: a distant line stays a line);
  - lights, a gradient sky and fog as lanekeep/world/appearance.py decides from the scenario.
Road and markings are visual only (contype 0): the flat ground plane carries the car, since
MuJoCo collides meshes by their convex hull, which for a curved ribbon is meaningless.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass, field

import mujoco
import numpy as np

from lanekeep.geometry.lens import is_distorted, lens_zoom
from lanekeep.geometry.markings import MarkingPiece
from lanekeep.geometry.road import Road
from lanekeep.geometry.road_mesh import Ribbon, ribbon
from lanekeep.mjcf import CAR_XML
from lanekeep.scenario.schema import Scenario, ScenarioError
from lanekeep.traffic.constant import ConstantFlow
from lanekeep.traffic.flow import TrafficFlow
from lanekeep.world import paint as paint_filter
from lanekeep.world import pavement, textures
from lanekeep.world.appearance import MODEL_EXTENT_M, Lighting, appearance_of
from lanekeep.world.camera_mount import apply_camera_mount, front_and_rear
from lanekeep.world.compiled import COMPILED_WORLDS, Compiled, world_key
from lanekeep.world.conditions import add_conditions
from lanekeep.world.groups import (
    GROUP_MARKING,
    GROUP_MARKING_LABEL,
    GROUP_RGB_OVERLAY,
    GROUP_UNSEEN,
    GROUP_WORLD,
)
from lanekeep.world.parts import (
    MARKING_Z_M,
    ROAD_Z_M,
    ConditionsInfo,
    WorldLayout,
    add_material,
    add_mesh_geom,
    add_texture,
)
from lanekeep.world.pavement import LANE_U, SLAB_M
from lanekeep.world.sky import sky_generator, sky_texture
from lanekeep.world.street_lights import update_pools
from lanekeep.world.traffic import make_flow, update_dynamic
from lanekeep.world.vehicle import Car

# The ground plane's rendering grid (a plane geom's third size). MuJoCo lights per vertex and
# draws a plane as a grid of quads, up to a few hundred a side: at 0.1 m spacing that grid cost
# 11 ms of CPU in a 38 ms front render (tools/profile_render.py). Under directional light only
# (sun, MuJoCo's headlight) every vertex of a flat plane is lit alike, so a coarse grid changes
# no pixel beyond rasterisation rounding (at most 2 DN on 0.4% of a frame); a spot light (the
# car's headlamps at night) lights the grass by its vertices, so there the grid stays fine.
GROUND_GRID_M = 50.0
GROUND_GRID_LIT_M = 0.1
PAVEMENT_SEED = 0x9A5E  # the pavement texture's own generator: [scenario seed, this]
PAINT_SEED = 0x9A17  # the worn paint texture's
PAINT_SHADE_STEP_M = 0.5  # how finely a paint strip is checked against the cast shadows
DOT_HEIGHT_M = 0.015  # a Botts' dot's dome above the paint layer
DOT_ALBEDO = 0.75  # a ceramic Botts' dot, cleaner and brighter than road paint
REFLECTOR_HEIGHT_M = 0.018  # a raised reflective marker's height above the paint layer
REFLECTOR_SLOPE_M = 0.035  # how far its reflective faces slope in, along the road
REFLECTOR_ALBEDO = 0.8  # its plastic body
OTHER_SURFACE_SEED = 1  # [scenario seed, PAVEMENT_SEED, this]: the other surface's texture
SECTIONS_SEED = 2  # ... and where its sections lie
PAINT_WEAR_SHIFT = 0.37  # each boundary reads the paint's wear texture this far along (v)


@dataclass
class World:
    """A compiled scenario: MuJoCo model and data, the car, the road, marking ids."""

    scenario: Scenario
    road: Road
    model: mujoco.MjModel
    data: mujoco.MjData
    car: Car
    marking_boundary: np.ndarray  # geom id -> boundary index, -1 for non-marking geoms
    conditions: ConditionsInfo | None = None  # conditions hook: what world_conditions added
    layout: WorldLayout = field(default_factory=WorldLayout)  # what build() laid beside the lanes
    traffic: TrafficFlow | ConstantFlow | None = None  # drives the other vehicles (None: none)

    def reset(self) -> None:
        """Put the car at the scenario's start pose and speed, everything else at rest."""
        mujoco.mj_resetData(self.model, self.data)
        if self.traffic is not None:
            self.traffic.reset()
        x, y, yaw = self.scenario.start_pose(self.road)
        self.car.place(x, y, yaw, self.scenario.start.speed_mps)
        self.car.apply(0.0, 0.0)
        update_pools(self)

    def step(self, steer: float, throttle: float, seconds: float, move_scene: bool = True
             ) -> None:
        """Apply the command and advance the world by `seconds`: the car's physics, then (with
        `move_scene`; the caller does it otherwise) the other vehicles to their state at the
        new time (so the next render sees them).

        Raises SimulationError when MuJoCo found the state unstable (NaN, inf or huge
        positions, velocities or accelerations): it then resets the data to the model's
        initial state, and going on would score a teleported car."""
        self.car.apply(steer, throttle)
        before = _instability_count(self.data)
        for _ in range(physics_steps(seconds, self.model.opt.timestep)):
            mujoco.mj_step(self.model, self.data)
        if _instability_count(self.data) != before:
            raise SimulationError(
                f"MuJoCo found the simulation unstable by t = {self.data.time:.2f} s "
                f"(bad position, velocity or acceleration) and reset it")
        if move_scene:
            self.move_scene()

    def move_scene(self) -> None:
        """The other vehicles and the lamps' pools to their state at the data's time (after
        the car's physics moved it; dm_control's Task calls it in `after_step`)."""
        update_dynamic(self, self.data.time)
        update_pools(self)

    def marking_mask(self, segmentation: np.ndarray, boundary: int | None = None) -> np.ndarray:
        """Boolean mask of marking pixels (of one boundary, or of any) in a geom-id image."""
        lookup = np.append(self.marking_boundary, -1)  # index -1 (sky) maps to -1
        boundaries = lookup[segmentation]
        return boundaries >= 0 if boundary is None else boundaries == boundary


def _add_environment(spec: mujoco.MjSpec, road: Road, scenario: Scenario,
                     lighting: Lighting) -> None:
    """Sky, sun, headlight, fog, clip planes, ground plane."""
    spec.stat.extent = MODEL_EXTENT_M
    spec.stat.center = [0.0, 0.0, 0.0]
    spec.visual.map.znear = 0.002  # x extent = 0.2 m
    spec.visual.map.zfar = 10.0  # x extent = 1 km
    spec.visual.map.fogstart, spec.visual.map.fogend = lighting.fog_start, lighting.fog_end
    spec.visual.rgba.fog = [*lighting.sky_horizon, 1.0]
    spec.visual.rgba.haze = [*lighting.sky_horizon, 1.0]
    spec.visual.quality.shadowsize = 2048
    spec.visual.quality.offsamples = scenario.camera.antialias_samples
    spec.visual.headlight.ambient = [lighting.headlight_ambient] * 3
    spec.visual.headlight.diffuse = [lighting.headlight_diffuse] * 3
    spec.visual.headlight.specular = [0.0, 0.0, 0.0]
    sky = sky_texture(lighting.sky_zenith, lighting.sky_horizon, lighting.clouds,
                      lighting.overcast, sky_generator(scenario.seed, scenario.name))
    texture = spec.add_texture(name="sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                               width=sky.shape[1], height=sky.shape[0], nchannel=3)
    texture.data = sky.tobytes()
    spec.worldbody.add_light(
        name="sun",
        type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
        pos=[0.0, 0.0, 100.0],
        dir=list(lighting.sun_dir),
        diffuse=list(lighting.sun_diffuse),
        ambient=list(lighting.sun_ambient),
        specular=[lighting.sun_specular] * 3,
        castshadow=scenario.camera.shadows,
    )
    # Ground plane around the whole road; it carries the tyre contacts.
    ends = road.position(np.linspace(0.0, road.length_m, 64))
    centre = ends.mean(axis=0)
    half = float(np.max(np.abs(ends - centre))) + 200.0
    spec.worldbody.add_geom(
        name="ground",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        pos=[float(centre[0]), float(centre[1]), 0.0],
        size=[half, half, GROUND_GRID_M],  # the cameras draw a copy (_draw_ground_last)
        material="grass",
        condim=3,
        friction=[1.0, 0.005, 0.0001],
        group=GROUP_WORLD,
    )


def _atlas_strip(road: Road, s0: float, s1: float, r0: float, r1: float, u0: float,
                 u1: float, v_shift: float, layout: WorldLayout,
                 grid_step_m: float | None) -> Ribbon:
    """A ribbon from r0 to r1 whose texture u runs from u0 to u1 (a part of the pavement atlas)
    and v = s / period + v_shift; with per-vertex spot lighting, a grid of strips `grid_step_m`
    wide, each cut at most twice as long."""
    lo, hi = min(r0, r1), max(r0, r1)
    n_strips = 1 if grid_step_m is None else max(1, math.ceil((hi - lo) / grid_step_m))
    cuts = np.linspace(lo, hi, n_strips + 1)
    step = 2.0 if grid_step_m is None else 2.0 * grid_step_m
    strips = []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        strip = ribbon(road, s0, s1, a, b, ROAD_Z_M, tile_m=1.0, max_step_m=step)
        r, s = strip.texcoords[:, 0], strip.texcoords[:, 1]  # metres (tile 1 m)
        uv = np.stack([u0 + (u1 - u0) * (r - r0) / (r1 - r0),
                       s / layout.pavement_period_m + v_shift], 1)
        strips.append(Ribbon(strip.vertices, strip.faces, uv))
    return Ribbon.concatenate(strips)


def _asphalt_mesh(road: Road, s0: float, s1: float, layout: WorldLayout,
                  grid_step_m: float | None) -> Ribbon:
    """One segment's pavement: each lane and each shoulder mapped onto its part of the atlas
    (lanekeep/world/pavement.py). Lanes start the texture one slab apart, so neighbours differ while
    concrete's transverse joints still run straight across the road."""
    slab_v = SLAB_M / layout.pavement_period_m
    edge_right, edge_left = road.boundary_r(0), road.boundary_r(road.n_lanes)
    strips = [  # shoulders: u = LANE_U at the edge line, 1 at the outer side
        _atlas_strip(road, s0, s1, edge_right, edge_right - layout.shoulder_m, LANE_U, 1.0,
                     0.0, layout, grid_step_m),
        _atlas_strip(road, s0, s1, edge_left, edge_left + layout.shoulder_m, LANE_U, 1.0,
                     slab_v * road.n_lanes, layout, grid_step_m),
    ]
    for lane in range(road.n_lanes):
        strips.append(_atlas_strip(road, s0, s1, road.boundary_r(lane),
                                   road.boundary_r(lane + 1), 0.0, LANE_U, slab_v * lane,
                                   layout, grid_step_m))
    return Ribbon.concatenate(strips)


def _surface_pieces(road: Road, layout: WorldLayout) -> list[tuple[float, float]]:
    """The road's segments, with the straight lead before s = 0 and after the end."""
    bounds = road.segment_bounds()
    if layout.lead_m <= 0.0:
        return bounds
    return [(-layout.lead_m, 0.0), *bounds, (road.length_m, road.length_m + layout.lead_m)]


def _cut(s0: float, s1: float, other: list[tuple[float, float]]
         ) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """[s0, s1) cut into the pieces of the road's own surface and those of `other` sections."""
    own, theirs, s = [], [], s0
    for a, b in other:
        a, b = max(a, s0), min(b, s1)
        if b <= a:
            continue
        if a > s:
            own.append((s, a))
        theirs.append((a, b))
        s = b
    if s < s1:
        own.append((s, s1))
    return own, theirs


def _add_road_surface(spec: mujoco.MjSpec, road: Road, layout: WorldLayout,
                      grid_step_m: float | None,
                      other: list[tuple[float, float]] | None = None) -> None:
    """Asphalt and gravel ribbons, one mesh per road segment for each; the sections `other`
    (s intervals, sorted) of another surface (pavement.sections) are cut out of them and
    merged into one mesh of the material "asphalt_other"."""
    edge_right, edge_left = road.boundary_r(0), road.boundary_r(road.n_lanes)
    asphalt_right, asphalt_left = edge_right - layout.shoulder_m, edge_left + layout.shoulder_m
    theirs: list[Ribbon] = []
    for i, (s0, s1) in enumerate(_surface_pieces(road, layout)):
        own, cut = _cut(s0, s1, other or [])
        theirs += [_asphalt_mesh(road, a, b, layout, grid_step_m) for a, b in cut]
        if own:
            asphalt = Ribbon.concatenate([_asphalt_mesh(road, a, b, layout, grid_step_m)
                                          for a, b in own])
            add_mesh_geom(spec, f"road_{i}", asphalt, "asphalt", GROUP_WORLD)
        gravel = Ribbon.concatenate(
            [
                ribbon(road, s0, s1, asphalt_right - layout.gravel_m, asphalt_right, ROAD_Z_M,
                       layout.tile_m),
                ribbon(road, s0, s1, asphalt_left, asphalt_left + layout.gravel_m, ROAD_Z_M,
                       layout.tile_m),
            ]
        )
        add_mesh_geom(spec, f"shoulder_{i}", gravel, "gravel", GROUP_WORLD)
    if theirs:
        add_mesh_geom(spec, "road_other", Ribbon.concatenate(theirs), "asphalt_other",
                      GROUP_WORLD)


def _dot_mesh(road: Road, piece: MarkingPiece, sides: int = 8) -> Ribbon:
    """A raised pavement marker: a low dome (a fan of `sides` triangles around a raised
    centre), which catches the light as a ceramic Botts' dot does."""
    radius = piece.width_m / 2.0
    s_mid = 0.5 * (piece.s_start_m + piece.s_end_m)
    ang = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    s = np.r_[s_mid, s_mid + radius * np.cos(ang)]
    r = np.r_[piece.r_m, piece.r_m + radius * np.sin(ang)]
    z = np.r_[MARKING_Z_M + DOT_HEIGHT_M, np.full(sides, MARKING_Z_M)]
    verts = np.c_[road.position(s, r), z]
    k = np.arange(1, sides + 1)
    faces = np.stack([np.zeros(sides, int), k, np.roll(k, -1)], 1).astype(np.int32)
    uv = np.c_[r - piece.r_m, s - s_mid] / piece.width_m
    return Ribbon(verts, faces, uv)


def _reflector_mesh(road: Road, piece: MarkingPiece) -> Ribbon:
    """A raised reflective pavement marker: a square block of side `piece.width_m`,
    REFLECTOR_HEIGHT_M high, whose faces towards and away from the traffic slope (the
    reflectors) and whose sides are steep."""
    a, b = 0.5 * piece.width_m, 0.5 * piece.width_m
    a_top, b_top = a - REFLECTOR_SLOPE_M, b - 0.25 * REFLECTOR_SLOPE_M
    s_mid = 0.5 * (piece.s_start_m + piece.s_end_m)
    ds = np.array([-a, a, a, -a, -a_top, a_top, a_top, -a_top])
    dr = np.array([-b, -b, b, b, -b_top, -b_top, b_top, b_top])
    z = np.r_[np.full(4, MARKING_Z_M), np.full(4, MARKING_Z_M + REFLECTOR_HEIGHT_M)]
    verts = np.c_[road.position(s_mid + ds, piece.r_m + dr), z]
    faces = [[4, 5, 6], [4, 6, 7]]  # the top; then each side, outwards (CCW seen from out)
    for i in range(4):
        j = (i + 1) % 4
        faces += [[i, j, 4 + j], [i, 4 + j, 4 + i]]
    uv = np.c_[dr, ds] / piece.width_m + 0.5
    return Ribbon(verts, np.asarray(faces, np.int32), uv)


def _in_cast_shadow(road: Road, pieces: list[MarkingPiece], conditions: ConditionsInfo
                    ) -> np.ndarray:
    """Per paint strip, whether any of it lies in a static cast shadow (zones, props), sampled
    along its centre line every PAINT_SHADE_STEP_M; all strips' points tested in one pass over
    the shadow polygons."""
    if not conditions.shadow_polygons or not pieces:
        return np.zeros(len(pieces), bool)
    counts = [max(2, int(math.ceil((p.s_end_m - p.s_start_m) / PAINT_SHADE_STEP_M)) + 1)
              for p in pieces]
    s = np.concatenate([np.linspace(p.s_start_m, p.s_end_m, n)
                        for p, n in zip(pieces, counts, strict=True)])
    r = np.repeat([p.r_m for p in pieces], counts)
    inside = conditions.shaded(road.position(s, r))
    return np.logical_or.reduceat(inside, np.cumsum([0, *counts[:-1]]))


def _add_markings(
    spec: mujoco.MjSpec, road: Road, layout: WorldLayout, conditions: ConditionsInfo,
    seed: int = 0, surface: float = paint_filter.ROAD_ALBEDO,
    sections: tuple[list[tuple[float, float]], float] | None = None,
) -> tuple[dict[str, int], set[str]]:
    """Marking meshes grouped by (boundary, segment, brightness level); returns name ->
    boundary, and the names of the colour render's own paint geoms. Paint strips are geometry
    for the segmentation only (GROUP_MARKING_LABEL) and, for the colour render
    (GROUP_RGB_OVERLAY), a translucent copy: a filtered ribbon for fresh paint (lanekeep/world/
    paint.py: soft edges, seeded fading along the road), the strip itself with the worn paint
    texture (flaked off in ragged pits, the asphalt showing) for faded levels, or, inside a
    static cast shadow, an opaque copy of the geometry. Raised dots are geometry in both
    renders (GROUP_MARKING), and so are raised reflective markers (one geom per boundary,
    `_reflector_mesh`): both are their boundary's marking in the masks, as a dataset's labels
    run the lane through them. The masks mark the whole strip; which of its pixels a camera
    shows as paint is for lanekeep/sensing/paint_visibility.py to say. `surface`: the grey of the
    carriageway (lanekeep/world/pavement.surface_albedo), which faded paint fades towards.
    `sections`: the s intervals of the road's sections of another surface and that surface's
    grey; paint strips are cut at their ends, and the pieces on a section get materials
    composed against its grey (geoms and materials named with an "_o"), as a line painted
    across a concrete bridge is lighter than the slab, not darker.

    Why shaded paint stays opaque geometry: MuJoCo draws translucent geoms twice, and a
    shadow overlay drawn after them darkens them once where it darkens the asphalt twice
    (paint_filter): a ribbon in shade would keep sqrt(0.3) = 0.55 of its light where the
    asphalt keeps 0.3, and shaded lines would stand out as they do not on a real road.
    Moving vehicles' shadows are not known here; under them the ribbons keep that error. The
    segmentation meshes do not depend on the shadows, so the masks are the same with or
    without them."""
    styles = road.markings
    other, other_surface = sections or ([], surface)
    greys = (surface, other_surface)  # per colour key's last field: 0 the road's, 1 a section's
    groups: dict[tuple[int, int, int], list[Ribbon]] = {}  # the masks' geometry, uncut
    translucent: dict[tuple[int, int, int, int], list[Ribbon]] = {}
    shaded: dict[tuple[int, int, int, int], list[Ribbon]] = {}
    dots: set[tuple[int, int, int]] = set()
    reflectors: dict[int, list[Ribbon]] = {}  # per boundary: one geom for the whole road
    bounds = road.segment_bounds()
    starts = np.array([b[0] for b in bounds])
    levels = layout.paint_brightness_levels
    pieces = road.marking_pieces(layout.lead_m)
    in_shadow = _in_cast_shadow(road, pieces, conditions)
    for piece, shade in zip(pieces, in_shadow, strict=True):
        if piece.reflector:
            reflectors.setdefault(piece.boundary, []).append(_reflector_mesh(road, piece))
            continue
        segment = int(np.searchsorted(starts, piece.s_start_m, side="right") - 1)
        level = int(np.clip(round(piece.brightness * (levels - 1)), 0, levels - 1))
        key, half = (piece.boundary, segment, level), piece.width_m / 2.0
        if piece.dot:
            groups.setdefault(key, []).append(_dot_mesh(road, piece))
            dots.add(key)
            continue
        groups.setdefault(key, []).append(ribbon(
            road, piece.s_start_m, piece.s_end_m, piece.r_m - half, piece.r_m + half,
            MARKING_Z_M, tile_m=1.0, max_step_m=1.0))
        for on_section, spans in enumerate(_cut(piece.s_start_m, piece.s_end_m, other)):
            for s0, s1 in spans:
                if shade or level < levels - 1:
                    strip = groups[key][-1] if (s0, s1) == (piece.s_start_m, piece.s_end_m) \
                        else ribbon(road, s0, s1, piece.r_m - half, piece.r_m + half,
                                    MARKING_Z_M, tile_m=1.0, max_step_m=1.0)
                else:
                    strip = paint_filter.filtered_strip(
                        road, s0, s1, piece.r_m, piece.width_m, MARKING_Z_M,
                        v_shift=PAINT_WEAR_SHIFT * piece.boundary)
                (shaded if shade else translucent).setdefault(
                    (*key, on_section), []).append(strip)
    paint_filter.add_paint_texture(spec, "paint_filtered",
                                   np.random.default_rng([seed, PAINT_SEED, 1]))
    paint_filter.add_worn_texture(spec, "paint_worn_rgba",
                                  np.random.default_rng([seed, PAINT_SEED, 2]))
    names: dict[str, int] = {}
    colour_only: set[str] = set()
    materials = {m.name for m in spec.materials}

    def material(name: str, texture: str, rgb: list[float], alpha: float = 1.0) -> str:
        if name not in materials:
            add_material(spec, name, texture, rgba=[*rgb, alpha], specular=0.2, shininess=0.3)
            materials.add(name)
        return name

    def paint_material(key: tuple[int, int, int, int], kind: str) -> str:
        """The colour render's material of one colour key: "" (opaque), "_rgb" (the
        translucent copy) or "_shaded" (fresh paint's opaque copy in a cast shadow)."""
        boundary, _, level, on_section = key
        grey, fresh = greys[on_section], level == levels - 1
        rgb = paint_filter.paint_rgb(np.asarray(styles[boundary].colour),
                                     0.35 + 0.65 * level / max(levels - 1, 1), grey)
        name = f"paint_b{boundary}_l{level}{'_o' if on_section else ''}"
        if kind == "_rgb":
            return material(f"{name}_rgb", "paint_filtered" if fresh else "paint_worn_rgba",
                            rgb, paint_filter.PAINT_ALPHA)
        if kind == "_shaded" and fresh:
            return material(f"{name}_shaded", "paint", paint_filter.shaded_rgb(rgb, grey))
        return material(name, "paint" if fresh else "paint_worn", rgb)

    for key, strips in sorted(groups.items()):
        boundary, segment, level = key
        name = f"marking_b{boundary}_s{segment}_l{level}"
        names[name] = boundary
        if key in dots:  # ceramic: brighter than paint, in both renders
            add_mesh_geom(spec, name, Ribbon.concatenate(strips),
                          material(f"paint_b{boundary}_dot", "paint",
                                   list(DOT_ALBEDO * np.asarray(styles[boundary].colour))),
                          GROUP_MARKING)
            continue
        add_mesh_geom(spec, name, Ribbon.concatenate(strips), paint_material((*key, 0), ""),
                      GROUP_MARKING_LABEL)
        for on_section, tag in enumerate(("", "_o")):
            colour_key = (*key, on_section)
            for copies, kind in ((translucent, "_rgb"), (shaded, "_shaded")):
                if colour_key in copies:
                    geom = f"{name}{tag}{kind}_rgb" if kind == "_shaded" else f"{name}{tag}_rgb"
                    add_mesh_geom(spec, geom, Ribbon.concatenate(copies[colour_key]),
                                  paint_material(colour_key, kind), GROUP_RGB_OVERLAY)
                    colour_only.add(geom)
    for boundary, blocks in sorted(reflectors.items()):
        name = f"marking_b{boundary}_reflectors"
        names[name] = boundary  # a boundary's marking, in both renders (as Botts' dots)
        add_mesh_geom(spec, name, Ribbon.concatenate(blocks),
                      material(f"paint_b{boundary}_reflector", "paint",
                               list(REFLECTOR_ALBEDO * np.asarray(styles[boundary].colour))),
                      GROUP_MARKING)
    return names, colour_only


def laid_layout(road: Road, layout: WorldLayout | None = None) -> WorldLayout:
    """The layout build() lays for `road` (the default unless one is given): a track has no
    lead, since its start and end meet and a lead would lie across it."""
    layout = layout or WorldLayout()
    if road.closed:
        layout = dataclasses.replace(layout, lead_m=0.0)
    return layout


def build_spec(
    scenario: Scenario, road: Road, layout: WorldLayout | None = None
) -> tuple[mujoco.MjSpec, dict[str, int], ConditionsInfo]:
    """The scenario's MjSpec, the marking geom names with their boundary index, and what the
    scenario's conditions added (lanekeep/world/conditions.py)."""
    layout = laid_layout(road, layout)
    spec = mujoco.MjSpec.from_file(str(CAR_XML))
    spec.modelname = f"lanekeep_{scenario.name}"
    spec.visual.global_.offwidth = max(scenario.camera.width, 1280)
    spec.visual.global_.offheight = max(scenario.camera.height, 720)
    rng = np.random.default_rng(scenario.seed)
    add_texture(spec, "asphalt", pavement.pavement(
        np.random.default_rng([scenario.seed, PAVEMENT_SEED]), scenario.road.pavement,
        road.lane_width_m, layout.shoulder_m, layout.pavement_period_m, layout.texture_px))
    style = scenario.road.pavement
    other = pavement.sections(
        np.random.default_rng([scenario.seed, PAVEMENT_SEED, SECTIONS_SEED]),
        -layout.lead_m, road.length_m + layout.lead_m, style.surface_changes)
    if other:
        add_texture(spec, "asphalt_other", pavement.pavement(
            np.random.default_rng([scenario.seed, PAVEMENT_SEED, OTHER_SURFACE_SEED]),
            pavement.section_style(style), road.lane_width_m, layout.shoulder_m,
            layout.pavement_period_m, layout.texture_px))
    add_texture(spec, "gravel", textures.gravel(rng))
    add_texture(spec, "grass", textures.grass(rng))
    add_texture(spec, "paint", textures.paint(rng))
    add_texture(spec, "paint_worn", textures.worn_paint(np.random.default_rng([scenario.seed,
                                                                               PAINT_SEED])))
    look = appearance_of(scenario, road)
    surf = look.surfaces
    add_material(spec, "asphalt", "asphalt", rgba=list(surf.asphalt_rgba),
                 specular=surf.asphalt_specular, shininess=surf.asphalt_shininess)
    if other:
        add_material(spec, "asphalt_other", "asphalt_other", rgba=list(surf.asphalt_rgba),
                     specular=surf.asphalt_specular, shininess=surf.asphalt_shininess)
    add_material(spec, "gravel", surf.verge_texture_gravel, rgba=list(surf.gravel_rgba),
                 specular=0.0)
    add_material(spec, "grass", surf.verge_texture_grass, texrepeat=[150.0, 150.0],
                 specular=0.0)
    _add_environment(spec, road, scenario, look.lighting)
    _add_road_surface(spec, road, layout, look.asphalt_grid_step_m, other)
    conditions = add_conditions(spec, scenario, road, layout)  # first: its cast shadows
    marking_names, ribbons = _add_markings(
        spec, road, layout, conditions, scenario.seed, pavement.surface_albedo(style),
        (other, pavement.surface_albedo(pavement.section_style(style))))
    paint_filter.draw_overlays_last(spec, GROUP_RGB_OVERLAY, ribbons)
    _draw_ground_last(spec)
    return spec, marking_names, conditions


def _draw_ground_last(spec: mujoco.MjSpec) -> None:
    """The cameras' ground: a visual copy of the contact plane, added after everything else.

    MuJoCo draws opaque geoms in model order; drawn first, the ground was shaded under every
    road, shoulder and prop pixel and then painted over. Drawn last, the depth test rejects
    those pixels before shading: the same frame (no pixel differs) for 3-6 ms less CPU a
    render (tools/profile_render.py). The contact plane keeps its place (geom 0, so the
    physics is untouched) in a group neither camera draws. Its grid is fine only where a local
    light (spot or point) lights it per vertex (see GROUND_GRID_M).
    """
    ground = spec.geom("ground")
    local = any(light.type != mujoco.mjtLightType.mjLIGHT_DIRECTIONAL for light in spec.lights)
    grid = GROUND_GRID_LIT_M if local else GROUND_GRID_M
    spec.worldbody.add_geom(name="ground_visual", type=mujoco.mjtGeom.mjGEOM_PLANE,
                            pos=list(ground.pos), size=[ground.size[0], ground.size[1], grid],
                            material=ground.material, contype=0, conaffinity=0,
                            group=GROUP_WORLD)
    ground.group = GROUP_UNSEEN


# "conditions.vehicles[1].lane = 5 not in 0..1", "conditions.shadows[0]: with this sun ...":
# a build-time message that starts with the key it is about.
_KEYED_MESSAGE = re.compile(r"(?P<key>[A-Za-z_]\w*(?:\[\d+\])*(?:\.[A-Za-z_]\w*(?:\[\d+\])*)*)"
                            r"\s*[:=]\s*(?P<message>.+)", re.DOTALL)


def scenario_error(scenario: Scenario, err: ValueError) -> ScenarioError:
    """A ValueError raised while building `scenario`'s world as the ScenarioError that names
    the scenario's file and, where the message starts with one, the key."""
    text = str(err)
    match = _KEYED_MESSAGE.fullmatch(text)
    key, message = (match["key"], match["message"]) if match else ("", text)
    return ScenarioError(scenario.source or scenario.name, key, message)


def _check_control_period(scenario: Scenario, timestep: float) -> None:
    """ValueError unless the control period is a whole number of physics steps."""
    try:
        physics_steps(scenario.control_period_s, timestep)
    except ValueError:
        raise ValueError(
            f"control_period_s = {scenario.control_period_s} is not an integer multiple of "
            f"the physics timestep {timestep} s"
        ) from None


def check_buildable(scenario: Scenario) -> None:
    """The checks across a scenario's fields that `build` makes, in 30-160 ms instead of its
    1-2 s: the build's own code on the bare car (the road, the conditions and props added to
    the car's MjSpec: speed bumps beyond the road, vehicles in a lane that does not exist,
    shadows the sun cannot cast, a sign beyond the road) and the control period against the
    physics timestep. The world's part of the one validation path (lanekeep/loop/checks.py
    `check_scenario`, which run, bench, sweep and falsify call); a caller that renders worlds
    without driving them (the datasets) calls this part alone.

    Raises:
      ScenarioError: naming the scenario's file and key.
    """
    try:
        road = scenario.build_road()
        spec = mujoco.MjSpec.from_file(str(CAR_XML))
        add_conditions(spec, scenario, road)
        _check_control_period(scenario, spec.option.timestep)
    except ScenarioError:
        raise
    except ValueError as err:
        raise scenario_error(scenario, err) from err


def build(scenario: Scenario, layout: WorldLayout | None = None) -> World:
    """Compile a scenario into a ready-to-step World with the car at its start pose.

    A scenario built before in this process starts from a copy of that build's compiled
    model (lanekeep/world/compiled.py): the same world, in milliseconds.

    Raises:
      ScenarioError: a check across the scenario's fields failed (a speed bump beyond the
        road's end, a vehicle in a lane that does not exist, shadows the sun cannot cast, a
        control period that is no whole number of physics steps).
    """
    try:
        road = scenario.build_road()
        key = world_key(scenario, layout)
        compiled = COMPILED_WORLDS.take(key)
        if compiled is None:
            compiled = _compile(scenario, road, layout)
            COMPILED_WORLDS.keep(key, compiled)
        model, marking_names, conditions = compiled.model, compiled.marking_names, \
            compiled.conditions
        traffic = make_flow(conditions.traffic_plan if conditions else None, road)
    except ScenarioError:
        raise
    except ValueError as err:
        raise scenario_error(scenario, err) from err
    marking_boundary = np.full(model.ngeom, -1, dtype=np.int32)
    for name, boundary in marking_names.items():
        marking_boundary[model.geom(name).id] = boundary
    data = mujoco.MjData(model)
    world = World(scenario, road, model, data, Car(model, data), marking_boundary, conditions,
                  laid_layout(road, layout), traffic)
    world.reset()
    return world


def _compile(scenario: Scenario, road: Road, layout: WorldLayout | None) -> Compiled:
    """The scenario's compiled model with its cameras mounted, the marking geoms' boundaries
    and what the conditions added (raises ValueError on a check across fields)."""
    spec, marking_names, conditions = build_spec(scenario, road, layout)
    model = spec.compile()
    apply_camera_mount(model, scenario.camera)
    cameras = front_and_rear(model, scenario.camera.width, scenario.camera.height)
    for name, coefficients in (("front", scenario.camera.distortion),
                               ("rear", scenario.camera.rear_distortion)):
        if is_distorted(coefficients):  # a folding lens, named before any render
            lens_zoom(cameras[name], coefficients)
    _check_control_period(scenario, model.opt.timestep)
    return Compiled(model, marking_names, conditions)


class SimulationError(RuntimeError):
    """The physics went unstable; the episode cannot go on."""


UNSTABLE_WARNINGS = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                     mujoco.mjtWarning.mjWARN_BADQACC)


def _instability_count(data: mujoco.MjData) -> int:
    return sum(int(data.warning[w].number) for w in UNSTABLE_WARNINGS)


def physics_steps(seconds: float, timestep: float) -> int:
    """How many physics steps make `seconds`; ValueError unless a whole number (>= 1)."""
    ratio = seconds / timestep
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        raise ValueError(f"{seconds} s is not a whole number of physics steps ({timestep} s)")
    return int(round(ratio))


def physics_steps_per_control(world: World) -> int:
    """Physics steps in one control period (validated integer in `build`)."""
    return int(round(world.scenario.control_period_s / world.model.opt.timestep))
