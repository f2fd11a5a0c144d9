"""The install puts one package at the top of site-packages: `lanekeep`. The repository's
detectors/, estimators/ and mjcf/ folders install inside it (pyproject's package-dir), so they
cannot clash with another distribution's generic `detectors` or `mjcf`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path, PurePosixPath

import lanekeep.detectors
import lanekeep.estimators
import lanekeep.mjcf

# What an install may add at the top of site-packages besides the package itself: its
# metadata, and in an editable install the finder that maps lanekeep.detectors to detectors/.
ALLOWED_PREFIXES = ("lanekeep", "__editable__", "__pycache__", "..")


def _pip_show_files() -> list[PurePosixPath]:
    out = subprocess.run([sys.executable, "-m", "pip", "show", "-f", "lanekeep"],
                         capture_output=True, text=True, check=True).stdout
    listing = out.split("Files:", 1)[1]
    return [PurePosixPath(line.strip()) for line in listing.splitlines() if line.strip()]


def test_pip_show_lists_no_generic_top_level_package():
    files = _pip_show_files()
    assert files, "pip show -f listed no files"
    tops = {path.parts[0] for path in files}
    stray = sorted(t for t in tops if not t.startswith(ALLOWED_PREFIXES))
    assert not stray, f"top-level entries besides lanekeep: {stray}"
    assert not tops & {"detectors", "estimators", "mjcf"}


def test_the_folders_are_subpackages_of_lanekeep_with_their_data():
    from importlib import resources

    assert resources.files("lanekeep.detectors").joinpath("detectors.toml").is_file()
    assert resources.files("lanekeep.estimators").joinpath("closed_loop_tracker.toml").is_file()
    assert resources.files("lanekeep.detectors.weights").joinpath("lanenet.pt").is_file()
    assert lanekeep.mjcf.CAR_XML.is_file()
    assert lanekeep.detectors.__name__ == "lanekeep.detectors"
    assert lanekeep.estimators.__name__ == "lanekeep.estimators"


def test_a_clone_maps_its_three_folders_and_nothing_else(tmp_path):
    """From a clone's root without the install (a fresh interpreter with the clone first on
    sys.path): lanekeep.detectors and friends import from the clone, lanekeep.tools,
    lanekeep.tests and lanekeep.docs do not exist."""
    root = PurePosixPath(__file__).parents[2]
    code = (
        "import sys, importlib.util; sys.path.insert(0, sys.argv[1])\n"
        "import lanekeep, lanekeep.detectors.base, lanekeep.estimators.kalman, lanekeep.mjcf\n"
        "assert lanekeep.detectors.__file__.startswith(sys.argv[1]), lanekeep.detectors.__file__\n"
        "print([importlib.util.find_spec('lanekeep.' + n) is None"
        " for n in ('tools', 'tests', 'docs')])\n")
    out = subprocess.run([sys.executable, "-S", "-c", code, str(root)], capture_output=True,
                         text=True, env={"MUJOCO_GL": "egl", "PATH": "/usr/bin:/bin",
                                         "PYTHONPATH": _site_packages()})
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "[True, True, True]"


def _site_packages() -> str:
    """The interpreter's third-party packages (numpy, ...) without its site hooks, so the
    editable install's own finder is not loaded."""
    import sysconfig

    return sysconfig.get_paths()["purelib"]


def test_every_subpackage_of_the_tree_is_listed_for_the_install():
    """pyproject's explicit `packages`: a subpackage left out imports from a clone (and an
    editable install) but is missing from a real install, as CI's is."""
    import tomllib

    root = Path(__file__).resolve().parents[2]
    listed = set(tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {".".join(p.parent.relative_to(root).parts)
             for p in root.glob("lanekeep/**/__init__.py")}
    for folder in ("detectors", "estimators", "mjcf"):
        found |= {".".join(("lanekeep", *p.parent.relative_to(root).parts))
                  for p in root.glob(f"{folder}/**/__init__.py")}
    assert found - listed == set(), f"not installed: {sorted(found - listed)}"
    assert listed - found == set(), f"listed but absent: {sorted(listed - found)}"
