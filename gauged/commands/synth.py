"""``gauged synth``: make synthetic data — labelled gauge images, recordings, a contact sheet."""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

import cv2
import numpy as np

log = logging.getLogger(__name__)

DEMO = {"seconds": 60.0, "fps": 2.0, "seed": 7}


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("synth", help="render synthetic gauges, recordings and contact sheets",
                                   description="Procedural gauges with complete labels; everything is a function of "
                                   "--seed, so the same command writes byte-identical files.")
    sub = parser.add_subparsers(dest="what", metavar="WHAT", required=True)
    images = sub.add_parser("images", help="labelled gauge crops: DIR/images/*.png and DIR/labels.jsonl",
                            epilog="example: gauged synth images --count 1000 --seed 9000000 --out /tmp/synth-eval")
    images.add_argument("--count", type=int, required=True)
    images.add_argument("--seed", type=int, default=0, help="first seed; image i uses seed + i")
    images.add_argument("--size", type=int, default=448, help="crop side in pixels (default 448)")
    images.add_argument("--out", type=Path, required=True)
    images.set_defaults(func=run_images)
    recording = sub.add_parser("recording", help="an MCAP recording of K dials whose needles move",
                               epilog="example: gauged synth recording --seconds 20 --fps 5 --gauges 2 --seed 1 --out /tmp/r.mcap")
    recording.add_argument("--seconds", type=float, default=60.0)
    recording.add_argument("--fps", type=float, default=2.0)
    recording.add_argument("--gauges", type=int, default=4, help="number of dials (1-4, the demo's dials in order)")
    recording.add_argument("--seed", type=int, default=DEMO["seed"])
    recording.add_argument("--ros2", action="store_true", help="images as ROS 2 sensor_msgs/msg/CompressedImage (cdr)")
    recording.add_argument("--out", type=Path, required=True)
    recording.set_defaults(func=run_recording)
    demo = sub.add_parser("demo", help="regenerate recordings/demo.mcap exactly",
                          description=f"The bundled demo: 4 dials, {DEMO['seconds']:g} s at {DEMO['fps']:g} fps, seed "
                          f"{DEMO['seed']}. Same as: gauged synth recording --seconds {DEMO['seconds']:g} --fps "
                          f"{DEMO['fps']:g} --gauges 4 --seed {DEMO['seed']} --out recordings/demo.mcap")
    demo.add_argument("--out", type=Path, default=Path("recordings/demo.mcap"))
    demo.add_argument("--ros2", action="store_true")
    demo.set_defaults(func=run_demo)
    sheet = sub.add_parser("sheet", help="a contact sheet of 48 random renders")
    sheet.add_argument("--out", type=Path, default=Path("sheet.png"))
    sheet.add_argument("--seed", type=int, default=0)
    sheet.set_defaults(func=run_sheet)


def run_images(args: argparse.Namespace) -> int:
    from gauged.training.dial_renderer import render_crop

    (args.out / "images").mkdir(parents=True, exist_ok=True)
    with (args.out / "labels.jsonl").open("w") as labels:
        for i in range(args.count):
            seed = args.seed + i
            image, truth = render_crop(seed, args.size)
            name = f"{seed:08d}.png"
            cv2.imwrite(str(args.out / "images" / name), image)
            labels.write(json.dumps({
                "image": name, "reading": truth.value, "min": truth.min_value, "max": truth.max_value,
                "unit": truth.unit, "box": truth.face_box,
                "points": {k: np.round(v, 3).tolist() for k, v in truth.points.items()}}) + "\n")
            if (i + 1) % 100 == 0 or i + 1 == args.count:
                log.info("rendered %d/%d", i + 1, args.count)
    print(args.out / "labels.jsonl")
    return 0


def _write(out: Path, gauges: int, seconds: float, fps: float, seed: int, ros2: bool) -> int:
    from gauged.synth.moving_dials import demo_dials, write_recording

    dials = demo_dials()[: max(1, min(4, gauges))]
    step = max(1, int(seconds * fps) // 10)
    frames = write_recording(out, dials, seconds, fps, seed, ros2=ros2,
                             progress=lambda i, n: i % step == 0 and log.info("frame %d/%d", i, n))
    log.info("wrote %d frames of %d dial(s) to %s (%.1f MB)", frames, len(dials), out, out.stat().st_size / 2**20)
    print(out)
    return 0


def run_recording(args: argparse.Namespace) -> int:
    return _write(args.out, args.gauges, args.seconds, args.fps, args.seed, args.ros2)


def run_demo(args: argparse.Namespace) -> int:
    return _write(args.out, 4, DEMO["seconds"], DEMO["fps"], DEMO["seed"], args.ros2)


def run_sheet(args: argparse.Namespace) -> int:
    from gauged.training.dial_renderer import render_crop

    tiles = [render_crop(args.seed + i, 192)[0] for i in range(48)]
    rows = [np.hstack(tiles[r * 8:(r + 1) * 8]) for r in range(6)]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.out), np.vstack(rows))
    print(args.out)
    return 0
