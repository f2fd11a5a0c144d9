"""The package's layer rules (lanekeep/__init__.py states them): each subpackage imports only
from lower layers; what the car runs (detectors, estimators, control, the driver) never imports
the world, sensing, scoring, the loop, the recorder, MuJoCo or dm_control, so that honesty holds
by construction; nothing imports the CLI, no private name crosses a module, and the import
graph has no cycle. Function-level and type-checking imports count.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FOLDERS = ("lanekeep", "detectors", "estimators", "mjcf")

# A subpackage may import its own modules and those of strictly lower layers; packages on one
# layer are peers and import neither each other. The order is the loop's data flow
# (../DESIGN.md): geometry and the scenario below the world, the world below what senses it,
# scoring and control above both, the loop above them, the faces and the CLI on top.
LAYERS = {
    "core": 0, "mjcf": 0,
    "geometry": 1,
    "detectors": 2, "realcam": 2, "traffic": 2,
    "estimators": 3,
    "scenario": 4,
    "world": 5,
    "sensing": 6,
    "control": 7,
    "driver": 8,
    "scoring": 9,
    "report": 10,
    "loop": 11, "evaluation": 11,
    "sweep": 12, "envs": 12, "tuning": 12,
    "cli": 13,
}
# The car's side: it is built from settings and a spec sheet and sees frames and its sensors'
# signals; none of its code may name the simulator, its truth, or what scores or records it.
CAR_SIDE = ("detectors", "estimators", "control", "driver")
TRUTH_SIDE = ("world", "sensing", "scoring", "loop", "report", "evaluation", "envs", "sweep",
              "tuning", "cli")
MUJOCO_MODULES = ("mujoco", "dm_control")


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    if parts[0] != "lanekeep":  # detectors/, estimators/, mjcf/ install as lanekeep.<folder>
        parts = ("lanekeep", *parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict[str, Path]:
    files = [p for folder in FOLDERS for p in (ROOT / folder).rglob("*.py")]
    return {_module_name(p): p for p in files}


def imports_of(path: Path) -> list[tuple[str, str | None, int]]:
    """(module, imported name or None, line) for every absolute import in the file."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(a.name, None, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found += [(node.module, a.name, node.lineno) for a in node.names]
    return found


def import_graph() -> dict[str, set[str]]:
    """module -> the project modules it imports anywhere in its body."""
    known = modules()
    graph: dict[str, set[str]] = {}
    for name, path in known.items():
        targets = set()
        for module, item, _ in imports_of(path):
            targets.add(module)
            if item is not None:
                targets.add(f"{module}.{item}")
        graph[name] = {t for t in targets if t in known and t != name}
    return graph


def layer_of(module: str) -> str | None:
    """The subpackage a lanekeep module belongs to (None: the top package itself)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[0] == "lanekeep" else None


def layer_violations(graph: dict[str, set[str]]) -> list[str]:
    bad = []
    for source, targets in graph.items():
        mine = layer_of(source)
        if mine is None:  # lanekeep/__init__.py: sets MUJOCO_GL, registers the Gym id
            continue
        for target in targets:
            theirs = layer_of(target)
            if theirs is None or theirs == mine:
                continue
            if LAYERS[theirs] >= LAYERS[mine]:
                bad.append(f"{source} ({mine}, layer {LAYERS[mine]}) imports {target} "
                           f"({theirs}, layer {LAYERS[theirs]})")
    return sorted(bad)


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}  # 1 = on the stack, 2 = done
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state and (cycle := visit(nxt)):
                return cycle
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def test_every_subpackage_has_a_layer():
    subpackages = {layer_of(m) for m in modules()} - {None}
    assert subpackages == set(LAYERS), subpackages ^ set(LAYERS)


def test_each_subpackage_imports_only_lower_layers():
    graph = import_graph()
    assert "lanekeep.world.build" in graph and "lanekeep.loop.episode" in graph
    assert layer_violations(graph) == []


def test_the_layer_check_catches_an_upward_import():
    graph = {"lanekeep.world.build": {"lanekeep.sensing.cameras"},
             "lanekeep.sensing.cameras": {"lanekeep.world.build"},
             "lanekeep.loop.episode": {"lanekeep.evaluation.dataset"}}
    assert len(layer_violations(graph)) == 2  # world -> sensing, and loop -> its peer


def test_nothing_imports_the_cli():
    graph = import_graph()
    importers = {m for m, targets in graph.items()
                 if layer_of(m) != "cli" and any(layer_of(t) == "cli" for t in targets)}
    assert importers == set()


def car_side_violations(known: dict[str, Path]) -> list[str]:
    """Imports by the car's side of the simulator, the truth or MuJoCo (any import, typing
    ones included: a type names what the code may be handed)."""
    bad = []
    for name, path in known.items():
        if layer_of(name) not in CAR_SIDE:
            continue
        for module, _, line in imports_of(path):
            root = module.split(".")[0]
            if root in MUJOCO_MODULES or (root == "lanekeep" and layer_of(module) in TRUTH_SIDE):
                where = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
                bad.append(f"{where}:{line} imports {module}")
    return bad


def test_the_car_side_never_imports_the_simulator_or_the_truth():
    assert car_side_violations(modules()) == []


def test_the_car_side_rule_catches_a_driver_that_imports_the_world(tmp_path):
    """A deliberate import of lanekeep.world by the driver (or of mujoco by a detector)."""
    leaky = tmp_path / "leaky_driver.py"
    leaky.write_text("from lanekeep.world.build import World\nimport mujoco\n")
    found = car_side_violations({"lanekeep.driver.leaky_driver": leaky,
                                 "lanekeep.detectors.leaky": leaky})
    assert len(found) == 4 and all("leaky" in f for f in found)
    assert any("lanekeep.world.build" in f for f in found)


def test_no_private_name_crosses_a_module():
    known = modules()
    crossings = [f"{path.relative_to(ROOT)}:{line} imports {item} from {module}"
                 for path in known.values()
                 for module, item, line in imports_of(path)
                 if module.startswith("lanekeep") and item and item.startswith("_")
                 and not item.startswith("__")]
    assert crossings == []


def test_no_import_cycle_between_project_modules():
    graph = import_graph()
    assert find_cycle(graph) is None, " -> ".join(find_cycle(graph))


def test_the_cycle_finder_finds_a_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_the_recorder_takes_no_episode():
    assert "lanekeep.loop.episode" not in import_graph()["lanekeep.report.record"]
