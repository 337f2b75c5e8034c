"""make_source selects the source of a camera by its `type:`."""

from __future__ import annotations

import pytest

from gauged.config.model import CameraConfig
from gauged.metrics import Metrics
from gauged.sources import make_source
from gauged.sources.mcap_source import McapSource
from gauged.sources.zenoh_source import ZenohSource


def test_make_source_builds_an_mcap_replay_from_config(recording):
    path, rec = recording("ros2-compressed", 2)
    camera = CameraConfig.model_validate(
        {"id": "cam1", "source": {"type": "mcap", "path": str(path), "topic": "/cam1/image", "pace": "fast"}})
    source = make_source(camera, metrics=Metrics())
    assert isinstance(source, McapSource)
    source.start()
    try:
        assert [source.next_frame(5.0).stamp_ns for _ in range(2)] == rec.stamps
    finally:
        source.stop()


def test_make_source_builds_a_zenoh_subscriber_and_needs_a_session(zenoh_pair):
    camera = CameraConfig.model_validate({"id": "cam1", "source": {"type": "zenoh", "key": "cam1/**"}})
    with pytest.raises(ValueError, match="needs a zenoh session"):
        make_source(camera)
    source = make_source(camera, session=zenoh_pair[0])
    assert isinstance(source, ZenohSource) and not source.finished
    source.start()
    source.stop()
