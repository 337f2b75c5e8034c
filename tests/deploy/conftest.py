"""Fixtures of the deployment tests: the unit file, and a copy of it that can be verified here."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.deploy.unit_file import UNIT, VENV_BIN, unit_settings


@pytest.fixture(scope="session")
def unit_text() -> str:
    return UNIT.read_text()


@pytest.fixture(scope="session")
def service(unit_text: str) -> dict[str, list[str]]:
    """The [Service] settings of deploy/systemd/gauged.service."""
    return unit_settings(unit_text)


@pytest.fixture
def runnable_unit(tmp_path: Path, unit_text: str) -> Path:
    """A copy of the unit whose programs exist on this machine.

    ``systemd-analyze verify`` refuses a unit whose ExecStart= binary is missing, and
    /opt/gauged/bin/gauged exists only on an installed edge computer; the copy points at the
    ``gauged`` script of the venv running the tests instead. Nothing else is changed.
    """
    gauged = VENV_BIN / "gauged"
    if not gauged.is_file():
        pytest.skip(f"{gauged} not found: install the package into the venv (pip install -e .)")
    unit = tmp_path / "gauged.service"
    unit.write_text(unit_text.replace("/opt/gauged/bin/gauged", str(gauged)))
    return unit
