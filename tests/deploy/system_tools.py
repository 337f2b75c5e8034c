"""Find the system tools the deployment tests run, or skip saying how to install them."""

from __future__ import annotations

import shutil
import subprocess

import pytest

INSTALL_HINT = "run deploy/ci/install-system-deps.sh as root, or: sudo apt-get install -y {package}"


def require_tool(tool: str, package: str) -> str:
    """The path of ``tool``, or skip the test naming the Debian package that provides it."""
    path = shutil.which(tool)
    if path is None:
        pytest.skip(f"{tool} not found: {INSTALL_HINT.format(package=package)}")
    return path


def run_tool(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """Run a tool and capture its output as text (never raises on a non-zero exit)."""
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout, check=False)
