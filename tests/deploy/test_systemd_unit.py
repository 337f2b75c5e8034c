"""deploy/systemd/gauged.service: systemd accepts it, it is hardened, and it matches the daemon.

``systemd-analyze`` (Debian package systemd) reads units offline, so these tests need no running
systemd; a machine without the tool skips them.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest
import yaml

from gauged.cli import EXIT_USAGE
from tests.deploy.system_tools import require_tool, run_tool
from tests.deploy.unit_file import DEPLOY, DROPIN_EXAMPLE, REPO, VENV_BIN

# Measured 1.1 ("OK") with systemd 252. The limit catches a lost protection (DynamicUser= or the
# empty CapabilityBoundingSet= alone add more than 0.9) without failing on a newer systemd that
# weighs a setting slightly differently.
MAX_EXPOSURE = 2.0


def verify(unit: Path) -> list[str]:
    """What ``systemd-analyze verify`` says about ``unit`` or its drop-ins (other units' noise aside)."""
    tool = require_tool("systemd-analyze", "systemd")
    result = run_tool(tool, "verify", "--man=no", str(unit))
    said = [line for line in (result.stdout + result.stderr).splitlines() if "gauged" in line]
    assert result.returncode == 0 or said, f"verify failed without naming gauged: {result.stderr}"
    return said


def test_unit_verifies_without_warnings(runnable_unit: Path) -> None:
    assert verify(runnable_unit) == []


def test_dropin_example_is_read_and_verifies(runnable_unit: Path) -> None:
    dropin_dir = runnable_unit.parent / "gauged.service.d"
    dropin_dir.mkdir()
    dropin = dropin_dir / "local.conf"
    shutil.copy(DROPIN_EXAMPLE, dropin)
    assert verify(runnable_unit) == []
    # The same check must notice a mistake in the drop-in, or the pass above proves nothing.
    dropin.write_text(DROPIN_EXAMPLE.read_text() + "NoSuchSetting=1\n")
    assert any("local.conf" in line and "NoSuchSetting" in line for line in verify(runnable_unit))


def test_unit_security_exposure_is_low(runnable_unit: Path) -> None:
    tool = require_tool("systemd-analyze", "systemd")
    result = run_tool(tool, "security", "--offline=yes", str(runnable_unit))
    if "--offline" in result.stderr and result.returncode != 0:
        pytest.skip(f"this systemd-analyze has no --offline (systemd 250+): {result.stderr.strip()}")
    match = re.search(r"Overall exposure level for gauged\.service: ([0-9.]+)", result.stdout)
    assert match, result.stdout[-2000:] + result.stderr
    exposure = float(match.group(1))
    print(f"systemd-analyze security: exposure {exposure}")
    assert exposure <= MAX_EXPOSURE, result.stdout


def test_unit_speaks_the_daemons_systemd_contract(service: dict[str, list[str]]) -> None:
    assert service["Type"] == ["notify"]
    assert service["NotifyAccess"] == ["main"]
    assert service["WatchdogSec"] and service["Restart"] == ["on-failure"]
    assert service["ExecReload"][-1] == "/bin/kill -HUP $MAINPID"
    (start,) = service["ExecStart"]
    assert start.split() == ["/opt/gauged/bin/gauged", "--log-format", "json", "run", "--config",
                             "/etc/gauged/gauged.yaml"]
    # A config error exits EXIT_USAGE; restarting cannot fix it.
    assert service["RestartPreventExitStatus"] == [str(EXIT_USAGE)]
    assert service["ConfigurationDirectory"] == ["gauged"] and service["StateDirectory"] == ["gauged"]


def test_unit_commands_parse_with_the_installed_cli(service: dict[str, list[str]], tmp_path: Path) -> None:
    """ExecStart's and ExecReload's arguments are accepted by this gauged (no typo in a flag)."""
    gauged = VENV_BIN / "gauged"
    config = tmp_path / "gauged.yaml"
    shutil.copy(DEPLOY / "config" / "gauged.yaml", config)
    check = service["ExecReload"][0].replace("/opt/gauged/bin/gauged", str(gauged))
    check = check.replace("/etc/gauged/gauged.yaml", str(config))
    result = run_tool(*check.split())
    assert result.returncode == 0, result.stdout + result.stderr
    start = service["ExecStart"][0].replace("/opt/gauged/bin/gauged", str(gauged)).split()
    help_result = run_tool(*start[:3], "run", "--help")  # global flags and sub-command as in the unit
    assert help_result.returncode == 0 and "--config" in help_result.stdout, help_result.stderr


@pytest.mark.parametrize("config", [DEPLOY / "config" / "gauged.yaml", REPO / "config" / "gauged.example.yaml"])
def test_configs_write_only_inside_the_state_directory(service: dict[str, list[str]], config: Path) -> None:
    """ProtectSystem=strict leaves only /var/lib/<StateDirectory> writable: MCAP and state go there."""
    state_dir = Path("/var/lib") / service["StateDirectory"][0]
    document = yaml.safe_load(config.read_text())
    written = [Path(document["outputs"]["mcap"]["dir"]), Path(document["state"]["dir"])]
    for path in written:
        assert path.is_relative_to(state_dir), f"{config.name}: {path} is outside {state_dir}"
