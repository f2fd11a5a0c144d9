"""The package's layer rules (lanekeep/__init__.py states them): each subpackage imports only
from lower layers, detectors and estimators never touch MuJoCo, nothing imports the CLI, no
private name crosses a module, and the import graph has no cycle. Function-level imports count.
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
    "detectors": 2, "realcam": 2,
    "estimators": 3,
    "scenario": 4,
    "world": 5,
    "sensing": 6,
    "scoring": 7,
    "control": 8,
    "report": 9,
    "loop": 10, "evaluation": 10,
    "sweep": 11, "envs": 11, "tuning": 11,
    "cli": 12,
}
NO_MUJOCO = ("detectors", "estimators")  # perception and estimation see frames, not a model
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


def test_detectors_and_estimators_never_touch_mujoco():
    for name, path in modules().items():
        if layer_of(name) in NO_MUJOCO:
            touched = [(m, line) for m, _, line in imports_of(path)
                       if m.split(".")[0] in MUJOCO_MODULES]
            assert touched == [], f"{path.relative_to(ROOT)} imports {touched}"


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
