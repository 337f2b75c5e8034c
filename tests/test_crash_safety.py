"""Crash safety of a running daemon's MCAP output: SIGKILL loses at most the open chunk, SIGTERM nothing.

``python -m gauged run`` replays the bundled demo (fast pace, the demo's gauges) with small MCAP chunks
(``chunk_kb: 4``) flushed often (``flush_s: 0.2``) and Prometheus on a free loopback port, and is
killed mid-recording. What it wrote is compared with ``gauged replay`` of the same recording and
gauges, whose readings are the same bytes (frame time drives everything, see tests/test_e2e_daemon.py):

- SIGKILL: the file has no footer, is read linearly (mcap's ``NonSeekingReader``) up to the cut,
  and its readings are a prefix of the replay's; what is missing is at most one chunk's worth of
  the readings the daemon had counted (``gauged_reads_total``, scraped just before the kill).
- SIGTERM: the file is finished (summary and footer) and holds exactly the readings of every frame
  the daemon read; the count of frames read is the daemon's own, from the tracker state it saves on
  stop after its workers have ended, and the final table and every alarm it logged match the file.

Readings the ticker may add between frames (a ``stale`` reading stamped with the extrapolated frame
clock) are not frame readings and are left out of the comparison.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
import yaml
from mcap.reader import NonSeekingReader, breakup_chunk, make_reader
from mcap.records import Channel, Chunk, Message
from mcap.stream_reader import StreamReader
from prometheus_client.parser import text_string_to_metric_families

from gauged.reader.factory import CROP_MODEL
from gauged.reader.onnx_model import packaged_model_path
from tests.sources.conftest import free_port

REPO = Path(__file__).resolve().parents[1]
DEMO, DEMO_CONFIG = REPO / "recordings" / "demo.mcap", REPO / "recordings" / "demo.yaml"
MAGIC = b"\x89MCAP0\r\n"
READINGS, ALARMS = "/gauged/readings", "/gauged/alarms"
CHUNK_KB, FLUSH_S = 4, 0.2

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not packaged_model_path(CROP_MODEL).is_file(),
                       reason=f"gauged/models/{CROP_MODEL} is missing: train and export it (gauged/models/README.md)"),
]


class Reference:
    """The readings of ``gauged replay`` of the demo: [(log_time, bytes)], the frame stamps, the gauges."""

    def __init__(self, readings: list[tuple[int, bytes]]):
        self.readings = readings
        self.frames = sorted({t for t, _ in readings})
        self.gauges = len(readings) // len(self.frames)
        self.quality = {(json.loads(d)["gauge"], t): json.loads(d)["quality"] for t, d in readings}


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Reference:
    out = tmp_path_factory.mktemp("reference") / "replay.mcap"
    done = subprocess.run([sys.executable, "-m", "gauged", "replay", str(DEMO), "--config", str(DEMO_CONFIG),
                           "--out", str(out)], cwd=REPO, capture_output=True, timeout=120)
    assert done.returncode == 0, done.stderr.decode()[-2000:]
    with out.open("rb") as stream:
        readings = [(m.log_time, m.data) for _, c, m in make_reader(stream).iter_messages(topics=[READINGS])]
    return Reference(readings)


def run_config(tmp_path: Path, port: int) -> Path:
    """The demo config, replaying fast into small, often flushed MCAP chunks, metrics on ``port``."""
    config = yaml.safe_load(DEMO_CONFIG.read_text())
    config["cameras"][0]["source"].update(path=str(DEMO), pace="fast", loop=False)
    config["outputs"] = {"zenoh": {"enabled": False},
                         "mcap": {"dir": str(tmp_path / "out"), "chunk_kb": CHUNK_KB, "flush_s": FLUSH_S},
                         "prometheus": {"listen": f"127.0.0.1:{port}"}}
    config["state"] = {"dir": str(tmp_path / "state")}
    path = tmp_path / "gauged.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


@contextmanager
def daemon_process(tmp_path: Path) -> Iterator[tuple[subprocess.Popen, int]]:
    """``python -m gauged run`` on the demo; (process, metrics port); killed if still running after."""
    port = free_port()
    config = run_config(tmp_path, port)
    with (tmp_path / "stdout").open("wb") as out, (tmp_path / "stderr").open("wb") as err:
        proc = subprocess.Popen([sys.executable, "-m", "gauged", "run", "--config", str(config)],
                                cwd=tmp_path, stdout=out, stderr=err)
    try:
        yield proc, port
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait(timeout=10)


def reads_counted(port: int) -> int | None:
    """Sum of ``gauged_reads_total`` over the gauges (readings produced), None while not serving."""
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=1) as response:
            text = response.read().decode()
    except OSError:
        return None
    return int(sum(s.value for f in text_string_to_metric_families(text) if f.name == "gauged_reads"
                   for s in f.samples if s.name == "gauged_reads_total"))


def wait_until(condition, timeout: float, what: str, proc: subprocess.Popen, tmp_path: Path) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if proc.poll() is not None or time.monotonic() > deadline:
            stderr = (tmp_path / "stderr").read_text()[-2000:]
            raise AssertionError(f"daemon {'exited' if proc.poll() is not None else 'too slow'} "
                                 f"waiting for {what}:\n{stderr}")
        time.sleep(0.05)


def output_file(tmp_path: Path) -> Path:
    (path,) = sorted((tmp_path / "out").glob("*.mcap"))
    return path


def read_leniently(path: Path) -> tuple[dict[str, list[tuple[int, bytes]]], Exception | None]:
    """Messages by topic, in file order, up to the first truncated record; and what stopped the read."""
    topics: dict[str, list[tuple[int, bytes]]] = {}
    with path.open("rb") as stream:
        try:
            reader = NonSeekingReader(stream, validate_crcs=True)
            for _schema, channel, message in reader.iter_messages(log_time_order=False):  # file order: no sort
                topics.setdefault(channel.topic, []).append((message.log_time, message.data))
        except Exception as err:  # noqa: BLE001 - the cut of an unfinished file
            return topics, err
    return topics, None


def scan_chunks(path: Path) -> list[tuple[set[str], int]]:
    """(channel topics, message count) of each complete chunk, read record by record up to the cut."""
    chunks = []
    with path.open("rb") as stream:
        try:
            for record in StreamReader(stream, emit_chunks=True).records:
                if isinstance(record, Chunk):  # mcap's writer puts schemas and channels into the chunks
                    inner = breakup_chunk(record, validate_crc=True)
                    chunks.append(({r.topic for r in inner if isinstance(r, Channel)},
                                   sum(isinstance(r, Message) for r in inner)))
        except Exception:  # noqa: BLE001 - the cut of an unfinished file
            pass
    return chunks


def frame_readings(readings: list[tuple[int, bytes]], reference: Reference) -> list[tuple[int, bytes]]:
    """The readings of frames (stamped with a frame's time), without the ticker's stale readings."""
    frames = set(reference.frames)
    return [(t, d) for t, d in readings if t in frames]


def test_sigkill_mid_recording_loses_at_most_the_open_chunk(tmp_path, reference):
    with daemon_process(tmp_path) as (proc, port):
        started = time.monotonic()
        wait_until(lambda: (reads_counted(port) or 0) >= 24 * reference.gauges, 40, "24 frames read", proc, tmp_path)
        counted = reads_counted(port)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
        ran_s = time.monotonic() - started
    assert proc.returncode == -signal.SIGKILL
    path = output_file(tmp_path)
    data = path.read_bytes()
    assert data.startswith(MAGIC) and not data.endswith(MAGIC), "the killed daemon's file must be unfinished"

    topics, cut = read_leniently(path)
    readings = topics.get(READINGS, [])
    assert cut is not None  # the linear read stops where the file ends, without a footer
    # Every complete chunk was read. The sink registers its three channels when it opens the file, so
    # they travel in the first chunk: the alarm channel is there before (and without) any alarm (and
    # the camera's overlay channel, registered at the first frame, may be there too).
    chunks = scan_chunks(path)
    sizes = [count for _, count in chunks]
    assert sum(len(v) for v in topics.values()) == sum(sizes)
    assert chunks[0][0] >= {READINGS, "/gauged/failures", ALARMS}
    assert readings, f"nothing readable after {ran_s:.1f} s"
    read_back = frame_readings(readings, reference)
    assert read_back == reference.readings[:len(read_back)]
    # A chunk is closed once it holds more than chunk_kb: it never holds more messages than this.
    chunk_capacity = CHUNK_KB * 1024 // min(len(d) for _, d in readings) + 1
    lost = counted - len(readings)
    print(f"SIGKILL after {ran_s:.1f} s: {counted} readings counted by the daemon before the kill, "
          f"{len(readings)} read back from {len(sizes)} complete chunks (largest {max(sizes)} messages, "
          f"capacity {chunk_capacity}), {lost} not in the file")
    assert lost <= chunk_capacity, "more than the open chunk was lost"
    assert len(readings) <= len(reference.readings)


def test_sigterm_mid_recording_loses_nothing(tmp_path, reference):
    with daemon_process(tmp_path) as (proc, port):
        stderr = tmp_path / "stderr"
        wait_until(lambda: "alarm boiler-pressure high:" in stderr.read_text(), 40, "the boiler's high alarm",
                   proc, tmp_path)
        counted = reads_counted(port)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=30) == 0, stderr.read_text()[-2000:]
    path = output_file(tmp_path)
    assert path.read_bytes().endswith(MAGIC), "a stopped daemon finishes its file"
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        topics: dict[str, list[tuple[int, bytes]]] = {}
        for _schema, channel, message in reader.iter_messages(log_time_order=False):
            topics.setdefault(channel.topic, []).append((message.log_time, message.data))
    assert summary is not None and summary.statistics.message_count == sum(len(v) for v in topics.values())
    assert {c.topic for c in summary.channels.values()} >= {READINGS, "/gauged/failures", ALARMS}

    readings = frame_readings(topics[READINGS], reference)
    frames_in_file, rest = divmod(len(readings), reference.gauges)
    assert rest == 0 and readings == reference.readings[:len(readings)]
    assert counted is not None and len(readings) >= counted
    assert frames_in_file < len(reference.frames), "SIGTERM came after the end of the recording"

    # Frames the daemon read, by its own account: the stamp of the last good reading it saved on stop.
    last_good = [json.loads(p.read_text())["last_good"] for p in (tmp_path / "state").glob("*.json")]
    last_stamp = max(g["stamp_ns"] for g in last_good if g is not None)
    frames_read = reference.frames.index(last_stamp) + 1
    if frames_read < len(reference.frames):  # had it read one more frame, some gauge would say so
        assert any(q == "good" for (g, t), q in reference.quality.items() if t == reference.frames[frames_read])
    print(f"SIGTERM: {counted} readings counted before the signal, {frames_read} frames read, "
          f"{frames_in_file} frames ({len(readings)} readings) in the finished file")
    assert frames_in_file == frames_read

    # The final table shows the last reading of each gauge; each is the file's last reading of that gauge.
    table = {line.split()[0]: line.split() for line in (tmp_path / "stdout").read_text().splitlines()[-4:]}
    for _, data in readings[-reference.gauges:]:
        last = json.loads(data)
        row = table[last["gauge"]]
        assert row[1] == ("-" if last["value"] is None else f"{last['value']:.3g}") and last["quality"] in row
    # Every alarm the daemon logged is in the file.
    logged = [line.split("gauged.daemon.app: alarm ", 1)[1] for line in stderr.read_text().splitlines()
              if "gauged.daemon.app: alarm " in line]
    written = [json.loads(d) for _, d in topics.get(ALARMS, [])]
    assert logged, "the run was stopped after the boiler's high alarm"
    assert sorted(logged) == sorted(f"{e['gauge']} {e['level']}: {e['message']}" for e in written)
