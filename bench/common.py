"""Shared bits of the benchmark scripts: machine description and median timing."""

from __future__ import annotations

import os
import platform
import sys


def machine() -> str:
    cpu = "unknown cpu"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def header(title: str) -> None:
    print(f"# {title}\n# machine: {machine()}\n# command: {' '.join([os.path.basename(sys.executable), *sys.argv])}")


from gauged.evaluation.timing import median_s  # noqa: E402,F401 (re-exported for the scripts)
