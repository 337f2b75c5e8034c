"""`gauged eval readings` as a user runs it on a synthetic labelled folder: the table's figures are
consistent with the per-image outcomes, and progress is reported on stderr."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from gauged.reader.factory import CROP_MODEL
from gauged.reader.onnx_model import packaged_model_path

pytestmark = pytest.mark.skipif(not packaged_model_path(CROP_MODEL).is_file(),
                                reason=f"gauged/models/{CROP_MODEL} is missing: train and export it")


def gauged(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "gauged", *args], capture_output=True, text=True, timeout=600)


def test_eval_readings_on_synthetic_renders(tmp_path):
    data = tmp_path / "renders"
    made = gauged("synth", "images", "--kind", "crop", "--size", "448", "--count", "3", "--seed", "5000100",
                  "--out", str(data))
    assert made.returncode == 0, made.stderr
    out = gauged("eval", "readings", "--data", str(data), "--json", "--threads", "1")
    assert out.returncode == 0, out.stderr
    assert "read 3/3 images" in out.stderr  # the progress line
    result = json.loads(out.stdout)
    images = result["images"]
    assert len(images) == 3 and result["all"]["count"] == 3
    refused = [i for i in images if i["value"] is None]
    assert result["all"]["failures"] == len(refused)
    for item in images:  # every image is either refused with a reason or read with its error
        if item["value"] is None:
            assert item["failure"]["stage"] and item["failure"]["reason"]
        else:
            assert item["failure"] is None and item["relative_error"] >= 0
    errors = [i["relative_error"] for i in images if i["value"] is not None]
    if errors:
        assert result["all"]["max_relative_error"] == pytest.approx(max(errors))
