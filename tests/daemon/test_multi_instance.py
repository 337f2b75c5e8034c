"""Two edge computers on one Zenoh router: a real router and two real ``gauged run`` processes on loopback.

The router reads ``deploy/zenoh/router.json5`` (only its listen endpoint moved to a free loopback
port): ``zenohd`` when it is installed, else zenoh-python in router mode (``tests/daemon/zenoh_router.py``).
``edge-01`` (Zenoh ``client``, the demo's camera and four gauges) and ``edge-02`` (``peer``, the plant
demo's two cameras and four of its gauges) connect to the router and nothing else; multicast scouting
is off everywhere. A camera driver session on the router publishes the bundled recordings' JPEG frames
on each node's camera keys (``plant-a/<node>/<camera>/image/compressed``), stamped now, and an HMI
session on the router watches ``gauged/**``, the liveliness tokens, and asks the queryables.

Checked, in order: every gauge of both daemons is read and published under ``gauged/plant-a``; a get
on ``gauged/plant-a/**`` returns each gauge's latest reading and alarm state from both; operator
commands (ack, shelve) reach the daemon that owns the gauge; SIGKILL of edge-02 withdraws its token
(the HMI sees the delete) while edge-01 keeps publishing and alone answers the get; restarted,
edge-02 takes its alarm states back from its state files (the acknowledged alarm stays acknowledged,
not re-annunciated; the shelve keeps its end and its operator) and publishes again.
"""

from __future__ import annotations

import json
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import yaml
import zenoh

from gauged.sources.image_decode import ImageMessage
from gauged.sources.mcap_read import ImageDecoder, McapMessages
from tests.daemon.zenoh_router import REPO, router_argv, wait_listening
from tests.deploy.daemon_process import DaemonProcess, free_port, require_daemon_inputs

SITE, PREFIX = "plant-a", "gauged/plant-a"
ROUTER_CONFIG = REPO / "deploy" / "zenoh" / "router.json5"
FRAME_PERIOD_S = 1.0  # per camera: 2 cores run both daemons and the router
FRAMES_PER_CAMERA = 12
ACKED = ("pump-discharge", "high")  # ~95 psi, its limit lowered to 60 so it is active throughout
SHELVED = ("feedwater-temp", "high")

pytestmark = [pytest.mark.slow, pytest.mark.timeout(150)]


@dataclass
class Edge:
    """One edge computer: its node name, Zenoh mode, recordings' cameras and gauges, and its process."""

    node: str
    mode: str
    recording: str
    cameras: tuple[str, ...]
    gauges: tuple[str, ...]
    overrides: dict[str, dict] = field(default_factory=dict)  # gauge -> alarms
    frames: dict[str, list[bytes]] = field(default_factory=dict)  # camera -> JPEG frames
    process: DaemonProcess | None = None
    config: Path | None = None

    def camera_key(self, camera: str) -> str:
        return f"{SITE}/{self.node}/{camera}/image/compressed"

    def write_config(self, workdir: Path, router: str) -> None:
        """The recording's own config (ROIs, scales, alarms) as this node's live config over Zenoh."""
        base = yaml.safe_load((REPO / "recordings" / f"{self.recording}.yaml").read_text())
        gauges = [g for g in base["gauges"] if g["id"] in self.gauges]
        for gauge in gauges:
            gauge.setdefault("alarms", {}).update(self.overrides.get(gauge["id"], {}))
        zenoh_section = {"mode": self.mode, "connect": [router], "multicast_scouting": False}
        if self.mode == "peer":
            zenoh_section["listen"] = []  # reachable through the router only
        config = {
            "site": SITE, "node": self.node, "zenoh": zenoh_section,
            "cameras": [{"id": c, "source": {"type": "zenoh", "key": self.camera_key(c)}} for c in self.cameras],
            "gauges": gauges,
            "outputs": {"zenoh": {"prefix": PREFIX}, "mcap": {"enabled": False}, "prometheus": {"enabled": False}},
            "state": {"dir": str(workdir / "state")},
        }
        workdir.mkdir(parents=True, exist_ok=True)
        self.config = workdir / "gauged.yaml"
        self.config.write_text(yaml.safe_dump(config, sort_keys=False))

    def start(self) -> None:
        assert self.config is not None
        self.process = DaemonProcess(self.config, self.config.parent)

    def state(self, gauge: str) -> dict:
        """The gauge's state file as the daemon last wrote it ({} while there is none)."""
        assert self.config is not None
        path = self.config.parent / "state" / f"{gauge}.json"
        return json.loads(path.read_text()) if path.is_file() else {}


EDGES = (
    Edge("edge-01", "client", "demo", ("cam1",),
         ("boiler-pressure", "steam-line", "feed-tank-temp", "header-pressure")),
    Edge("edge-02", "peer", "plant-demo", ("cam1", "cam2"),
         ("feedwater-temp", "steam-header", "pump-discharge", "tank-vacuum"),
         overrides={"pump-discharge": {"high": 60.0}}),
)


def recorded_jpegs(recording: str, camera: str, count: int) -> list[bytes]:
    """The first ``count`` JPEG frames of ``/<camera>/image`` in a bundled recording."""
    decoder, frames = ImageDecoder(), []
    for schema, channel, message in McapMessages(REPO / "recordings" / f"{recording}.mcap", [f"/{camera}/image"]):
        image = decoder.parse(schema, channel, message)
        assert isinstance(image, ImageMessage), image
        frames.append(image.data)
        if len(frames) == count:
            break
    return frames


def client_config(endpoint: str) -> zenoh.Config:
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("connect/endpoints", json.dumps([endpoint]))
    config.insert_json5("scouting/multicast/enabled", "false")
    return config


class CameraDrivers(threading.Thread):
    """While ``publishing`` is set, publishes each edge's next frame on each of its camera keys every
    FRAME_PERIOD_S (to nobody while that edge is down, as a real camera driver would)."""

    def __init__(self, session: zenoh.Session, edges: tuple[Edge, ...]) -> None:
        super().__init__(name="camera-drivers", daemon=True)
        self.session, self.edges = session, edges
        self.halt, self.publishing = threading.Event(), threading.Event()

    def run(self) -> None:
        index = 0
        while not self.halt.wait(FRAME_PERIOD_S):
            if not self.publishing.is_set():
                continue
            for edge in self.edges:
                for camera, frames in edge.frames.items():
                    self.session.put(edge.camera_key(camera), frames[index % len(frames)],
                                     encoding=zenoh.Encoding.IMAGE_JPEG, timestamp=self.session.new_timestamp())
            index += 1


class Hmi:
    """A control-room session on the router: readings and alarms under gauged/**, and liveliness.

    Samples wait in Zenoh channels and are taken on the test's thread (``poll``).
    """

    def __init__(self, session: zenoh.Session) -> None:
        self.session = session
        self.samples = session.declare_subscriber("gauged/**", zenoh.handlers.FifoChannel(100_000))
        self.tokens = session.liveliness().declare_subscriber(f"{PREFIX}/@alive/*", zenoh.handlers.FifoChannel(100),
                                                              history=True)
        self.readings: list[tuple[str, dict]] = []  # (key, reading) in arrival order
        self.alarms: list[dict] = []
        self.alive: list[tuple[str, str]] = []  # ("PUT" or "DELETE", node)

    def poll(self) -> Hmi:
        while (sample := self.samples.try_recv()) is not None:
            key = str(sample.key_expr)
            if key.endswith("/reading"):
                self.readings.append((key, json.loads(sample.payload.to_bytes())))
            elif key.endswith("/alarm"):
                self.alarms.append(json.loads(sample.payload.to_bytes()))
        while (sample := self.tokens.try_recv()) is not None:
            self.alive.append((str(sample.kind).rsplit(".", 1)[-1], str(sample.key_expr).rsplit("/", 1)[-1]))
        return self

    def read_since(self, stamp_ns: int) -> set[str]:
        """Gauges with a reading of a frame stamped at or after ``stamp_ns``."""
        return {r["gauge"] for _, r in self.poll().readings if r["stamp_ns"] >= stamp_ns and r["quality"] != "stale"}

    def latest(self) -> dict[str, dict]:
        return {key: reading for key, reading in self.poll().readings}

    def get(self, selector: str, payload: dict | None = None) -> dict[str, dict]:
        """key -> JSON body of every ok reply (only readings and alarm states for a wildcard)."""
        body = None if payload is None else json.dumps(payload)
        replies = self.session.get(selector, payload=body, timeout=10)
        return {str(r.ok.key_expr): json.loads(r.ok.payload.to_bytes()) for r in replies
                if r.ok is not None and str(r.ok.key_expr).endswith(("/reading", "/alarm", "/ack", "/shelve"))}


def wait_until(condition: Callable[[], object], timeout: float, what: str, edges: tuple[Edge, ...] = ()) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        for edge in edges:
            if edge.process is not None and not edge.process.alive():
                raise AssertionError(f"{edge.node} exited while waiting for {what}: {edge.process.describe()}")
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")
        time.sleep(0.05)


def settle(hmi: Hmi, quiet_s: float = 1.0, timeout: float = 15.0) -> None:
    """Wait until no reading has arrived for ``quiet_s`` (the daemons read every frame sent)."""
    deadline, count, since = time.monotonic() + timeout, -1, time.monotonic()
    while time.monotonic() < deadline:
        if len(hmi.poll().readings) != count:
            count, since = len(hmi.readings), time.monotonic()
        elif time.monotonic() - since >= quiet_s:
            return
        time.sleep(0.05)
    raise AssertionError(f"readings still arriving after {timeout:g} s without frames")


def alarm_status(state: dict, level: str) -> dict:
    """One level's status in a queryable's alarm document ({gauge, alarms: [status, ...]})."""
    return next(s for s in state["alarms"] if s["level"] == level)


@contextmanager
def router(tmp_path: Path) -> Iterator[str]:
    """A router on a free loopback port, its endpoint; skips when none can be started."""
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    log = (tmp_path / "router.log").open("wb")
    proc = subprocess.Popen(router_argv(ROUTER_CONFIG, endpoint), cwd=REPO, stdin=subprocess.DEVNULL,
                            stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        if not wait_listening("127.0.0.1", port, proc, timeout=15):
            pytest.skip(f"no Zenoh router could be started ({' '.join(router_argv(ROUTER_CONFIG, endpoint))}): "
                        + (tmp_path / "router.log").read_text(errors="replace")[-500:])
        yield endpoint
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
        log.close()


@pytest.fixture
def plant(tmp_path: Path) -> Iterator[tuple[tuple[Edge, ...], Hmi, CameraDrivers]]:
    require_daemon_inputs()
    edges = tuple(Edge(e.node, e.mode, e.recording, e.cameras, e.gauges, dict(e.overrides)) for e in EDGES)
    with ExitStack() as stack:
        endpoint = stack.enter_context(router(tmp_path))
        for edge in edges:
            edge.frames = {c: recorded_jpegs(edge.recording, c, FRAMES_PER_CAMERA) for c in edge.cameras}
            edge.write_config(tmp_path / edge.node, endpoint)
            edge.start()
            stack.callback(lambda e=edge: e.process.stop(timeout=15))
        hmi_session, driver_session = zenoh.open(client_config(endpoint)), zenoh.open(client_config(endpoint))
        stack.callback(driver_session.close)
        stack.callback(hmi_session.close)
        hmi = Hmi(hmi_session)
        drivers = CameraDrivers(driver_session, edges)
        drivers.start()
        stack.callback(drivers.join, 5)
        stack.callback(drivers.halt.set)
        yield edges, hmi, drivers


def test_two_edge_computers_share_one_router_and_survive_a_crash(plant) -> None:
    (edge1, edge2), hmi, drivers = plant
    both = (edge1, edge2)
    # Both daemons come up (model loading takes a few seconds each) and declare their tokens.
    wait_until(lambda: {("PUT", e.node) for e in both} <= set(hmi.poll().alive), 45, "both liveliness tokens", both)
    started_ns = time.time_ns()
    drivers.publishing.set()

    # (1) One subscriber on the router sees every gauge of both edge computers.
    all_gauges = {*edge1.gauges, *edge2.gauges}
    wait_until(lambda: hmi.read_since(started_ns) >= all_gauges, 40, "a reading of every gauge", both)
    for key, reading in hmi.readings:
        assert key == f"{PREFIX}/{reading['gauge']}/reading"
    valued = {r["gauge"] for _, r in hmi.readings if r["value"] is not None}
    for edge in both:  # real reads of the recordings' dials, not only refusals
        assert len(valued & set(edge.gauges)) >= 2, f"{edge.node}: gauges with a value: {sorted(valued)}"

    # Operator commands go through the router to the daemon that owns the gauge.
    wait_until(lambda: any(a["gauge"] == ACKED[0] and a["level"] == ACKED[1] and a["state"] == "active_unacknowledged"
                           for a in hmi.poll().alarms), 30, f"{ACKED} to activate", both)
    ack = hmi.get(f"{PREFIX}/{ACKED[0]}/alarm/ack", {"level": ACKED[1], "who": "alice", "why": "pump 2 started"})
    assert ack[f"{PREFIX}/{ACKED[0]}/alarm/ack"]["ok"] is True, ack
    shelve = hmi.get(f"{PREFIX}/{SHELVED[0]}/alarm/shelve",
                     {"level": SHELVED[1], "who": "bob", "why": "sensor swap", "duration_s": 1800})
    assert shelve[f"{PREFIX}/{SHELVED[0]}/alarm/shelve"]["ok"] is True, shelve

    # (2) With the cameras paused, a get returns every gauge's latest reading and alarm state, from both.
    drivers.publishing.clear()
    settle(hmi)
    state = hmi.get(f"{PREFIX}/**")
    latest = hmi.latest()
    for gauge in all_gauges:
        assert state[f"{PREFIX}/{gauge}/reading"] == latest[f"{PREFIX}/{gauge}/reading"], gauge
        assert state[f"{PREFIX}/{gauge}/alarm"]["gauge"] == gauge
    assert alarm_status(state[f"{PREFIX}/{ACKED[0]}/alarm"], ACKED[1])["state"] == "active_acknowledged"
    shelved = alarm_status(state[f"{PREFIX}/{SHELVED[0]}/alarm"], SHELVED[1])
    assert shelved["state"] == "shelved" and shelved["shelved_by"] == "bob", shelved
    alive = {str(r.ok.key_expr) for r in hmi.session.liveliness().get(f"{PREFIX}/@alive/*", timeout=5) if r.ok}
    assert alive == {f"{PREFIX}/@alive/{e.node}" for e in both}

    # The changed alarm states are on disk within a tick or two (the daemon saves when they change).
    wait_until(lambda: edge2.state(ACKED[0]).get("alarms", {}).get(ACKED[1], {}).get("state") == "active_acknowledged"
               and edge2.state(SHELVED[0]).get("alarms", {}).get(SHELVED[1], {}).get("state") == "shelved",
               10, "edge-02's state files", both)

    # (3) SIGKILL edge-02: the router drops its session and with it the token; edge-01 goes on.
    drivers.publishing.set()
    assert edge2.process is not None
    edge2.process.proc.kill()
    assert edge2.process.proc.wait(10) == -signal.SIGKILL
    killed_ns = time.time_ns()
    wait_until(lambda: ("DELETE", edge2.node) in hmi.poll().alive, 15, "edge-02's token to be withdrawn", (edge1,))
    assert ("DELETE", edge1.node) not in hmi.alive
    wait_until(lambda: hmi.read_since(killed_ns) >= set(edge1.gauges), 20, "edge-01's readings after the kill", (edge1,))
    answered = {key.split("/")[2] for key in hmi.get(f"{PREFIX}/**")}
    assert answered == set(edge1.gauges), answered
    alive = {str(r.ok.key_expr) for r in hmi.session.liveliness().get(f"{PREFIX}/@alive/*", timeout=5) if r.ok}
    assert alive == {f"{PREFIX}/@alive/{edge1.node}"}

    # (4) Restarted, edge-02 takes back its alarm states from its state files.
    alarms_before = len(hmi.poll().alarms)
    edge2.start()
    wait_until(lambda: hmi.poll().alive.count(("PUT", edge2.node)) == 2, 45, "edge-02's token again", both)
    restarted_ns = time.time_ns()
    acked = alarm_status(hmi.get(f"{PREFIX}/{ACKED[0]}/alarm")[f"{PREFIX}/{ACKED[0]}/alarm"], ACKED[1])
    assert acked["state"] == "active_acknowledged" and acked["active"] is True, acked
    restored = alarm_status(hmi.get(f"{PREFIX}/{SHELVED[0]}/alarm")[f"{PREFIX}/{SHELVED[0]}/alarm"], SHELVED[1])
    assert restored["state"] == "shelved" and restored["shelved_by"] == "bob", restored
    assert restored["shelved_until_ns"] == shelved["shelved_until_ns"]
    stderr = edge2.process.stderr()
    for gauge in edge2.gauges:
        assert f"restored state of {gauge} saved" in stderr, gauge

    # ... and publishes again; the acknowledged alarm is not annunciated anew.
    wait_until(lambda: hmi.read_since(restarted_ns) >= all_gauges, 40, "readings of every gauge after the restart",
               both)
    again = [a for a in hmi.poll().alarms[alarms_before:] if (a["gauge"], a["level"]) == ACKED]
    assert not any(a["state"] == "active_unacknowledged" for a in again), again
    assert edge1.process is not None and edge1.process.alive()
