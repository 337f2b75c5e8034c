"""The runtime works inside the unit's sandbox: MemoryDenyWriteExecute=, SystemCallFilter= and
RestrictAddressFamilies= as the unit sets them, and the unit's environment.

systemd is not PID 1 in containers and CI, so the service cannot be started for real; these three
settings are kernel features, applied here by ``sandbox_exec.py`` (seccomp through libseccomp,
``PR_SET_MDWE``) from what the unit file says, around ``runtime_probe.py``, which runs the
libraries the daemon runs. The syscall groups come from ``systemd-analyze syscall-filter``, so the
allow-list is the one this systemd would install. Not covered: the file-system and namespace
settings (ProtectSystem=, PrivateTmp=, PrivateUsers=, ...), which need systemd itself.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.deploy.system_tools import require_tool, run_tool
from tests.deploy.unit_file import REPO, unit_environment

HERE = Path(__file__).parent
EXIT_UNSUPPORTED = 77


def syscall_groups() -> dict[str, list[str]]:
    """Every ``@group`` of this systemd and its members (names and nested ``@groups``)."""
    tool = require_tool("systemd-analyze", "systemd")
    result = run_tool(tool, "syscall-filter")
    assert result.returncode == 0, result.stderr
    groups: dict[str, list[str]] = {}
    current: list[str] | None = None
    for line in result.stdout.splitlines():
        if line.startswith("@"):
            current = groups.setdefault(line.strip(), [])
        elif not line.strip() or not line.startswith(" "):
            current = None
        elif current is not None and not line.strip().startswith("#"):
            current.append(line.strip())
    return groups


def expand(item: str, groups: dict[str, list[str]]) -> set[str]:
    if not item.startswith("@"):
        return {item}
    return set().union(*(expand(member, groups) for member in groups[item]))


def allowed_syscalls(filters: list[str], groups: dict[str, list[str]]) -> set[str]:
    """The allow-list that ``SystemCallFilter=`` lines produce (systemd.exec(5) semantics).

    The first line must be an allow-list; systemd then adds @default itself, and each later line
    adds its calls or, prefixed with ``~``, removes them.
    """
    assert filters and not filters[0].startswith("~"), "expected an allow-list first"
    allowed = expand("@default", groups)
    for line in filters:
        deny = line.startswith("~")
        calls = set().union(*(expand(word, groups) for word in line.lstrip("~").split()))
        allowed = allowed - calls if deny else allowed | calls
    return allowed


def sandboxed(service: dict[str, list[str]], tmp_path: Path, *command: str,
              env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """Run ``command`` under the unit's syscall filter, address families and MDWE setting."""
    listing = tmp_path / "allowed-syscalls.txt"
    listing.write_text("\n".join(sorted(allowed_syscalls(service["SystemCallFilter"], syscall_groups()))))
    assert service["SystemCallErrorNumber"] == ["EPERM"], "sandbox_exec.py denies with EPERM, as the unit"
    args = [sys.executable, str(HERE / "sandbox_exec.py"), "--syscalls", str(listing),
            "--families", ",".join(service["RestrictAddressFamilies"][0].split())]
    if service.get("MemoryDenyWriteExecute") == ["yes"]:
        args.append("--mdwe")
    result = subprocess.run([*args, "--", *command], capture_output=True, text=True, timeout=120,
                            env=env, cwd=REPO, check=False)
    if result.returncode == EXIT_UNSUPPORTED:
        pytest.skip(f"this kernel cannot apply the unit's restrictions: {result.stderr.strip()}")
    return result


def test_runtime_works_inside_the_units_sandbox(service: dict[str, list[str]], tmp_path: Path) -> None:
    env = {**os.environ, **unit_environment(service),
           # DynamicUser= gives a home the service cannot write to.
           "HOME": "/proc/gauged-home-is-not-writable"}
    probe = [sys.executable, str(HERE / "runtime_probe.py"), str(tmp_path)]
    if service.get("MemoryDenyWriteExecute") == ["yes"]:
        probe.insert(2, "--expect-mdwe")
    result = sandboxed(service, tmp_path, *probe, env=env)
    assert result.returncode == 0 and result.stdout.rstrip().endswith("probe ok"), \
        f"exit {result.returncode}\n{result.stdout}\n{result.stderr[-4000:]}"


def test_sandbox_refuses_what_the_unit_forbids(service: dict[str, list[str]], tmp_path: Path) -> None:
    """The filter above really bites: a forbidden syscall and a forbidden socket family fail."""
    code = ("import os, socket\n"
            "try:\n    os.sched_setaffinity(0, {0}); print('setaffinity allowed')\n"
            "except PermissionError: print('setaffinity refused')\n"
            "try:\n    socket.socket(socket.AF_PACKET, socket.SOCK_RAW); print('packet allowed')\n"
            "except PermissionError: print('packet refused')\n"
            "socket.socket(socket.AF_INET, socket.SOCK_DGRAM).close(); print('inet allowed')\n")
    result = sandboxed(service, tmp_path, sys.executable, "-c", code)
    assert result.stdout.split("\n")[:3] == ["setaffinity refused", "packet refused", "inet allowed"], \
        result.stdout + result.stderr


def test_unit_environment_turns_off_onnxruntime_telemetry(service: dict[str, list[str]], tmp_path: Path) -> None:
    """onnxruntime 1.29+ keeps a device id under ~/.cache and uploads telemetry unless told not to."""
    code = ("import numpy as np, onnxruntime as ort\n"
            "from onnxruntime.datasets import get_example\n"
            "s = ort.InferenceSession(get_example('sigmoid.onnx'), providers=['CPUExecutionProvider'])\n"
            "s.run(None, {s.get_inputs()[0].name: np.zeros((3, 4, 5), np.float32)})\n")
    base = {k: v for k, v in os.environ.items() if not k.startswith("ORT_")}
    homes = {"default": tmp_path / "default", "unit": tmp_path / "unit"}
    for name, home in homes.items():
        home.mkdir()
        env = {**base, "HOME": str(home)} | (unit_environment(service) if name == "unit" else {})
        result = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                                timeout=120, check=False)
        assert result.returncode == 0, result.stderr
    if not any(homes["default"].iterdir()):
        pytest.skip(f"onnxruntime {_ort_version()} writes no telemetry state: nothing to turn off")
    assert not any(homes["unit"].iterdir()), sorted(p.name for p in homes["unit"].rglob("*"))


def _ort_version() -> str:
    import onnxruntime

    return onnxruntime.__version__
