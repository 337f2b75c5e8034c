"""Exercise what the daemon's process does at run time, for the hardening tests to watch.

Run as a script (``python runtime_probe.py [--expect-mdwe] WORKDIR``), usually under
``sandbox_exec.py``; not collected by pytest. It loads a config, decodes a JPEG with OpenCV, runs
an onnxruntime session (a model shipped in ``gauged/models`` when there is one, else
onnxruntime's bundled example), publishes a reading through the real Zenoh, MCAP and Prometheus
sinks, reads it back over Zenoh and HTTP, and sends sd_notify datagrams. ``--expect-mdwe`` first
checks that writable+executable memory is refused, i.e. that the memory-deny-write-execute
restriction set by the launcher survived ``execve``. Exit 0 and a last line ``probe ok`` when
everything worked.

This covers the libraries' code paths, not the daemon's main loop; a test of ``gauged run`` itself
under the same restrictions belongs with the daemon's tests.
"""

from __future__ import annotations

import mmap
import socket
import sys
import time
import urllib.request
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def check_mdwe() -> None:
    """Fail unless writable+executable memory is refused (MemoryDenyWriteExecute is in force)."""
    try:
        mmap.mmap(-1, mmap.PAGESIZE, prot=mmap.PROT_READ | mmap.PROT_WRITE | mmap.PROT_EXEC)
    except PermissionError:
        print("mdwe: a writable+executable mapping is refused")
        return
    raise SystemExit("mdwe: expected in force, but W+X memory is allowed")


def run_ocr(int8_detector) -> None:
    import numpy as np

    from gauged.reader.ocr.engine import OcrEngine, OcrUnavailable

    try:
        engine = OcrEngine(threads=2, int8_detector=int8_detector)
    except OcrUnavailable as exc:
        print(f"ocr: not installed ({exc})")
        return
    texts = engine.detect(np.full((96, 96, 3), 255, np.uint8), max_side=96)
    print(f"ocr: {engine.model_files[0].name} -> {len(texts)} texts on a blank image")


def run_onnx() -> None:
    import numpy as np
    import onnxruntime as ort

    from gauged.reader.onnx_model import OnnxModel

    shipped = sorted((REPO / "gauged" / "models").glob("*.onnx"))
    if shipped:
        for path in shipped:
            if path.name.startswith("ocr_"):  # the OCR's own files run in OcrEngine, below
                continue
            if path.name == "numbers.onnx":  # reads text lines, not images
                from gauged.reader.ocr.number_net import NumberNet

                print(f"onnx: {path.name} -> {NumberNet(path, threads=2).read([np.zeros((20, 40, 3), np.uint8)])}")
                continue
            if path.name == "minus.onnx":  # reads the left end of text lines, not images
                from gauged.reader.ocr.minus_net import MinusNet

                print(f"onnx: {path.name} -> {MinusNet(path, threads=2).log_odds([np.zeros((20, 40, 3), np.uint8)]).shape}")
                continue
            if path.name == "notch_check.onnx":  # looks at the crop model's peaks, not at an image
                run_notch_check(path)
                continue
            model = OnnxModel(path, threads=2)
            out = model(np.zeros((model.input_size, model.input_size, 3), np.float32))
            print(f"onnx: {path.name} -> {out.shape}")
        from gauged.reader.factory import OCR_DET_INT8_MODEL

        run_ocr(REPO / "gauged" / "models" / OCR_DET_INT8_MODEL)
        return
    from onnxruntime.datasets import get_example

    options = ort.SessionOptions()
    options.intra_op_num_threads = 2
    session = ort.InferenceSession(get_example("sigmoid.onnx"), options, providers=["CPUExecutionProvider"])
    (inp,) = session.get_inputs()
    out = session.run(None, {inp.name: np.zeros([d if isinstance(d, int) else 1 for d in inp.shape], np.float32)})
    print(f"onnx: bundled sigmoid.onnx -> {out[0].shape} (no model shipped in gauged/models yet)")


def run_notch_check(path: Path) -> None:
    import numpy as np

    from gauged.reader.stages.keypoints import CROP_CHANNELS, decode_crop_maps
    from gauged.reader.stages.notch_check import NotchCheck

    logits = np.full((len(CROP_CHANNELS), 128, 128), -5.0, np.float32)
    logits[CROP_CHANNELS.index("major"), 40, 60] = 5.0
    keypoints = decode_crop_maps(logits, 256)
    p = NotchCheck(path, threads=2).probabilities(np.zeros((256, 256, 3), np.float32), logits, keypoints)
    print(f"onnx: {path.name} -> {p.shape} for {len(keypoints.major)} peak")


def decode_jpeg() -> None:
    import cv2
    import numpy as np

    image = np.random.default_rng(0).integers(0, 255, (240, 320, 3), np.uint8)
    ok, jpeg = cv2.imencode(".jpg", image)
    assert ok
    decoded = cv2.imdecode(jpeg, cv2.IMREAD_COLOR)
    print(f"cv2: decoded {decoded.shape}")


def publish_through_sinks(workdir: Path) -> None:
    import zenoh

    from gauged.config.model import ZenohConfig
    from gauged.metrics import Metrics
    from gauged.sinks.mcap_sink import McapSink
    from gauged.sinks.prometheus_sink import PrometheusSink
    from gauged.sinks.zenoh_sink import ZenohSink
    from gauged.sources.zenoh_session import open_session
    from gauged.types import Quality, Reading, ScaleInfo

    reading = Reading(gauge="g1", camera="cam1", stamp_ns=time.time_ns(), value=4.2, raw_value=4.25, unit="bar",
                      quality=Quality.GOOD, confidence=0.9, scale=ScaleInfo(0.0, 10.0, "bar", True))
    metrics = Metrics()
    prom = PrometheusSink(metrics, "127.0.0.1:0", gauges=["g1"])
    mcap = McapSink(workdir / "mcap")
    # No multicast scouting: the probe talks to itself over loopback only.
    session = open_session(ZenohConfig(mode="peer", listen=["tcp/127.0.0.1:0"], multicast_scouting=False))
    received: list[zenoh.Sample] = []
    subscriber = session.declare_subscriber("probe/**", received.append)
    sink = ZenohSink(session, "probe", "node1", gauges=["g1"])
    try:
        for out in (prom, mcap, sink):
            out.publish_reading(reading)
        deadline = time.monotonic() + 5
        while not received and time.monotonic() < deadline:
            time.sleep(0.01)
        assert received, "zenoh: the reading was not received"
        replies = list(session.get("probe/g1/reading", timeout=5.0))
        assert replies and replies[0].ok is not None, "zenoh: the queryable did not answer"
        print(f"zenoh: received {received[0].key_expr}, queryable answered")
        with urllib.request.urlopen(f"http://127.0.0.1:{prom.port}/metrics", timeout=5) as response:
            body = response.read().decode()
        assert 'gauged_reading_value{gauge="g1",unit="bar"} 4.2' in body, "prometheus: reading missing"
        print("prometheus: /metrics served the reading")
    finally:
        sink.close()
        subscriber.undeclare()
        session.close()
        mcap.close()
        prom.close()
    assert mcap.files and all(f.stat().st_size > 0 for f in mcap.files), "mcap: no file written"
    print(f"mcap: wrote {[f.name for f in mcap.files]}")


def notify_systemd(workdir: Path) -> None:
    from gauged.systemd_notify import SystemdNotifier

    path = workdir / "notify.sock"
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as server:
        server.bind(str(path))
        notifier = SystemdNotifier({"NOTIFY_SOCKET": str(path)})
        assert notifier.ready("probe") and notifier.watchdog()
        assert server.recv(4096).startswith(b"READY=1")
        assert server.recv(4096) == b"WATCHDOG=1"
    print("sd_notify: READY=1 and WATCHDOG=1 delivered")


def main(argv: list[str]) -> int:
    workdir = Path([a for a in argv if not a.startswith("--")][0])
    if "--expect-mdwe" in argv:
        check_mdwe()
    from gauged.config import load_config

    config = load_config(REPO / "config" / "gauged.example.yaml")
    print(f"config: {len(config.gauges)} gauges")
    decode_jpeg()
    run_onnx()
    publish_through_sinks(workdir)
    notify_systemd(workdir)
    print("probe ok")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
