"""open_sinks: the configured outputs, wrapped, fed one reading end to end."""

from __future__ import annotations

import json
import time
import urllib.request

import pytest
from mcap.reader import make_reader

from gauged.metrics import Metrics
from gauged.sinks import open_sinks
from gauged.sinks.config import OutputsConfig


def test_open_sinks_publishes_one_reading_to_every_output(zenoh_pair, tmp_path, reading):
    daemon, peer = zenoh_pair
    outputs = OutputsConfig.model_validate({"zenoh": {"prefix": "gauged/site"}, "mcap": {"dir": str(tmp_path)},
                                            "prometheus": {"listen": "127.0.0.1:0"}})
    metrics = Metrics()
    sinks = open_sinks(outputs, metrics=metrics, session=daemon, node="n1", gauges=["boiler-pressure"],
                       failure_pairs=[("needle", "no_needle")], name_prefix="site")
    try:
        assert [s.name for s in sinks] == ["prometheus", "mcap", "zenoh"]
        for sink in sinks:
            sink.publish_reading(reading(0))
        time.sleep(0.3)
        replies = [r.ok for r in peer.get("gauged/site/boiler-pressure/reading", timeout=3.0) if r.ok]
        assert [json.loads(s.payload.to_bytes())["value"] for s in replies] == [4.5]
        port = sinks[0].sink.port
        text = urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=5).read().decode()
        assert 'gauged_reading_value{gauge="boiler-pressure",unit="bar"} 4.5' in text
    finally:
        for sink in reversed(sinks):
            sink.close()
    files = list(tmp_path.glob("site-*.mcap"))
    with open(files[0], "rb") as f:
        assert [json.loads(m.data)["value"] for _, _, m in make_reader(f).iter_messages()] == [4.5]


def test_open_sinks_without_session_fails_and_closes_what_it_opened(tmp_path):
    outputs = OutputsConfig.model_validate({"mcap": {"dir": str(tmp_path)}, "prometheus": {"enabled": False}})
    with pytest.raises(ValueError, match="no zenoh session"):
        open_sinks(outputs, metrics=Metrics(), session=None, node="n1")
