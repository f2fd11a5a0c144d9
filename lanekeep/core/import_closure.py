"""The package modules a module can reach through its imports, read from the source.

A cache key that must change when the code behind a result changes (the eval sets' renders,
lanekeep/evaluation/eval_sets.py) hashes these files rather than the whole package: an edit of a
detector, a metric or the CLI then leaves the cached renders valid, while any edit of the world,
camera or scenario code they import still invalidates them.

Static, on purpose: every `import` statement counts wherever it sits (top level, inside a
function, under `if TYPE_CHECKING`), so the closure holds at least what any run of the module
can import. Imports by computed name (`importlib.import_module(name)`) are not seen; the code
that draws a set has none.
"""

from __future__ import annotations

import ast
import importlib.util
from pathlib import Path


def _source(name: str) -> Path | None:
    """The .py file of module or package `name`, or None (not found, not Python source)."""
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None
    if spec is None or spec.origin is None or not spec.origin.endswith(".py"):
        return None
    return Path(spec.origin)


def _imported_names(tree: ast.AST, module: str, is_package: bool) -> set[str]:
    """Absolute names every import statement of `module` names (relative ones resolved); for
    `from X import Y` both X and X.Y, since Y may be a submodule."""
    names: set[str] = set()
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                parent = ".".join(parts[: len(parts) - node.level + 1])
                base = f"{parent}.{base}" if base else parent
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names if alias.name != "*")
    return names


def import_closure(root_module: str, prefix: str = "lanekeep") -> dict[str, Path]:
    """{module name: source file} of `root_module` and every `prefix` module it reaches through
    import statements, its parent packages' `__init__` included."""
    found: dict[str, Path] = {}
    todo = [root_module]
    while todo:
        name = todo.pop()
        if name in found or not (name == prefix or name.startswith(prefix + ".")):
            continue
        path = _source(name)
        if path is None:
            continue
        found[name] = path
        is_package = path.name == "__init__.py"
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        reached = _imported_names(tree, name, is_package)
        parts = name.split(".")
        reached.update(".".join(parts[:i]) for i in range(1, len(parts)))  # parents run first
        todo.extend(sorted(reached - found.keys()))
    return found
