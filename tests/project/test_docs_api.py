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
