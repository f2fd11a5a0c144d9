"""lanekeep/core/import_closure.py: the modules a module reaches through its import statements,
wherever they sit, relative ones resolved, and nothing it does not import."""

import sys
import textwrap

from lanekeep.core.import_closure import import_closure


def test_closure_follows_every_import_statement_and_stops_at_the_prefix(tmp_path, monkeypatch):
    pkg = tmp_path / "toypkg"
    (pkg / "sub").mkdir(parents=True)
    files = {
        "__init__.py": "",
        "root.py": """
            import json
            from toypkg import top_level
            from .sub import relative_target

            def later():
                from toypkg.sub.deep import inside_a_function  # only when called
            """,
        "top_level.py": "",
        "unused.py": "import toypkg.root\n",
        "sub/__init__.py": "",
        "sub/relative_target.py": "from ..top_level import *\n",
        "sub/deep.py": "inside_a_function = 1\n",
    }
    for name, text in files.items():
        (pkg / name).write_text(textwrap.dedent(text), encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        found = import_closure("toypkg.root", prefix="toypkg")
    finally:
        for name in [n for n in sys.modules if n == "toypkg" or n.startswith("toypkg.")]:
            del sys.modules[name]
    assert set(found) == {"toypkg", "toypkg.root", "toypkg.top_level", "toypkg.sub",
                          "toypkg.sub.relative_target", "toypkg.sub.deep"}
    assert found["toypkg.sub.deep"] == pkg / "sub" / "deep.py"
