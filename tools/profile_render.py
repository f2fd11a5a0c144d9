"""What each part of a scenario's scene costs the software renderer, one part removed at a time.

    MUJOCO_GL=egl .venv/bin/python tools/profile_render.py clear_curve case3_mild_turn_shade_bumps
    MUJOCO_GL=egl .venv/bin/python tools/profile_render.py clear_curve --frames out/render_parts

Why CPU time: Mesa's llvmpipe rasterises on a thread per core, so a render's wall time depends
on whatever else the machine runs; the process's CPU time (all its threads) does much less. Each
variant is timed interleaved with the others, `--rounds` rounds of `--renders` renders, and the
table gives the fastest and the median render per camera. The pose is the car at the scenario's
start plus `--ahead` metres along its lane (the first frames of an episode).

Variants: the scene as built (`as built`), then without one thing: MuJoCo's skybox, the
ground plane, the road surface meshes, the shoulders, the roadside props, the translucent
overlays (group 5: shadows, filtered paint, puddles), and each kind of them on its own (cast
shadows, vehicles' contact shadows, filtered paint, puddles, vehicles' light glows), the paint
geometry (group 1), and the haze and fog scene flags. A large saving names what to make
cheaper; a saving that changes many pixels is not one to take (`--frames` writes each
variant's frames).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from collections.abc import Callable
from pathlib import Path

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import numpy as np

Toggle = tuple[Callable[[], None], Callable[[], None]]


def _variants(world, rig) -> dict[str, Toggle]:
    """label -> (apply, undo): each removes one part of the scene from both cameras' renders."""
    import mujoco

    from lanekeep.world.groups import GROUP_CAR_BODY

    model = world.model
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, i) or ""
             for i in range(model.ngeom)]

    def hide(select: Callable[[int, str], bool]) -> Toggle:
        ids = np.array([i for i, n in enumerate(names) if select(i, n)], dtype=int)
        saved = model.geom_group[ids].copy()

        def apply() -> None:
            model.geom_group[ids] = GROUP_CAR_BODY  # a group neither camera draws

        def undo() -> None:
            model.geom_group[ids] = saved
        return apply, undo

    def flag(name: str, value: bool) -> Toggle:
        flag_id = getattr(mujoco.mjtRndFlag, name)
        return (lambda: rig.force_flags.update({flag_id: value}),
                lambda: rig.force_flags.pop(flag_id, None))

    group = model.geom_group
    return {
        "as built": (lambda: None, lambda: None),
        "no skybox": flag("mjRND_SKYBOX", False),
        "no ground plane": hide(lambda i, n: n == "ground_visual"),
        "no road surface": hide(lambda i, n: n.startswith("road")),
        "no shoulders": hide(lambda i, n: n.startswith("shoulder")),
        "no roadside props": hide(lambda i, n: n.startswith("props") and group[i] == 0),
        "no translucent overlays": hide(lambda i, n: group[i] == 5),
        "no cast shadows": hide(lambda i, n: group[i] == 5 and "shadow" in n
                                and "contact" not in n),
        "no contact shadows": hide(lambda i, n: n.endswith("contact_shadow")),
        "no filtered paint": hide(lambda i, n: group[i] == 5 and n.startswith("marking")),
        "no puddles": hide(lambda i, n: n == "cond_puddles"),
        "no vehicle glows": hide(lambda i, n: n.endswith("_glow")),
        "no paint geometry": hide(lambda i, n: group[i] == 1),
        "no haze": flag("mjRND_HAZE", False),
        "no fog": flag("mjRND_FOG", False),
    }


class _FlagRig:
    """The episode's camera rig with scene flags forced on or off for one variant."""

    def __init__(self, rig) -> None:
        self.rig = rig
        self.force_flags: dict[int, bool] = {}

    def render(self, data, camera: str) -> np.ndarray:
        if not self.force_flags:
            return self.rig.render_rgb(data, camera)
        import mujoco

        flags = self.rig._renderers[camera].scene.flags
        saved = flags.copy()
        # render_rgb sets the shadow and fog flags itself: force those through its settings
        settings = self.rig.settings
        fog = self.force_flags.get(mujoco.mjtRndFlag.mjRND_FOG, settings.fog)
        self.rig.settings = dataclasses.replace(settings, fog=bool(fog))
        for flag_id, value in self.force_flags.items():
            flags[flag_id] = value
        try:
            return self.rig.render_rgb(data, camera)
        finally:
            self.rig.settings = settings
            flags[:] = saved


def profile(name: str, renders: int, rounds: int, ahead_m: float,
            frames_dir: Path | None) -> dict[str, dict[str, tuple[float, float, float]]]:
    """{variant: {camera: (min ms, median ms, share of pixels changed)}} for one scenario."""
    import mujoco

    from lanekeep.scenario.schema import load_scenario
    from lanekeep.sensing.cameras import CameraRig, RenderSettings
    from lanekeep.world.build import build

    scenario = load_scenario(name)
    world = build(scenario)
    road = world.road
    s = scenario.start.s_m + ahead_m
    r = road.lane_center_r(scenario.road.ego_lane)
    x, y = road.position(s, r)
    world.car.place(float(x), float(y), float(road.heading_at(s)), scenario.start.speed_mps)
    mujoco.mj_forward(world.model, world.data)
    rig = _FlagRig(CameraRig(world.model, RenderSettings.of(scenario)))
    variants = _variants(world, rig)
    cameras = rig.rig.CAMERA_NAMES
    times: dict[str, dict[str, list[float]]] = {v: {c: [] for c in cameras} for v in variants}
    reference = {c: rig.render(world.data, c) for c in cameras}
    changed: dict[str, dict[str, float]] = {}
    try:
        for _ in range(rounds):
            for label, (apply, undo) in variants.items():
                apply()
                try:
                    for camera in cameras:
                        frame = rig.render(world.data, camera)  # warm, and the frame to show
                        if label not in changed or camera not in changed[label]:
                            diff = np.any(frame != reference[camera], axis=-1)
                            changed.setdefault(label, {})[camera] = float(diff.mean())
                            if frames_dir is not None:
                                _write(frames_dir / f"{name}_{camera}_{_slug(label)}.png", frame)
                        for _ in range(renders):
                            start = time.process_time()
                            rig.render(world.data, camera)
                            times[label][camera].append(time.process_time() - start)
                finally:
                    undo()
    finally:
        rig.rig.close()
    return {label: {c: (1e3 * min(ts), 1e3 * float(np.median(ts)), changed[label][c])
                    for c, ts in per_camera.items()}
            for label, per_camera in times.items()}


def _slug(label: str) -> str:
    return label.replace(" ", "_")


def _write(path: Path, rgb: np.ndarray) -> None:
    import cv2

    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))


def table(name: str, result: dict[str, dict[str, tuple[float, float, float]]]) -> str:
    """Markdown: per variant and camera the CPU ms (fastest, median), the saving against the
    scene as built and the share of pixels that changed."""
    base = result["as built"]
    lines = [f"### {name}", "",
             "| variant | front ms (min / med) | saving | changed px | rear ms (min / med) "
             "| saving | changed px |", "|---|---|---|---|---|---|---|"]
    for label, per_camera in result.items():
        cells = [label]
        for camera in ("front", "rear"):
            fastest, median, changed = per_camera[camera]
            saving = base[camera][0] - fastest
            cells += [f"{fastest:.1f} / {median:.1f}",
                      "" if label == "as built" else f"{saving:+.1f}",
                      "" if label == "as built" else f"{100 * changed:.0f}%"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenarios", nargs="+")
    parser.add_argument("--renders", type=int, default=5, help="timed renders per round")
    parser.add_argument("--rounds", type=int, default=4, help="interleaved rounds")
    parser.add_argument("--ahead", type=float, default=30.0,
                        help="metres along the lane from the start")
    parser.add_argument("--frames", type=Path, default=None,
                        help="write each variant's frames here (PNG)")
    args = parser.parse_args(argv)
    for name in args.scenarios:
        result = profile(name, args.renders, args.rounds, args.ahead, args.frames)
        print(table(name, result), end="\n\n", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
