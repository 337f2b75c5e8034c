"""Where the deployment files are, and a reader of systemd unit files."""

from __future__ import annotations

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DEPLOY = REPO / "deploy"
UNIT = DEPLOY / "systemd" / "gauged.service"
DROPIN_EXAMPLE = DEPLOY / "systemd" / "gauged.service.d" / "local.conf.example"
VENV_BIN = Path(sys.executable).parent


def unit_settings(text: str, section: str = "Service") -> dict[str, list[str]]:
    """``Key -> [values in order]`` of one section of a unit file (comments left out)."""
    settings: dict[str, list[str]] = {}
    current = None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith(("#", ";")):
            continue
        if line.startswith("[") and line.endswith("]"):
            current = line[1:-1]
        elif current == section and "=" in line:
            key, _, value = line.partition("=")
            settings.setdefault(key.strip(), []).append(value.strip())
    return settings


def unit_environment(settings: dict[str, list[str]]) -> dict[str, str]:
    """The variables set by the unit's ``Environment=`` lines (plain ``KEY=VALUE`` words)."""
    env: dict[str, str] = {}
    for line in settings.get("Environment", []):
        for word in line.split():
            key, _, value = word.partition("=")
            env[key] = value
    return env
