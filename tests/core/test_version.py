"""`lanekeep --version` prints the version the installed distribution carries."""

import importlib.metadata
import subprocess
import sys

import lanekeep


def test_version_option_prints_the_installed_version():
    done = subprocess.run([sys.executable, "-m", "lanekeep.cli", "--version"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"lanekeep {importlib.metadata.version('lanekeep')}"
    assert lanekeep.__version__ == importlib.metadata.version("lanekeep")
