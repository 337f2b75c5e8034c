"""``gauged replay``: read a recording as fast as possible, write the results to one MCAP file, exit."""

from __future__ import annotations

import argparse
import logging
import shutil
import sys
import tempfile
import time
from pathlib import Path

from gauged.daemon.app import Daemon
from gauged.config import ConfigError, load_config, load_default_config
from gauged.config.model import GaugedConfig
from gauged.reader.onnx_model import ModelNotAvailable

log = logging.getLogger(__name__)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "replay", help="process a recording as fast as possible into one MCAP file",
        description="Read every frame of FILE.mcap (no pacing, no loop, no frame dropped) with the cameras and "
        "gauges of --config, and write /gauged/readings, /gauged/failures and /gauged/alarms to --out. Zenoh and "
        "Prometheus outputs are off and no state is restored or saved, so two replays of the same recording "
        "give identical readings. Each camera's topic is taken from its mcap source in the config.",
        epilog="example: gauged replay recordings/demo.mcap --config recordings/demo.yaml --out /tmp/readings.mcap")
    parser.add_argument("recording", metavar="FILE.mcap", help="recording to read")
    parser.add_argument("-c", "--config", metavar="FILE", help="config naming cameras (topics) and gauges "
                        "(default: the embedded demo config)")
    parser.add_argument("-o", "--out", metavar="OUT.mcap", required=True, help="MCAP file to write")
    parser.set_defaults(func=run)


def batch_config(config: GaugedConfig, recording: Path, out_dir: Path) -> GaugedConfig:
    """The config with every camera replaying ``recording`` fast and only the MCAP output on."""
    cameras = []
    for camera in config.cameras:
        if camera.source.type != "mcap":
            raise ValueError(f"camera {camera.id} has a {camera.source.type} source; replay needs an mcap source "
                             "naming the camera's topic")
        source = camera.source.model_copy(update={"path": recording, "pace": "fast", "loop": False})
        cameras.append(camera.model_copy(update={"source": source, "max_rate_hz": None}))
    outputs = config.outputs.model_copy(update={
        "zenoh": config.outputs.zenoh.model_copy(update={"enabled": False}),
        "prometheus": config.outputs.prometheus.model_copy(update={"enabled": False}),
        "mcap": config.outputs.mcap.model_copy(update={"enabled": True, "dir": out_dir, "rotate_mb": 1e9,
                                                       "rotate_s": 1e12}),
    })
    return config.model_copy(update={"cameras": cameras, "outputs": outputs})


def run(args: argparse.Namespace) -> int:
    recording, out = Path(args.recording), Path(args.out)
    if not recording.is_file():
        print(f"{recording}: no such recording", file=sys.stderr)
        return 2
    try:
        config = load_config(args.config) if args.config else load_default_config()
    except ConfigError as exc:
        for issue in exc.issues:
            print(issue, file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="gauged-replay-") as tmp:
        try:
            batch = batch_config(config, recording, Path(tmp))
        except ValueError as exc:
            print(exc, file=sys.stderr)
            return 2
        started = time.monotonic()
        daemon = Daemon(batch, batch=True)
        try:
            daemon.start()
        except ModelNotAvailable as exc:
            log.error("%s", exc)
            return 1
        try:
            daemon.wait()
        finally:
            daemon.stop()
        written = sorted(Path(tmp).glob("*.mcap"))
        if len(written) != 1:
            log.error("expected one output file, got %d", len(written))
            return 1
        out.parent.mkdir(parents=True, exist_ok=True)
        shutil.move(str(written[0]), out)
    frames = sum(w.frames_read for w in daemon.workers)
    log.info("replayed %d frame(s) in %.1f s -> %s", frames, time.monotonic() - started, out)
    print(out)
    return 0
