"""deploy/zenoh/: zenoh accepts the router configs, and the plant wiring they describe works.

The wiring test builds the documented topology inside this process on loopback ports: the central
router (router.json5), an edge computer's router (edge-router.json5), gauged's session from
deploy/config/gauged.yaml (through gauged's own ``zenoh_config``) with the real ``ZenohSink``, a
camera driver on the edge router and an HMI on the central router. Only the endpoints are
rewritten to free loopback ports; everything else is read from the files.
"""

from __future__ import annotations

import json
import socket
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import pytest
import zenoh

from gauged.config import load_config
from gauged.sinks.zenoh_sink import ZenohSink
from gauged.sources.zenoh_session import zenoh_config
from gauged.types import Quality, Reading, ScaleInfo
from tests.deploy.unit_file import DEPLOY

ZENOH = DEPLOY / "zenoh"
CENTRAL, EDGE = ZENOH / "router.json5", ZENOH / "edge-router.json5"
GAUGED_CONFIG = DEPLOY / "config" / "gauged.yaml"
WAIT_S = 10.0


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def router_config(path: Path, listen: int, connect: int | None = None, **overrides: object) -> zenoh.Config:
    config = zenoh.Config.from_file(str(path))
    config.insert_json5("listen/endpoints", json.dumps([f"tcp/127.0.0.1:{listen}"]))
    if connect is not None:
        config.insert_json5("connect/endpoints", json.dumps([f"tcp/127.0.0.1:{connect}"]))
    for key, value in overrides.items():
        config.insert_json5(key, json.dumps(value))
    return config


def client_config(port: int) -> zenoh.Config:
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("connect/endpoints", json.dumps([f"tcp/127.0.0.1:{port}"]))
    config.insert_json5("scouting/multicast/enabled", "false")
    return config


def wait_for(condition: Callable[[], bool], action: Callable[[], None] = lambda: None) -> bool:
    """Repeat ``action`` until ``condition`` holds (declarations take a moment to propagate)."""
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        action()
        if condition():
            return True
        time.sleep(0.1)
    return False


@contextmanager
def plant(*, central_overrides: dict[str, object] | None = None) -> Iterator[dict]:
    """The documented topology on loopback; yields the sessions, the sink and what arrived where."""
    config = load_config(GAUGED_CONFIG)
    central_port, edge_port = free_port(), free_port()
    got: dict[str, list] = {"frames": [], "readings": [], "commands": []}
    with ExitStack() as stack:
        def opened(conf: zenoh.Config) -> zenoh.Session:
            session = zenoh.open(conf)
            stack.callback(session.close)
            return session

        # The edge router starts first: it must keep retrying until the central router is up.
        edge = opened(router_config(EDGE, edge_port, connect=central_port))
        central = opened(router_config(CENTRAL, central_port, **(central_overrides or {})))
        gauged_zenoh = config.zenoh.model_copy(update={"connect": [f"tcp/127.0.0.1:{edge_port}"]})
        gauged = opened(zenoh_config(gauged_zenoh))
        camera, hmi = opened(client_config(edge_port)), opened(client_config(central_port))
        prefix = config.outputs.zenoh.prefix
        gauges = [g.id for g in config.gauges]
        frames_sub = gauged.declare_subscriber(config.cameras[0].source.key, got["frames"].append)
        readings_sub = hmi.declare_subscriber(f"{prefix}/*/reading", got["readings"].append)
        def on_command(gauge: str, kind: str, payload: bytes) -> dict:
            got["commands"].append((gauge, kind))
            return {"ok": True}

        sink = ZenohSink(gauged, prefix, "edge-01", gauges=gauges, on_command=on_command)
        stack.callback(sink.close)
        stack.callback(frames_sub.undeclare)
        stack.callback(readings_sub.undeclare)
        yield {"edge": edge, "central": central, "camera": camera, "hmi": hmi, "sink": sink, "prefix": prefix,
               "gauge": gauges[0], "camera_key": config.cameras[0].source.key.replace("**", "frame"), "got": got}


def reading(gauge: str) -> Reading:
    return Reading(gauge=gauge, camera="cam1", stamp_ns=1_700_000_000_000_000_000, value=4.2, raw_value=4.2,
                   unit="bar", quality=Quality.GOOD, confidence=0.9, scale=ScaleInfo(0.0, 10.0, "bar", True))


@pytest.mark.parametrize("path", [CENTRAL, EDGE], ids=lambda p: p.name)
def test_router_config_is_accepted_by_zenoh(path: Path) -> None:
    config = zenoh.Config.from_file(str(path))
    assert json.loads(config.get_json("mode")) == "router"
    assert json.loads(config.get_json("scouting/multicast/enabled")) is False


def test_zenoh_rejects_a_config_with_an_unknown_key(tmp_path: Path) -> None:
    """from_file validates, so the acceptance above means something."""
    broken = tmp_path / "router.json5"
    broken.write_text(CENTRAL.read_text().replace("adminspace:", "admin_space:"))
    with pytest.raises(zenoh.ZError, match="admin_space"):
        zenoh.Config.from_file(str(broken))


def test_plant_wiring_carries_frames_readings_liveliness_and_commands() -> None:
    with plant() as p:
        got, prefix, gauge = p["got"], p["prefix"], p["gauge"]
        # A camera driver on the edge computer reaches gauged through the edge router.
        assert wait_for(lambda: bool(got["frames"]), lambda: p["camera"].put(p["camera_key"], b"\xff\xd8jpeg"))
        # gauged's readings reach a subscriber on the central router.
        assert wait_for(lambda: bool(got["readings"]), lambda: p["sink"].publish_reading(reading(gauge)))
        assert json.loads(got["readings"][-1].payload.to_bytes())["value"] == 4.2
        # The latest state answers a get from the control room, and the daemon is seen alive.
        replies = [r.ok for r in p["hmi"].get(f"{prefix}/**", timeout=WAIT_S) if r.ok is not None]
        assert f"{prefix}/{gauge}/reading" in {str(s.key_expr) for s in replies}
        alive = [r.ok for r in p["hmi"].liveliness().get(f"{prefix}/@alive/*", timeout=WAIT_S) if r.ok is not None]
        assert [str(s.key_expr) for s in alive] == [f"{prefix}/@alive/edge-01"]
        # With access control off (as shipped), an operator's acknowledgement reaches the daemon.
        assert wait_for(lambda: bool(got["commands"]), lambda: p["hmi"].put(f"{prefix}/{gauge}/alarm/ack", b"{}"))
        assert got["commands"][0] == (gauge, "ack")


def test_router_access_control_example_blocks_alarm_commands_only() -> None:
    """router.json5's access_control, enabled for the loopback interface, refuses alarm commands
    arriving there while readings still flow."""
    with plant(central_overrides={"access_control/enabled": True,
                                  "access_control/subjects": [{"id": "edge-network", "interfaces": ["lo"]}]}) as p:
        got, prefix, gauge = p["got"], p["prefix"], p["gauge"]
        assert wait_for(lambda: bool(got["readings"]), lambda: p["sink"].publish_reading(reading(gauge)))
        for _ in range(20):
            p["hmi"].put(f"{prefix}/{gauge}/alarm/ack", b"{}")
            time.sleep(0.1)
        assert got["commands"] == []
