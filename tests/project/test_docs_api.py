"""Every ```python block of docs/api.md runs as it stands, so the API page cannot drift from the
code. Each block runs on its own, as a reader pastes it into a script: in a fresh module (its
own namespace, its own `__name__`, importable by that name as a script's `__main__` is) with a
temporary folder as the working directory. A block that raises, or fails its own asserts,
fails here. The blocks share this process, so torch and the renderers start once, not once
a block."""

from __future__ import annotations

import re
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
API = ROOT / "docs" / "api.md"
BLOCK = re.compile(r"^```python\n(.*?)^```$", re.DOTALL | re.MULTILINE)


def python_blocks(text: str) -> list[str]:
    """The ```python blocks of a Markdown text, in order."""
    return BLOCK.findall(text)


BLOCKS = python_blocks(API.read_text(encoding="utf-8"))


def _label(code: str) -> str:
    """A block's test id: its first line that is neither an import nor blank."""
    for line in code.splitlines():
        if line.strip() and not line.startswith(("import ", "from ")):
            return line.strip()[:40]
    return code.splitlines()[0][:40]


def test_the_page_has_its_examples():
    """One block per part of the page at least: Episode (run, judge, record, step,
    observe/act), scenario_from_dict, LaneEstimator, Gymnasium, dm_env, plug-ins."""
    assert len(BLOCKS) >= 10, f"docs/api.md has {len(BLOCKS)} python blocks"


NUMERIC = re.compile(r"^(?:import|from) (numpy|torch|cv2|gymnasium)\b", re.MULTILINE)
LANEKEEP = re.compile(r"^(?:import|from) lanekeep\b", re.MULTILINE)


def imports_lanekeep_first(code: str) -> bool:
    """Whether `import lanekeep` (or a `from lanekeep...`) comes before any numeric library's
    import: pasted into a fresh script, such a block runs on the pinned kernels
    (lanekeep/core/reproducibility.py), as the CLI does. These blocks share one process here,
    so the order is checked as written."""
    numeric, first = NUMERIC.search(code), LANEKEEP.search(code)
    return numeric is None or (first is not None and first.start() < numeric.start())


def test_the_rule_reads_import_order():
    assert imports_lanekeep_first("import lanekeep\nimport numpy as np\n")
    assert imports_lanekeep_first("import math\n")
    assert not imports_lanekeep_first("import numpy as np\nfrom lanekeep.loop import x\n")


# The examples and tools a user runs as scripts (a plug-in module such as
# examples/sabotage.py is imported by lanekeep's own CLI, after lanekeep).
SCRIPTS = sorted(str(p.relative_to(ROOT)) for folder in ("examples", "tools")
                 for p in (ROOT / folder).rglob("*.py")
                 if "__main__" in p.read_text(encoding="utf-8"))


@pytest.mark.parametrize("source", [*(f"docs/api.md block {i}" for i in range(len(BLOCKS))),
                                    *SCRIPTS])
def test_every_example_imports_lanekeep_before_numpy(source: str) -> None:
    code = (BLOCKS[int(source.rsplit(" ", 1)[1])] if source.startswith("docs/")
            else (ROOT / source).read_text(encoding="utf-8"))
    assert imports_lanekeep_first(code), f"{source}: import lanekeep before numpy, torch, cv2"


@pytest.mark.parametrize("index", range(len(BLOCKS)),
                         ids=[f"{i}:{_label(c)}" for i, c in enumerate(BLOCKS)])
def test_docs_api_example_runs(index: int, tmp_path: Path, monkeypatch) -> None:
    code = BLOCKS[index]
    name = f"docs_api_block_{index}"
    module = types.ModuleType(name)
    module.__file__ = str(API)
    monkeypatch.setitem(sys.modules, name, module)  # `f"{__name__}:Class"` resolves
    monkeypatch.chdir(tmp_path)  # blocks write under out/
    compiled = compile(code, f"docs/api.md block {index}", "exec")
    exec(compiled, module.__dict__)  # noqa: S102 - the page's own examples
