"""The OpenGL backend MuJoCo renders with, checked once with a message a user can act on.

`import mujoco` loads the backend named by MUJOCO_GL; a backend that this machine lacks
(osmesa without its library, glfw without a display) fails deep inside PyOpenGL with an
AttributeError, and a renderer that cannot start fails inside `mujoco.Renderer`. Both are a
property of the machine, not a bug: the CLI reports them as one line and exit 2.
"""

from __future__ import annotations

import os
from types import ModuleType

from lanekeep.core.config_io import ConfigError

ADVICE = ("on a headless machine set MUJOCO_GL=egl and install an EGL driver "
          "(e.g. Mesa's libegl1)")


class RendererUnavailable(ConfigError):
    """MuJoCo's renderer cannot start here; the message names MUJOCO_GL and what to do."""

    def __init__(self, reason: str):
        backend = os.environ.get("MUJOCO_GL", "")
        super().__init__(f"MUJOCO_GL={backend}", "",
                         f"cannot start MuJoCo's renderer ({' '.join(reason.split())}); {ADVICE}")


def require_mujoco() -> ModuleType:
    """`mujoco`, imported; RendererUnavailable when its GL backend cannot load."""
    try:
        import mujoco
    except Exception as err:  # noqa: BLE001 - whatever the backend raises means the same
        raise RendererUnavailable(f"{type(err).__name__}: {err}") from err
    return mujoco
