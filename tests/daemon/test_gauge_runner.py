"""The locked read of a gauge runner: the needle scan reads most locked frames, the crop model every
tenth one and every frame the scan cannot tell, and the periodic full read stays."""

from __future__ import annotations

import numpy as np
import pytest

from gauged.config.model import GaugeConfig, ScaleLockConfig
from gauged.daemon import gauge_runner
from gauged.daemon.gauge_runner import GaugeRunner
from gauged.reader.pipeline import GaugeReader
from gauged.reader.stages.needle_scan import ScannedNeedle
from gauged.tracking.tracker import GaugeTracker
from gauged.types import Frame

from ..reader.dial_maps import CROP, Dial
from ..reader.stages.test_needle_scan import render
from ..reader.test_failure_reasons import DialCropModel

DIAL = Dial(needle_deg=300.0)  # 6.11 on a 0..10 scale over 135..405 degrees
ROI = [18, 18, 238, 238]  # its padded square is nearly the whole 256 px frame: the crop is the frame, 0.3% larger
PERIOD_NS = 500_000_000


def runner_for(recheck_every_s: float = 300.0) -> tuple[GaugeRunner, DialCropModel]:
    config = GaugeConfig(id="g1", camera="cam1", roi=ROI, scale={"min": 0.0, "max": 10.0, "unit": "bar"},
                         smoothing={"method": "none", "hampel_window": 1})
    model = DialCropModel(DIAL)
    lock = ScaleLockConfig(frames=2, recheck_every_s=recheck_every_s)
    return GaugeRunner(config, lock, GaugeReader(model), GaugeTracker.from_config(config)), model


def frames(count: int, image: np.ndarray | None = None, start: int = 0):
    image = render(DIAL, DIAL.needle_deg) if image is None else image
    for k in range(start, start + count):
        yield Frame(image, stamp_ns=(k + 1) * PERIOD_NS, camera="cam1", frame_id=k)


def locked(runner: GaugeRunner) -> int:
    """Read frames until the scale locks; returns the next frame's index."""
    for k, frame in enumerate(frames(10)):
        runner.process(frame, tuple(ROI))
        if runner.scale_lock.is_locked:
            return k + 1
    raise AssertionError("the scale did not lock")


def test_locked_frames_are_scanned_and_one_in_ten_read_by_the_crop_model():
    runner, model = runner_for()
    start = locked(runner)
    calls = model.calls
    outputs = [runner.process(frame, tuple(ROI)) for frame in frames(25, start=start)]
    by_model = [k for k, out in enumerate(outputs) if out.read.keypoints is not None]
    assert by_model == [0, 10, 20]  # the first locked frame (nothing learnt yet), then every tenth
    assert model.calls - calls == 3
    scanned = [out for out in outputs if out.read.keypoints is None]
    assert all(isinstance(out.read.needle, ScannedNeedle) and "needle_scan" in out.read.seconds for out in scanned)
    values = [out.reading.value for out in outputs]
    assert all(v is not None for v in values) and max(values) - min(values) < 0.03
    assert values[1] == pytest.approx(10 * (300 - 135) / 270, abs=0.05)


def test_a_frame_the_scan_cannot_tell_is_read_by_the_crop_model():
    runner, model = runner_for()
    start = locked(runner)
    list(map(lambda f: runner.process(f, tuple(ROI)), frames(3, start=start)))  # learnt, then scanning
    calls = model.calls
    two_needles = render(DIAL, (DIAL.needle_deg, 200.0))
    out = runner.process(next(frames(1, two_needles, start + 3)), tuple(ROI))
    assert model.calls == calls + 1 and out.read.keypoints is not None  # the scan saw two peaks
    assert out.reading.value == pytest.approx(10 * (300 - 135) / 270, abs=0.05)  # the crop model's needle
    # nothing is learnt from a crop with two needles: the next frame is the crop model's too, and
    # the look learnt on it scans the one after
    after = [runner.process(frame, tuple(ROI)) for frame in frames(2, start=start + 4)]
    assert [out.read.keypoints is None for out in after] == [False, True]


def test_the_periodic_full_read_stays_and_keeps_the_look():
    runner, model = runner_for(recheck_every_s=3.0)
    start = locked(runner)
    outputs = [runner.process(frame, tuple(ROI)) for frame in frames(10, start=start)]
    looks = [out.read.look for out in outputs]
    assert "known" in looks[5:7]  # the full read 3 s (6 frames) after the lock re-verifies it
    full = looks.index("known")
    assert outputs[full + 1].read.keypoints is None  # the same lock: the scan goes on


def test_without_the_scan_every_locked_frame_is_read_by_the_crop_model(monkeypatch):
    monkeypatch.setattr(gauge_runner, "CROP_MODEL_EVERY", 1)
    runner, model = runner_for()
    start = locked(runner)
    outputs = [runner.process(frame, tuple(ROI)) for frame in frames(5, start=start)]
    assert all(out.read.keypoints is not None for out in outputs)
