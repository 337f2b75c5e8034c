"""The command line: help, exit codes, check-config, run on the default, log formats."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def gauged(*args: str, cwd: Path = REPO) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "gauged", *args], cwd=cwd, capture_output=True, text=True, timeout=120)


def test_cli_help_lists_subcommands():
    result = gauged("--help")
    assert result.returncode == 0
    for command in ("run", "check-config", "version"):
        assert command in result.stdout


def test_cli_no_command_is_usage_error():
    assert gauged().returncode == 2


def test_cli_unknown_option_is_usage_error():
    result = gauged("--frobnicate")
    assert result.returncode == 2 and "--help" in result.stderr


def test_cli_version_prints_version():
    from gauged import __version__

    result = gauged("version")
    assert result.returncode == 0 and result.stdout.strip() == f"gauged {__version__}"


def test_cli_check_config_example_passes():
    result = gauged("check-config", "config/gauged.example.yaml")
    assert result.returncode == 0, result.stderr
    assert "boiler-pressure" in result.stdout and result.stdout.rstrip().endswith("valid")


def test_cli_check_config_broken_copy_names_path_and_line(tmp_path):
    text = (REPO / "config" / "gauged.example.yaml").read_text()
    lines = text.splitlines()
    index = next(i for i, line in enumerate(lines) if line.strip().startswith("high: 8.0"))
    lines[index] = lines[index].replace("high: 8.0", "high: 0.8")
    broken = tmp_path / "gauged.yaml"
    broken.write_text("\n".join(lines) + "\n")
    result = gauged("check-config", str(broken))
    assert result.returncode == 2
    assert f"{broken}:{index + 1} gauges[0].alarms.high: must be greater than alarms.low" in result.stderr


def test_cli_check_config_missing_file_is_config_error(tmp_path):
    result = gauged("check-config", str(tmp_path / "missing.yaml"))
    assert result.returncode == 2 and "cannot read the file" in result.stderr


def test_cli_json_log_format_emits_json_lines(tmp_path):
    broken = tmp_path / "bad.yaml"
    broken.write_text("cameras: 5\n")
    result = gauged("--log-format", "json", "run", "--config", str(broken))
    assert result.returncode == 2
    assert "cameras" in result.stderr


def test_json_formatter_carries_extra_fields():
    import logging

    from gauged.logging_setup import JsonFormatter

    record = logging.makeLogRecord({"msg": "bad frame %s", "args": ("x",), "levelname": "WARNING", "name": "g", "camera": "cam1"})
    entry = json.loads(JsonFormatter().format(record))
    assert entry["msg"] == "bad frame x" and entry["camera"] == "cam1" and entry["level"] == "warning"
