"""Load test (issue 36): several cameras of 1280x720 JPEG over real Zenoh on loopback into `gauged run`.

    python bench/bench_load.py [--cameras 4] [--gauges 4] [--fps 15] [--seconds 60] [--warmup 20] [--repeats 1]

What runs:

- **The daemon** is a separate process, as in production: ``python -m gauged --log-format json run``
  on a generated config in a temp dir (Zenoh peer listening on a free loopback port, multicast off;
  one Zenoh camera per ``--cameras``; ``--gauges`` per camera with ROIs and scales, so they lock;
  MCAP sink, Zenoh readings and annotations, Prometheus on a free loopback port: the default outputs).
- **The cameras** are one publisher thread per camera in this process, on one Zenoh peer session
  connected to the daemon's endpoint. Each publishes ROS 2 ``sensor_msgs/msg/CompressedImage`` in
  CDR (what rmw_zenoh sends; ``gauged/sources/image_decode.py``) on
  ``bench/edge/<camera>/image/compressed``, the daemon subscribing to ``.../image/compressed/**``.
  The header stamp is the wall clock at publish time, so it is the frame's ``stamp_ns`` in the
  daemon and in its readings. Cameras are started out of phase (as unsynchronised cameras are).
- **Frames** are rendered once per camera by the synthetic engine (``gauged.synth.moving_dials``: the
  demo's dials, moved apart as in ``bench_daemon.py``, a different wall and jitter per camera),
  ``--loop-frames`` of them played forwards then backwards (so the needles never jump), JPEG q85.
- **Readings** are taken by a subscriber on ``gauged/bench/*/reading`` in this process; each is
  matched to its frame by (camera, stamp).

Measured over the ``--seconds`` window only, after a warm-up that lasts until every gauge's scale is
locked (``gauged_scale_locked``) plus 3 s, or ``--warmup`` seconds at most; before and after the
window the cameras pause until the daemon's received counters stop moving (under load Zenoh holds a
backlog), so that the frames received in the window are the frames sent in it:

- per camera: frames sent; received, dropped (replaced by a newer one before the reader took it:
  newest frame wins, ``gauged_frames_dropped_total``), skipped and invalid, from the daemon's
  Prometheus endpoint; read = received - dropped - skipped - invalid; frames whose readings this
  process got; sent - received is what the transport lost;
- latency of every reading: publish time (= the frame's stamp) -> the reading received here, p50/p99,
  and per frame to its last gauge's reading;
- the daemon's CPU (utime + stime of every thread, ``/proc/<pid>/stat``) as % of one core, its RSS
  sampled every 0.5 s and its peak (``VmHWM``), and this process's own CPU (the cameras and the
  subscriber share the same 2 cores);
- the envelope: locked gauges per core of the daemon's CPU at the fps read.

``--repeats N`` runs N fresh daemons and prints the median of each figure after the runs.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
import zenoh

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import header  # noqa: E402

from gauged.sources.image_decode import parse_ros_image_cdr  # noqa: E402
from gauged.synth.moving_dials import DialSpec, demo_dials, render_frames  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
WIDTH, HEIGHT = 1280, 720
# Where the dials hang in a 1280x720 frame (bench_daemon.STREAM_BOXES for the first four).
BOXES = [(60, 80, 360, 380), (420, 60, 700, 340), (780, 80, 1100, 400), (420, 380, 700, 660),
         (60, 420, 360, 700), (780, 420, 1100, 700), (1110, 60, 1270, 220), (1110, 400, 1270, 560)]
PREFIX = "gauged/bench"
CLK_TCK = os.sysconf("SC_CLK_TCK")
PAGE_KB = os.sysconf("SC_PAGE_SIZE") // 1024


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def camera_key(camera: str) -> str:
    return f"bench/edge/{camera}/image/compressed"


# -- frames ---------------------------------------------------------------------------------------------

def cdr_compressed_image(jpeg: bytes, frame_id: str) -> bytearray:
    """A little-endian CDR ``sensor_msgs/msg/CompressedImage`` (stamp zero: bytes 4..12 set per publish)."""
    body = bytearray(struct.pack("<iI", 0, 0))

    def string(text: str) -> None:
        raw = text.encode() + b"\0"
        body.extend(b"\0" * (-len(body) % 4))
        body.extend(struct.pack("<I", len(raw)) + raw)

    string(frame_id)
    string("jpeg")
    body.extend(b"\0" * (-len(body) % 4))
    body.extend(struct.pack("<I", len(jpeg)) + jpeg)
    body.extend(b"\0" * (-len(body) % 4))
    return bytearray(b"\x00\x01\x00\x00") + body


def dials_for(gauges: int) -> list[DialSpec]:
    demo = demo_dials()
    if gauges > len(BOXES):
        raise SystemExit(f"--gauges at most {len(BOXES)}")
    specs = []
    for i in range(gauges):
        s = demo[i % len(demo)]
        seed = s.seed if i < len(demo) else s.seed + 1000 * i
        specs.append(DialSpec(s.gauge if i < len(demo) else f"{s.gauge}-{i}", seed, s.min_value, s.max_value, s.unit,
                              BOXES[i], s.profile))
    return specs


@dataclass
class CameraFrames:
    camera: str
    payloads: list[bytearray]  # CDR messages, the loop in publish order
    rois: dict[str, tuple[int, int, int, int]]
    jpeg_kb: float


def render_camera(camera: str, index: int, dials: list[DialSpec], fps: float, loop_frames: int) -> CameraFrames:
    frames, rois = [], {}
    for stamp_ns, image, truth in render_frames(dials, loop_frames / fps, fps, seed=11 + index, width=WIDTH,
                                                height=HEIGHT):
        ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 85])
        assert ok
        frames.append(jpeg.tobytes())
        if not rois:
            for g in truth["gauges"]:
                x0, y0, x1, y1 = g["box"]
                rois[g["gauge"]] = (max(0, int(x0) - 4), max(0, int(y0) - 4), min(WIDTH, int(x1) + 5),
                                    min(HEIGHT, int(y1) + 5))
    order = frames + frames[-2:0:-1]  # forwards then backwards: the needles never jump at the wrap
    payloads = [cdr_compressed_image(jpeg, camera) for jpeg in order]
    check = parse_ros_image_cdr(bytes(payloads[0]), "compressed")
    assert check and check.data == order[0], check
    return CameraFrames(camera, payloads, rois, statistics.mean(len(j) for j in frames) / 1024)


# -- the daemon -----------------------------------------------------------------------------------------

def gauge_id(camera: str, dial: str) -> str:
    return f"{camera}-{dial}"


def write_config(tmp: Path, cameras: list[CameraFrames], dials: list[DialSpec], zenoh_endpoint: str,
                 prometheus_port: int) -> Path:
    lines = ["site: bench", "node: bench-daemon",
             f'zenoh: {{mode: peer, listen: ["{zenoh_endpoint}"], connect: [], multicast_scouting: false}}',
             "cameras:"]
    for cam in cameras:
        lines.append(f'  - {{id: {cam.camera}, source: {{type: zenoh, key: "{camera_key(cam.camera)}/**"}}}}')
    lines.append("gauges:")
    for cam in cameras:
        for d in dials:
            roi = list(cam.rois[d.gauge])
            lines.append(f"  - {{id: {gauge_id(cam.camera, d.gauge)}, camera: {cam.camera}, roi: {roi}, "
                         f"scale: {{min: {d.min_value}, max: {d.max_value}, unit: {d.unit}}}}}")
    lines += ["outputs:", f"  zenoh: {{prefix: {PREFIX}}}", f"  mcap: {{dir: {tmp / 'mcap'}, images: none}}",
              f'  prometheus: {{listen: "127.0.0.1:{prometheus_port}"}}', f"state: {{dir: {tmp / 'state'}}}"]
    path = tmp / "gauged.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def scrape(port: int) -> dict[tuple[str, tuple[tuple[str, str], ...]], float]:
    """Every sample of the daemon's /metrics: (name, sorted labels) -> value."""
    from prometheus_client.parser import text_string_to_metric_families

    with urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=5) as response:
        text = response.read().decode()
    out = {}
    for family in text_string_to_metric_families(text):
        for s in family.samples:
            out[(s.name, tuple(sorted(s.labels.items())))] = s.value
    return out


def metric(samples: dict, name: str, **labels: str) -> float:
    return samples.get((name, tuple(sorted(labels.items()))), 0.0)


def invalid(samples: dict, camera: str) -> float:
    return sum(v for (n, labels), v in samples.items()
               if n == "gauged_frames_invalid_total" and ("camera", camera) in labels)


def drain(port: int, cameras: list[str], longest_s: float) -> None:
    """Wait until no camera's received counter moved for 0.5 s (``longest_s`` at most)."""
    deadline = time.monotonic() + longest_s
    last = None
    while time.monotonic() < deadline:
        samples = scrape(port)
        now = [metric(samples, "gauged_frames_received_total", camera=c) for c in cameras]
        if now == last:
            return
        last = now
        time.sleep(0.5)


def proc_cpu_s(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime, stime (fields 14, 15)


def proc_status_kb(pid: int, key: str) -> int:
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1])
    return 0


# -- one run --------------------------------------------------------------------------------------------

@dataclass
class Result:
    seconds: float
    sent: dict[str, int]
    received: dict[str, float]
    dropped: dict[str, float]
    skipped: dict[str, float]
    invalid: dict[str, float]
    frames_with_readings: dict[str, int]
    readings: int
    readings_unmatched: int
    latency_ms: list[float]
    frame_latency_ms: list[float]
    locked: int
    gauges: int
    cpu_pct: float
    bench_cpu_pct: float
    rss_mb_max: float
    hwm_mb: float
    load: tuple[float, float]
    warmup_s: float
    notes: list[str] = field(default_factory=list)

    @property
    def read(self) -> dict[str, float]:
        return {c: self.received[c] - self.dropped[c] - self.skipped[c] - self.invalid[c] for c in self.sent}

    def pct(self, values: list[float], q: float) -> float:
        return float(np.percentile(values, q)) if values else float("nan")


class Cameras:
    """One publisher thread per camera, paced at ``fps``, stamping each frame with the publish time."""

    def __init__(self, session: zenoh.Session, cameras: list[CameraFrames], fps: float) -> None:
        self.fps = fps
        self.stop = threading.Event()
        self.paused = threading.Event()  # set: publish nothing (the pacing clock restarts on resume)
        self.epoch = 0
        self.lock = threading.Lock()
        self.counting = False
        self.sent: dict[str, int] = {c.camera: 0 for c in cameras}
        self.stamps: dict[tuple[str, int], int] = {}  # (camera, stamp_ns) -> publish time (= stamp)
        self.late: dict[str, int] = {c.camera: 0 for c in cameras}
        self.publishers = {c.camera: session.declare_publisher(camera_key(c.camera),
                                                               encoding=zenoh.Encoding.APPLICATION_CDR)
                           for c in cameras}
        start = time.monotonic() + 0.2
        self.threads = [threading.Thread(target=self._run, args=(c, start + i / (fps * len(cameras))),
                                         name=f"cam-{c.camera}", daemon=True) for i, c in enumerate(cameras)]
        for t in self.threads:
            t.start()

    def resume(self) -> None:
        """Publish again, each camera keeping its phase, from now."""
        with self.lock:
            self.epoch += 1
            self.resumed_at = time.monotonic()
        self.paused.clear()

    def _run(self, cam: CameraFrames, start: float) -> None:
        publisher = self.publishers[cam.camera]
        period = 1.0 / self.fps
        k, epoch, phase = 0, 0, start % period
        frame = 0
        while not self.stop.is_set():
            if self.paused.is_set():
                self.stop.wait(0.01)
                continue
            if self.epoch != epoch:  # resumed after a pause: restart the clock at the next slot of our phase
                with self.lock:
                    epoch, resumed = self.epoch, self.resumed_at
                start, k = resumed + (phase - resumed) % period, 0
            due = start + k * period
            wait = due - time.monotonic()
            if wait > 0:
                if self.stop.wait(wait):
                    break
            elif wait < -period:  # this thread fell a whole frame behind: skip ahead, count it
                missed = int(-wait / period)
                k += missed
                with self.lock:
                    if self.counting:
                        self.late[cam.camera] += missed
                continue
            payload = bytearray(cam.payloads[frame % len(cam.payloads)])
            frame += 1
            stamp = time.time_ns()
            payload[4:12] = struct.pack("<iI", *divmod(stamp, 1_000_000_000))
            publisher.put(bytes(payload))
            with self.lock:
                if self.counting:
                    self.sent[cam.camera] += 1
                    self.stamps[(cam.camera, stamp)] = stamp
            k += 1

    def close(self) -> None:
        self.stop.set()
        for t in self.threads:
            t.join(5)
        for p in self.publishers.values():
            p.undeclare()


def run_once(args: argparse.Namespace, cameras: list[CameraFrames], dials: list[DialSpec], tmp: Path,
             repeat: int) -> Result:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    prom = free_port()
    config = write_config(tmp, cameras, dials, endpoint, prom)
    env = dict(os.environ, ORT_DISABLE_TELEMETRY="1")  # as deploy/systemd/gauged.service sets it
    env.update(item.split("=", 1) for item in args.daemon_env)
    log_path = tmp / f"daemon-{repeat}.log"
    log = log_path.open("w")
    proc = subprocess.Popen([sys.executable, "-m", "gauged", "--log-format", "json", "run", "--config", str(config),
                             "--table", "never"], cwd=tmp, env=env, stdout=log, stderr=subprocess.STDOUT)
    n_gauges = len(cameras) * len(dials)
    notes: list[str] = []
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("listen/endpoints", "[]")
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    session = None
    cams = None
    try:
        deadline = time.monotonic() + 60
        while True:  # up when /metrics answers (after the reader and the sinks are built)
            if proc.poll() is not None:
                raise SystemExit(f"daemon exited with status {proc.returncode}; log:\n{log_path.read_text()[-3000:]}")
            try:
                scrape(prom)
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise SystemExit(f"daemon did not serve /metrics in 60 s; log:\n{log_path.read_text()[-3000:]}")
                time.sleep(0.2)
        session = zenoh.open(conf)
        deadline = time.monotonic() + 10
        while not session.info.peers_zid() and time.monotonic() < deadline:
            time.sleep(0.05)
        if not session.info.peers_zid():
            raise SystemExit("the bench's Zenoh session did not connect to the daemon")
        readings: list[tuple[bytes, int]] = []
        listening = threading.Event()

        def on_reading(sample) -> None:  # a Zenoh thread: note the time, parse later
            if listening.is_set():
                readings.append((sample.payload.to_bytes(), time.time_ns()))

        subscriber = session.declare_subscriber(f"{PREFIX}/*/reading", on_reading)
        time.sleep(0.5)  # let the subscriptions meet
        cams = Cameras(session, cameras, args.fps)
        # Warm-up: until every scale is locked (+3 s of steady state), or --warmup s at most.
        warm_start = time.monotonic()
        locked_at = None
        while time.monotonic() - warm_start < args.warmup:
            time.sleep(0.5)
            if proc.poll() is not None:
                raise SystemExit(f"daemon died in the warm-up; log:\n{log_path.read_text()[-3000:]}")
            samples = scrape(prom)
            locked = sum(metric(samples, "gauged_scale_locked", gauge=gauge_id(c.camera, d.gauge))
                         for c in cameras for d in dials)
            if locked >= n_gauges and locked_at is None:
                locked_at = time.monotonic()
            if locked_at is not None and time.monotonic() - locked_at >= 3:
                break
        warmup_s = time.monotonic() - warm_start
        if locked_at is None:
            notes.append(f"not every scale locked within the {args.warmup:g} s warm-up")
        # The measured window: pause the cameras until the frames in flight have arrived (under load
        # Zenoh can hold a backlog), so that the window's received frames are the window's sent ones.
        cams.paused.set()
        drain(prom, [c.camera for c in cameras], 3.0)
        load0 = os.getloadavg()[0]
        before = scrape(prom)
        cpu0, self0, t0 = proc_cpu_s(proc.pid), resource.getrusage(resource.RUSAGE_SELF), time.monotonic()
        with cams.lock:
            cams.counting = True
        cams.resume()
        listening.set()
        rss_max = 0
        while time.monotonic() - t0 < args.seconds:
            rss_max = max(rss_max, proc_status_kb(proc.pid, "VmRSS"))
            time.sleep(min(0.5, max(0.0, args.seconds - (time.monotonic() - t0))))
            if proc.poll() is not None:
                raise SystemExit(f"daemon died during the run; log:\n{log_path.read_text()[-3000:]}")
        with cams.lock:
            cams.counting = False
        window = time.monotonic() - t0
        cpu1, self1 = proc_cpu_s(proc.pid), resource.getrusage(resource.RUSAGE_SELF)
        cams.close()
        drain(prom, [c.camera for c in cameras], 10.0)
        time.sleep(1.0)  # the last frames' readings
        listening.clear()
        after = scrape(prom)
        rss_max = max(rss_max, proc_status_kb(proc.pid, "VmRSS"))
        hwm = proc_status_kb(proc.pid, "VmHWM")
        load1 = os.getloadavg()[0]
        subscriber.undeclare()
    finally:
        if cams is not None and not cams.stop.is_set():
            cams.close()
        if session is not None:
            session.close()
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        log.close()
    levels: dict[str, list[str]] = {}
    for line in log_path.read_text().splitlines():
        try:
            level = str(json.loads(line).get("level", ""))
        except (ValueError, AttributeError):
            level = "other"  # not a JSON log line (a traceback from a library, say)
        if level in ("warning", "error", "critical", "other"):
            levels.setdefault(level, []).append(line)
    for level, lines in levels.items():
        notes.append(f"{len(lines)} {level} line(s) in the daemon log, first: {lines[0][:300]}")

    latency, by_frame = [], {}
    unmatched = 0
    for payload, received in readings:
        r = json.loads(payload)
        key = (r.get("camera"), int(r.get("stamp_ns") or 0))
        if key not in cams.stamps:
            unmatched += 1  # a stale tick, or a frame published before or after the window
            continue
        ms_ = (received - cams.stamps[key]) / 1e6
        latency.append(ms_)
        by_frame[key] = max(by_frame.get(key, 0.0), ms_)
    names = [c.camera for c in cameras]
    delta = {name: {c: metric(after, name, camera=c) - metric(before, name, camera=c) for c in names}
             for name in ("gauged_frames_received_total", "gauged_frames_dropped_total", "gauged_frames_skipped_total")}
    locked = int(sum(metric(after, "gauged_scale_locked", gauge=gauge_id(c.camera, d.gauge))
                     for c in cameras for d in dials))
    late = sum(cams.late.values())
    if late:
        notes.append(f"publisher threads fell behind and skipped {late} frame slots in the window (not sent, not counted)")
    bench_cpu = (self1.ru_utime + self1.ru_stime - self0.ru_utime - self0.ru_stime) / window * 100
    return Result(
        seconds=window, sent=dict(cams.sent), received=delta["gauged_frames_received_total"],
        dropped=delta["gauged_frames_dropped_total"], skipped=delta["gauged_frames_skipped_total"],
        invalid={c: invalid(after, c) - invalid(before, c) for c in names},
        frames_with_readings={c: sum(1 for (cam, _) in by_frame if cam == c) for c in names},
        readings=len(readings), readings_unmatched=unmatched, latency_ms=latency,
        frame_latency_ms=list(by_frame.values()), locked=locked, gauges=n_gauges,
        cpu_pct=(cpu1 - cpu0) / window * 100, bench_cpu_pct=bench_cpu, rss_mb_max=rss_max / 1024,
        hwm_mb=hwm / 1024, load=(load0, load1), warmup_s=warmup_s, notes=notes)


# -- report ---------------------------------------------------------------------------------------------

def envelope(r: Result, fps: float, cores_total: int) -> tuple[float, float, float]:
    """(read fps per camera, locked gauges per core of daemon CPU at that fps, the same scaled to ``fps``)."""
    cams = len(r.sent)
    read_fps = sum(r.read.values()) / cams / r.seconds
    cores_used = r.cpu_pct / 100
    per_core = r.locked / cores_used if cores_used > 0 else float("nan")
    at_fps = per_core * read_fps / fps
    return read_fps, per_core, at_fps


def report(r: Result, args: argparse.Namespace, label: str) -> None:
    print(f"\n## {label}: {len(r.sent)} cameras x {r.gauges // len(r.sent)} gauges, {args.fps:g} fps, "
          f"{r.seconds:.1f} s measured after a {r.warmup_s:.1f} s warm-up; load {r.load[0]:.2f} -> {r.load[1]:.2f}")
    print(f"{'camera':<8} {'sent':>6} {'recv':>6} {'read':>6} {'dropped':>8} {'skipped':>8} {'invalid':>8} "
          f"{'lost':>5} {'w/ readings':>12} {'read fps':>9}")
    for c in r.sent:
        print(f"{c:<8} {r.sent[c]:>6} {r.received[c]:>6.0f} {r.read[c]:>6.0f} {r.dropped[c]:>8.0f} "
              f"{r.skipped[c]:>8.0f} {r.invalid[c]:>8.0f} {r.sent[c] - r.received[c]:>5.0f} "
              f"{r.frames_with_readings[c]:>12} {r.read[c] / r.seconds:>9.1f}")
    print("(lost = sent - received, +-1 at the window's edges; read = received - dropped - skipped - invalid; "
          "w/ readings = frames of the window whose readings this process received)")
    sent, dropped = sum(r.sent.values()), sum(r.dropped.values())
    print(f"{'all':<8} {sent:>6} {sum(r.received.values()):>6.0f} {sum(r.read.values()):>6.0f} {dropped:>8.0f}   "
          f"dropped {dropped / max(1, sent):.1%} of sent (newest frame wins)")
    print(f"readings received {r.readings} ({r.readings_unmatched} not of a window frame: ticks or edges); "
          f"scales locked at the end {r.locked} of {r.gauges}")
    print(f"latency publish -> reading received: p50 {r.pct(r.latency_ms, 50):.1f} ms, "
          f"p99 {r.pct(r.latency_ms, 99):.1f} ms, max {max(r.latency_ms, default=float('nan')):.1f} ms "
          f"over {len(r.latency_ms)} readings; per frame to its last gauge: p50 {r.pct(r.frame_latency_ms, 50):.1f}, "
          f"p99 {r.pct(r.frame_latency_ms, 99):.1f} ms")
    n = max(1, len(r.latency_ms) // 3)
    if len(r.latency_ms) >= 3:
        thirds = [r.latency_ms[:n], r.latency_ms[n:-n], r.latency_ms[-n:]]
        print("latency median first / middle / last third: "
              + " / ".join(f"{statistics.median(t):.1f}" for t in thirds) + " ms")
    print(f"daemon CPU {r.cpu_pct:.0f}% of one core ({r.cpu_pct / os.cpu_count():.0f}% of {os.cpu_count()}), "
          f"RSS max {r.rss_mb_max:.0f} MB (peak VmHWM {r.hwm_mb:.0f} MB); this process (cameras + subscriber) "
          f"CPU {r.bench_cpu_pct:.0f}% of one core")
    read_fps, per_core, at_fps = envelope(r, args.fps, os.cpu_count() or 1)
    print(f"envelope: {r.locked} locked gauges at {read_fps:.1f} fps read per camera on {r.cpu_pct / 100:.2f} cores "
          f"of daemon CPU = {per_core:.1f} locked gauges per core at {read_fps:.1f} fps "
          f"({at_fps:.1f} per core at {args.fps:g} fps)")
    for note in r.notes:
        print(f"note: {note}")


def median_report(results: list[Result], args: argparse.Namespace) -> None:
    med = statistics.median
    print(f"\n## median of {len(results)} runs")
    for c in results[0].sent:
        print(f"{c}: sent {med(r.sent[c] for r in results):.0f}, read {med(r.read[c] for r in results):.0f}, "
              f"dropped {med(r.dropped[c] for r in results):.0f}")
    print(f"latency p50 {med(r.pct(r.latency_ms, 50) for r in results):.1f} ms, "
          f"p99 {med(r.pct(r.latency_ms, 99) for r in results):.1f} ms; daemon CPU "
          f"{med(r.cpu_pct for r in results):.0f}%, RSS peak {med(r.hwm_mb for r in results):.0f} MB; envelope "
          f"{med(envelope(r, args.fps, os.cpu_count() or 1)[1] for r in results):.1f} locked gauges per core at "
          f"{med(envelope(r, args.fps, os.cpu_count() or 1)[0] for r in results):.1f} fps")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cameras", type=int, default=4)
    parser.add_argument("--gauges", type=int, default=4, help=f"gauges per camera (at most {len(BOXES)})")
    parser.add_argument("--fps", type=float, default=15.0, help="frames per second per camera")
    parser.add_argument("--seconds", type=float, default=60.0, help="length of the measured window")
    parser.add_argument("--warmup", type=float, default=120.0,
                        help="longest warm-up before the window (it ends 3 s after every scale locked)")
    parser.add_argument("--loop-frames", type=int, default=20,
                        help="frames rendered per camera, played forwards then backwards")
    parser.add_argument("--repeats", type=int, default=1, help="fresh daemons run; the median is printed")
    parser.add_argument("--daemon-env", action="append", default=[], metavar="KEY=VALUE",
                        help="an environment variable for the daemon (repeatable), e.g. MALLOC_ARENA_MAX=2")
    args = parser.parse_args()
    header("gauged load test: cameras over Zenoh on loopback into `gauged run`")
    print(f"# load average at start: {' '.join(f'{v:.2f}' for v in os.getloadavg())}"
          + (f"; daemon environment: {' '.join(args.daemon_env)}" if args.daemon_env else ""))
    if any("=" not in item for item in args.daemon_env):
        parser.error("--daemon-env takes KEY=VALUE")
    dials = dials_for(args.gauges)
    started = time.monotonic()
    cameras = [render_camera(f"cam{i + 1}", i, dials, args.fps, args.loop_frames) for i in range(args.cameras)]
    print(f"rendered {args.loop_frames} frames x {args.cameras} cameras ({WIDTH}x{HEIGHT}, JPEG q85, "
          f"{statistics.mean(c.jpeg_kb for c in cameras):.0f} KB a frame) in {time.monotonic() - started:.1f} s")
    results = []
    for repeat in range(args.repeats):
        with tempfile.TemporaryDirectory(prefix="gauged-load-") as tmp:
            results.append(run_once(args, cameras, dials, Path(tmp), repeat))
        report(results[-1], args, f"run {repeat + 1} of {args.repeats}")
    if len(results) > 1:
        median_report(results, args)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
