"""`gauged read` as a user runs it: one line per gauge, the --json contract, refusals, debug pictures."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from gauged.reader.factory import CROP_MODEL
from gauged.reader.onnx_model import packaged_model_path
from gauged.synth.crop import render_crop

pytestmark = pytest.mark.skipif(not packaged_model_path(CROP_MODEL).is_file(),
                                reason=f"gauged/models/{CROP_MODEL} is missing: train and export it")
JSON_KEYS = {"image", "value", "unit", "confidence", "scale", "failure"}


def gauged(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "gauged", *args], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def dial(tmp_path_factory) -> tuple[Path, dict]:
    """A clean 448 px render of one gauge and its truth."""
    sample = render_crop(11, 448, clean=True)
    path = tmp_path_factory.mktemp("read") / "dial.png"
    cv2.imwrite(str(path), sample.image)
    return path, sample.truth


def test_read_json_with_a_known_scale_gives_the_value_and_the_contract_fields(dial, tmp_path):
    path, truth = dial
    given = str(path)  # the path exactly as given comes back
    out = gauged("read", "--json", "--threads", "1", "--scale", str(truth["min"]), str(truth["max"]), "bar",
                 "--debug-dir", str(tmp_path / "why"), given)
    assert out.returncode == 0, out.stderr
    lines = [json.loads(line) for line in out.stdout.splitlines()]
    assert len(lines) == 1 and JSON_KEYS <= set(lines[0])
    rec = lines[0]
    assert rec["image"] == given and rec["failure"] is None, rec
    span = truth["max"] - truth["min"]
    assert abs(rec["value"] - truth["value"]) <= 0.03 * span, (rec["value"], truth["value"])
    assert rec["scale"] == {"min": truth["min"], "max": truth["max"], "unit": "bar"} and rec["unit"] == "bar"
    assert 0.5 <= rec["confidence"] <= 1.0
    picture = cv2.imread(str(tmp_path / "why" / "dial-0.png"))
    assert picture is not None and picture.shape[0] > 100


def test_read_unreadable_and_empty_images_still_give_one_line_with_the_failure(tmp_path):
    broken = tmp_path / "broken.jpg"
    broken.write_bytes(b"\xff\xd8 not really a jpeg")
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((300, 300, 3), 127, np.uint8))
    out = gauged("read", "--json", "--threads", "1", str(broken), str(blank))
    assert out.returncode == 0, out.stderr
    recs = {r["image"]: r for r in map(json.loads, out.stdout.splitlines())}
    assert set(recs) == {str(broken), str(blank)}
    for rec in recs.values():
        assert rec["value"] is None and rec["failure"]["stage"] and rec["failure"]["reason"], rec
    assert recs[str(broken)]["failure"]["stage"] == "decode"
    text = gauged("read", "--threads", "1", str(broken))
    assert text.returncode == 0 and "refused at decode (unreadable)" in text.stdout


def test_read_rejects_a_bad_scale_with_a_usage_error(dial):
    out = gauged("read", "--scale", "10", "0", str(dial[0]))
    assert out.returncode == 2 and "max" in out.stderr.lower()
