"""Real Zenoh sessions on loopback for the tests (no multicast, explicit endpoints, bounded waits)."""

from __future__ import annotations

import json
import socket
import time
from collections.abc import Iterator

import zenoh

from gauged.config.model import ZenohConfig
from gauged.sources.zenoh_session import open_session


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def peer_config(connect: str) -> zenoh.Config:
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("listen/endpoints", "[]")
    conf.insert_json5("connect/endpoints", json.dumps([connect]))
    return conf


def zenoh_pair_sessions() -> Iterator[tuple[zenoh.Session, zenoh.Session]]:
    """(daemon session listening on loopback, peer session connected to it); both closed after."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    daemon = open_session(ZenohConfig(mode="peer", listen=[endpoint], multicast_scouting=False))
    peer = zenoh.open(peer_config(endpoint))
    try:
        deadline = time.monotonic() + 5
        while not peer.info.peers_zid() and time.monotonic() < deadline:
            time.sleep(0.02)
        assert peer.info.peers_zid(), "peer session did not connect on loopback"
        yield daemon, peer
    finally:
        peer.close()
        daemon.close()
