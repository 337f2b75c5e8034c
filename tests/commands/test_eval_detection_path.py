"""``gauged eval readings`` scores the path the daemon runs: the same boxes, located by one module
(:mod:`gauged.reader.locate`), read the same way (``read_box(..., located=True)``).

A synthetic recording of one gauge without an ROI is replayed by the daemon (``gauged replay``): four
frames, fewer than the scale lock needs (locked reads are the daemon's steady state, not a photo's). Its
frames, written losslessly, are read by ``gauged eval readings``. Every frame must give the same raw
value, or be refused by both.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import cv2
import pytest

from gauged.reader.factory import CROP_MODEL
from gauged.reader.onnx_model import packaged_model_path
from gauged.sources.mcap_source import iter_frames
from tests.test_e2e_daemon import REPO

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not packaged_model_path(CROP_MODEL).is_file(),
                       reason=f"gauged/models/{CROP_MODEL} is missing: train and export it (gauged/models/README.md)"),
]


def _gauged(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "gauged", *args], cwd=REPO, capture_output=True, text=True,
                          timeout=600, check=True)


def _messages(path: Path, topic: str) -> list[dict]:
    from mcap.reader import make_reader

    with path.open("rb") as stream:
        return [json.loads(m.data) for _s, c, m in make_reader(stream).iter_messages() if c.topic == topic]


def test_eval_readings_reads_each_frame_as_the_daemon_does(tmp_path):
    recording = tmp_path / "one.mcap"
    _gauged("synth", "recording", "--seconds", "4", "--fps", "1", "--gauges", "1", "--seed", "3",
            "--out", str(recording))
    config = tmp_path / "one.yaml"
    config.write_text(
        "site: test\nzenoh: {mode: peer, multicast_scouting: false}\n"
        f"cameras:\n  - id: cam1\n    source: {{type: mcap, path: {recording}, topic: /cam1/image, pace: fast, loop: false}}\n"
        "gauges:\n  - id: dial\n    camera: cam1\n"  # no ROI: the daemon locates it
        "outputs:\n  mcap: {dir: " + str(tmp_path / "out") + ", images: none}\n")
    out = tmp_path / "readings.mcap"
    _gauged("replay", str(recording), "--config", str(config), "--out", str(out))
    daemon = {r["stamp_ns"]: r["raw_value"] for r in _messages(out, "/gauged/readings") if r["gauge"] == "dial"}

    truths = {t["stamp_ns"]: t for t in _messages(recording, "/cam1/truth")}
    folder = tmp_path / "frames"
    folder.mkdir()
    labels, stamps = [], []
    for frame in iter_frames(recording, "/cam1/image"):
        name = f"{frame.frame_id:04d}.png"  # lossless: eval decodes the very pixels the daemon read
        cv2.imwrite(str(folder / name), frame.image)
        gauge = truths[frame.stamp_ns]["gauges"][0]
        labels.append({"image": name, "reading": gauge["value"], "min": gauge["min"], "max": gauge["max"]})
        stamps.append(frame.stamp_ns)
    (folder / "labels.json").write_text(json.dumps(labels))
    result = json.loads(_gauged("eval", "readings", "--data", str(folder), "--json", "--threads", "1").stdout)

    assert len(stamps) == 4 and set(stamps) <= set(daemon)
    evaluated = [image["value"] for image in result["images"]]
    assert any(v is not None for v in evaluated), "no frame was read: the comparison would say nothing"
    for stamp, value in zip(stamps, evaluated, strict=True):
        assert (value is None) == (daemon[stamp] is None), (stamp, value, daemon[stamp])
        if value is not None:
            assert value == pytest.approx(daemon[stamp], rel=1e-9, abs=1e-9)
