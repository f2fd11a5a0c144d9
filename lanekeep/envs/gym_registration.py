"""Registers "lanekeep/LaneKeep-v0" with Gymnasium on `import lanekeep`, without importing
Gymnasium there.

Gymnasium 1.x has no plugin entry points (1.0 removed them), so the id must be registered by
code. Importing gymnasium (and numpy with it) in `lanekeep/__init__.py` would cost every CLI
start ~0.15 s, so: if gymnasium is already imported, register now; otherwise a one-shot import
hook registers right after gymnasium's own `__init__` has run. Without gymnasium installed,
nothing happens.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import sys

ENV_ID = "lanekeep/LaneKeep-v0"
ENTRY_POINT = "lanekeep.envs.gym_env:LaneKeepGymEnv"


def register() -> None:
    """Add the id to gymnasium's registry (idempotent); gymnasium must be importable."""
    import gymnasium

    if ENV_ID not in gymnasium.registry:
        gymnasium.register(id=ENV_ID, entry_point=ENTRY_POINT)


class _AfterGymnasiumImport(importlib.abc.MetaPathFinder):
    """Finds gymnasium's real spec once, and wraps its loader to register after it ran."""

    def find_spec(self, fullname, path, target=None):
        if fullname != "gymnasium":
            return None
        sys.meta_path.remove(self)  # one shot; and the lookup below must not find us again
        spec = importlib.util.find_spec(fullname)
        if spec is None or spec.loader is None:
            return spec
        run = spec.loader.exec_module

        def exec_module(module):
            run(module)
            register()

        spec.loader.exec_module = exec_module  # this spec's own loader instance
        return spec


def install() -> None:
    """Register now if gymnasium is loaded, else when it is first imported."""
    if "gymnasium" in sys.modules:
        register()
    elif not any(isinstance(f, _AfterGymnasiumImport) for f in sys.meta_path):
        # Without gymnasium installed the hook only ever sees a failing import: harmless.
        sys.meta_path.insert(0, _AfterGymnasiumImport())
