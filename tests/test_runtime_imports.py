"""The runtime never imports torch: it runs the shipped ONNX files on onnxruntime alone."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "gauged"


def test_no_runtime_module_imports_torch():
    offenders = []
    for path in PACKAGE.rglob("*.py"):
        if "training" in path.relative_to(PACKAGE).parts:
            continue
        if re.search(r"^\s*(import torch|from torch)", path.read_text(), re.M):
            offenders.append(str(path.relative_to(PACKAGE)))
    assert offenders == []


def test_running_the_daemon_and_reader_loads_no_torch():
    code = (
        "import sys, gauged.cli, gauged.daemon.app, gauged.reader.factory, gauged.reader.pipeline, gauged.reader.stages.ocr, "
        "gauged.evaluation.models, gauged.commands.read, gauged.commands.eval, gauged.commands.synth\n"
        "gauged.cli.build_parser()\n"
        "print('torch' in sys.modules)"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False"
