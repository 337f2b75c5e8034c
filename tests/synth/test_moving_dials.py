from __future__ import annotations

import json

import numpy as np
from mcap.reader import make_reader

from gauged.sources.mcap_source import iter_frames
from gauged.synth.moving_dials import EPOCH_NS, demo_dials, excursion, write_recording


def test_write_recording_is_byte_identical_for_a_seed(tmp_path):
    dials = demo_dials()[:2]
    write_recording(tmp_path / "a.mcap", dials, seconds=2, fps=2, seed=3)
    write_recording(tmp_path / "b.mcap", dials, seconds=2, fps=2, seed=3)
    assert (tmp_path / "a.mcap").read_bytes() == (tmp_path / "b.mcap").read_bytes()


def test_write_recording_frames_and_truth_read_back(tmp_path):
    dials = demo_dials()[:1]
    path = tmp_path / "r.mcap"
    assert write_recording(path, dials, seconds=3, fps=2, seed=1) == 6
    frames = list(iter_frames(path, "/cam1/image"))
    assert [f.stamp_ns for f in frames] == [EPOCH_NS + i * 500_000_000 for i in range(6)]
    assert frames[0].image.shape == (540, 960, 3)
    with path.open("rb") as stream:
        truths = [json.loads(m.data) for _, _, m in make_reader(stream).iter_messages(topics=["/cam1/truth"])]
    assert [t["stamp_ns"] for t in truths] == [f.stamp_ns for f in frames]
    gauge = truths[0]["gauges"][0]
    assert gauge["gauge"] == "boiler-pressure" and gauge["value"] == 5.0
    x0, y0, x1, y1 = (int(v) for v in gauge["box"])
    dial = frames[0].image[y0:y1, x0:x1].astype(float)
    assert dial.std() > 20  # something was drawn where the truth says the dial is


def test_write_recording_ros2_flavour_reads_back(tmp_path):
    path = tmp_path / "ros.mcap"
    write_recording(path, demo_dials()[:1], seconds=1, fps=2, seed=1, ros2=True)
    frames = list(iter_frames(path, "/cam1/image"))
    assert len(frames) == 2 and frames[1].stamp_ns - frames[0].stamp_ns == 500_000_000


def test_excursion_profile_shape():
    profile = excursion(5.0, 9.4, rise_at=10, hold_from=25, hold_to=38, fall_to=48)
    values = [profile(t) for t in (0, 10, 17.5, 30, 43, 50)]
    assert np.allclose(values, [5.0, 5.0, 7.2, 9.4, 7.2, 5.0])
