"""deploy/ci/install-system-deps.sh: harmless without root, silent when everything is there."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from tests.deploy.system_tools import require_tool
from tests.deploy.unit_file import DEPLOY

SCRIPT = DEPLOY / "ci" / "install-system-deps.sh"


def run_script(path_dirs: list[Path], *, as_nobody: bool) -> subprocess.CompletedProcess[str]:
    bash = shutil.which("bash")
    assert bash
    command = [bash, str(SCRIPT)]
    if as_nobody:
        command = [require_tool("setpriv", "util-linux"), "--reuid=65534", "--regid=65534", "--clear-groups", *command]
    env = {"PATH": os.pathsep.join(map(str, path_dirs)), "LANG": "C"}
    return subprocess.run(command, env=env, capture_output=True, text=True, timeout=60, check=False)


def test_without_root_it_installs_nothing_and_says_how(tmp_path: Path) -> None:
    # A PATH with the shell's helpers but neither systemd-analyze nor promtool on it.
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in ("id", "date", "apt-get"):
        if found := shutil.which(tool):
            (bin_dir / tool).symlink_to(found)
    tmp_path.chmod(0o755)
    result = run_script([bin_dir], as_nobody=os.geteuid() == 0)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "sudo apt-get install -y --no-install-recommends systemd prometheus" in result.stdout
    assert "installing nothing" in result.stdout


def test_with_every_tool_present_it_does_nothing() -> None:
    dirs = {Path(require_tool(tool, package)).parent
            for tool, package in (("systemd-analyze", "systemd"), ("promtool", "prometheus"))}
    dirs |= {Path(p).parent for p in map(shutil.which, ("id", "date")) if p}
    result = run_script(sorted(dirs), as_nobody=False)
    assert result.returncode == 0 and result.stdout.rstrip().endswith("nothing to install"), result.stdout
