"""Steady-state cost of the daemon with locked scales, and a 15 fps 1280x720 stream with 4 gauges.

    python bench/bench_daemon.py [--runs 100] [--seconds 20] [--fps 15] [--threads 2] [--skip-stream] [--crop-model]

1. Locked cost: each gauge of the bundled demo (``recordings/demo.yaml``) is read frame after frame by
   its :class:`~gauged.daemon.gauge_runner.GaugeRunner`, as in the daemon, until its scale locks; then
   the runner's locked frames are timed on the demo's frames in turn (frame times running on at the
   recording's 2 fps): the needle scan on most, the crop model on one in ten
   (``gauge_runner.CROP_MODEL_EVERY``) and on every frame the scan cannot tell, then the tracker.
   Median, 90th percentile and mean of ``--runs`` frames per gauge after 10 warm-up frames, the share
   the crop model read, and the per-stage split. ``--crop-model`` has the crop model read every locked
   frame (crop, crop model, needle, value), as before the scan.
   The CPU column is the process's CPU time per call (every thread, onnxruntime's spinning workers
   included): on a machine shared with other jobs the wall time includes waiting for a core, the
   CPU time does not. A gauge whose scale never locks is read in full on every frame; its full-read
   cost is shown instead.
2. Stream: a 1280x720 JPEG recording at ``--fps`` with the demo's 4 dials is replayed at real-time pace
   through the real daemon (MCAP source, camera worker, gauge runners, tracker, ticker, MCAP sink).
   A frame's latency is the wall time from when the source was due to hand it over (replay start plus
   its log time offset) to when its last gauge's result was published. The script reports frames
   sent, read and dropped (newest frame wins), and the median latency in the first and last third
   of the frames read: a last third much slower than the first means the daemon is falling behind.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from mcap.reader import make_reader

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import header  # noqa: E402

from gauged.daemon import gauge_runner  # noqa: E402
from gauged.daemon.app import Daemon  # noqa: E402
from gauged.config import load_config  # noqa: E402
from gauged.config.model import GaugedConfig, ReaderConfig  # noqa: E402
from gauged.daemon.gauge_runner import GaugeRunner  # noqa: E402
from gauged.reader.factory import build_reader  # noqa: E402
from gauged.reader.pipeline import GaugeReader  # noqa: E402
from gauged.sources.mcap_source import iter_frames  # noqa: E402
from gauged.synth.moving_dials import EPOCH_NS, DialSpec, demo_dials, write_recording  # noqa: E402
from gauged.tracking.tracker import GaugeTracker  # noqa: E402
from gauged.types import Frame  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
DEMO, DEMO_CONFIG = REPO / "recordings" / "demo.mcap", REPO / "recordings" / "demo.yaml"
STREAM_BOXES = [(60, 80, 360, 380), (420, 60, 700, 340), (780, 80, 1100, 400), (420, 380, 700, 660)]
LOCK_WITHIN_FRAMES = 30
WARMUP = 10


def ms(seconds: float) -> str:
    return f"{1000 * seconds:6.1f} ms"


def timed_runs(fn, runs: int) -> tuple[list[float], list[float]]:
    """Wall and CPU seconds (this process, every thread) of ``runs`` calls after the warm-up."""
    for _ in range(WARMUP):
        fn()
    wall, cpu = [], []
    for _ in range(runs):
        start, start_cpu = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return wall, cpu


def locked_cost(config: GaugedConfig, reader: GaugeReader, frames: list[Frame], runs: int) -> None:
    path = "crop model on every locked frame" if gauge_runner.CROP_MODEL_EVERY == 1 else (
        f"needle scan, crop model on 1 in {gauge_runner.CROP_MODEL_EVERY} locked frames")
    print(f"\n## locked frame per gauge ({path}; {runs} frames after {WARMUP} warm-up, demo frames in turn)")
    print(f"{'gauge':<18} {'median':>9} {'p90':>9} {'mean':>9} {'cpu':>9} {'model':>6}   wall per stage (median)")
    medians, cpu_medians, means = [], [], []
    for gauge in config.gauges:
        runner = GaugeRunner(gauge, config.scale_lock, reader, GaugeTracker.from_config(gauge))
        box = tuple(float(v) for v in gauge.roi)
        for frame in frames[:LOCK_WITHIN_FRAMES]:
            runner.process(frame, box)
            if runner.scale_lock.locked is not None:
                break
        if runner.scale_lock.locked is None:
            full, _ = timed_runs(lambda: reader.read_box(frames[0].image, box, 1.0, runner.known), max(10, runs // 5))
            print(f"{gauge.id:<18} never locked in {LOCK_WITHIN_FRAMES} frames: read in full on every frame, "
                  f"{ms(statistics.median(full)).strip()} median")
            continue
        turn = iter(range(10**9))
        step = frames[1].stamp_ns - frames[0].stamp_ns
        stages: dict[str, list[float]] = {}
        by_model: list[bool] = []

        def read() -> None:
            k = next(turn)
            frame = frames[k % len(frames)]
            output = runner.process(replace(frame, stamp_ns=frames[-1].stamp_ns + (k + 1) * step), box)
            by_model.append(output.read is not None and output.read.keypoints is not None)
            for stage, seconds in (output.read.seconds if output.read is not None else {}).items():
                stages.setdefault(stage, []).append(seconds)

        times, cpu = timed_runs(read, runs)
        medians.append(statistics.median(times))
        cpu_medians.append(statistics.median(cpu))
        means.append(statistics.mean(times))
        split = ", ".join(f"{stage} {1000 * statistics.median(v):.1f}" for stage, v in stages.items())
        print(f"{gauge.id:<18} {ms(statistics.median(times))} {ms(float(np.percentile(times, 90)))} "
              f"{ms(statistics.mean(times))} {ms(statistics.median(cpu))} {sum(by_model[-runs:]) / runs:6.0%}   "
              f"{split} ms")
    if medians:
        print(f"locked steady-state cost per gauge per frame: median {ms(statistics.median(medians)).strip()} wall, "
              f"{ms(statistics.median(cpu_medians)).strip()} CPU, mean {ms(statistics.median(means)).strip()}, "
              f"over {len(medians)} gauges (target <= 5 ms, issue 36)")


def stream_recording(path: Path, seconds: float, fps: float) -> dict[str, tuple[int, int, int, int]]:
    """Write the 1280x720 stream of the demo's dials, moved apart; returns ROIs from the truth."""
    placed = [DialSpec(s.gauge, s.seed, s.min_value, s.max_value, s.unit, box, s.profile)
              for s, box in zip(demo_dials(), STREAM_BOXES)]
    write_recording(path, placed, seconds, fps, seed=11, width=1280, height=720, jpeg_quality=85)
    with path.open("rb") as stream:
        _, _, first = next(make_reader(stream).iter_messages(topics=["/cam1/truth"]))
    rois = {}
    for g in json.loads(first.data)["gauges"]:
        x0, y0, x1, y1 = g["box"]
        rois[g["gauge"]] = (max(0, int(x0) - 4), max(0, int(y0) - 4), int(x1) + 5, int(y1) + 5)
    return rois


def stream_config(config: GaugedConfig, recording: Path, rois: dict, out: Path) -> GaugedConfig:
    camera = config.cameras[0]
    source = camera.source.model_copy(update={"path": recording, "pace": "realtime", "loop": False})
    outputs = config.outputs.model_copy(update={
        "zenoh": config.outputs.zenoh.model_copy(update={"enabled": False}),
        "prometheus": config.outputs.prometheus.model_copy(update={"enabled": False}),
        "mcap": config.outputs.mcap.model_copy(update={"dir": out / "mcap"}),
    })
    return config.model_copy(update={
        "cameras": [camera.model_copy(update={"source": source})],
        "gauges": [g.model_copy(update={"roi": rois[g.id]}) for g in config.gauges],
        "outputs": outputs,
        "state": config.state.model_copy(update={"dir": out / "state"}),
    })


def stream(config: GaugedConfig, reader: GaugeReader, seconds: float, fps: float) -> None:
    print(f"\n## 1280x720 JPEG stream at {fps:g} fps, {len(config.gauges)} gauges, {seconds:g} s, real-time pace")
    with tempfile.TemporaryDirectory(prefix="gauged-bench-") as tmp:
        recording = Path(tmp) / "stream.mcap"
        rois = stream_recording(recording, seconds, fps)
        daemon = Daemon(stream_config(config, recording, rois, Path(tmp)), reader_factory=lambda c: reader)
        done: dict[int, float] = {}  # frame stamp -> when its last gauge was published
        publish = daemon.gauge_output

        def timed(frame: Frame, output) -> None:
            publish(frame, output)
            done[frame.stamp_ns] = time.monotonic()

        daemon.gauge_output = timed  # the camera worker publishes through this attribute
        started = time.monotonic()  # the source starts its clock within a few ms of this
        daemon.start()
        try:
            finished = daemon.wait(timeout=seconds * 3 + 30)
        finally:
            daemon.stop()
        ran_s = time.monotonic() - started
        with next((Path(tmp) / "mcap").glob("*.mcap")).open("rb") as f:
            written = sum(1 for _ in make_reader(f).iter_messages(topics=["/gauged/readings"]))
    latencies = [t - (started + (stamp - EPOCH_NS) / 1e9) for stamp, t in sorted(done.items())]
    third = max(1, len(latencies) // 3)
    sent = int(round(seconds * fps))
    received = daemon.metrics.value("gauged_frames_received_total", camera="cam1") or 0
    dropped = daemon.metrics.value("gauged_frames_dropped_total", camera="cam1") or 0
    read = daemon.workers[0].frames_read
    print(f"frames sent {sent}, received {received:.0f}, read {read}, dropped {dropped:.0f} (newest frame wins); "
          f"{read / ran_s:.1f} frames/s read over {ran_s:.1f} s{'' if finished else ' (did not finish)'}")
    extra = written - read * len(config.gauges)
    print(f"readings written to MCAP: {written}" + (f" ({extra} of them the ticker's stale readings)" if extra else "")
          + "; scales locked at the end: "
          + (", ".join(g for g, r in daemon.runners.items() if r.scale_lock.is_locked) or "none"))
    thirds = [latencies[:third], latencies[third:-third] or latencies, latencies[-third:]]
    print("latency frame due -> last reading published: median first / middle / last third "
          + " / ".join(ms(statistics.median(t)).strip() for t in thirds) + f", max {ms(max(latencies)).strip()}")
    print(f"(reading every frame in order at {read / ran_s:.1f} frames/s, the last frame would have waited "
          f"{max(0.0, sent / (read / ran_s) - seconds):.0f} s)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=100, help="timed read_locked runs per gauge")
    parser.add_argument("--seconds", type=float, default=20.0, help="length of the stream")
    parser.add_argument("--fps", type=float, default=15.0, help="frame rate of the stream")
    parser.add_argument("--threads", type=int, default=2, help="onnxruntime threads of the crop model")
    parser.add_argument("--skip-stream", action="store_true", help="only measure the locked cost")
    parser.add_argument("--crop-model", action="store_true",
                        help="read every locked frame with the crop model (no needle scan), as before issue 36")
    args = parser.parse_args()
    if args.crop_model:
        gauge_runner.CROP_MODEL_EVERY = 1
    header("gauged daemon steady state")
    config = load_config(DEMO_CONFIG)
    config = config.model_copy(update={"reader": ReaderConfig(threads=args.threads)})
    reader = build_reader(config.reader)
    frames = list(iter_frames(DEMO, "/cam1/image"))[:LOCK_WITHIN_FRAMES]
    locked_cost(config, reader, frames, args.runs)
    if not args.skip_stream:
        stream(config, reader, args.seconds, args.fps)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
