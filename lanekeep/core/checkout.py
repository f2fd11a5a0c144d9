"""Running from a clone without installing it: the three folders the install maps into the
`lanekeep` namespace (pyproject's package-dir: detectors/, estimators/, mjcf/) are found
beside the package, and nothing else of the clone is.

A finder at the end of `sys.meta_path`, asked only when no installed package answered, for
exactly those three names: an install (editable or not) always wins, and `lanekeep.tools`,
`lanekeep.tests` or `lanekeep.docs` are never importable, as appending the clone to the
package's `__path__` made them.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import os
import sys

MAPPED = ("detectors", "estimators", "mjcf")  # pyproject.toml [tool.setuptools.package-dir]


class CheckoutFolders(importlib.abc.MetaPathFinder):
    """Finds `lanekeep.<folder>` for the folders of MAPPED in a clone's root."""

    def __init__(self, root: str) -> None:
        self.root = root

    def find_spec(self, fullname: str, path=None, target=None
                  ) -> importlib.machinery.ModuleSpec | None:
        package, _, folder = fullname.partition(".")
        if package != "lanekeep" or folder not in MAPPED:
            return None
        location = os.path.join(self.root, folder)
        init = os.path.join(location, "__init__.py")
        if not os.path.isfile(init):
            return None
        return importlib.util.spec_from_file_location(
            fullname, init, submodule_search_locations=[location])


def map_checkout_folders(root: str) -> None:
    """Install the finder for the clone at `root` when `root` is one (it holds pyproject.toml
    and detectors/registry.py) and no finder for it is installed yet."""
    if not (os.path.isfile(os.path.join(root, "pyproject.toml"))
            and os.path.isfile(os.path.join(root, "detectors", "registry.py"))):
        return
    if any(isinstance(f, CheckoutFolders) and f.root == root for f in sys.meta_path):
        return
    sys.meta_path.append(CheckoutFolders(root))
