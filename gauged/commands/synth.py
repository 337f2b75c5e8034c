"""``gauged synth``: render synthetic gauges with complete ground truth.

    gauged synth images --count N --seed S --out DIR [--kind scene|crop] [--masks] [--workers W] [--direction D]
    gauged synth recording --seconds T --fps F --gauges K --seed S --out FILE.mcap [--ros2] [--direction D]
    gauged synth sheet --out sheet.png [--seed S] [--direction D]
    gauged synth demo --out recordings/demo.mcap [--ros2]
    gauged synth plant-demo --out recordings/plant-demo.mcap [--ros2-out FILE.mcap]

The ground-truth schema is documented in ``gauged/synth/truth.py`` and ``docs/synth.md``.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import cv2
import numpy as np

from gauged.commands.argtypes import positive_float, positive_int

log = logging.getLogger(__name__)


def _quality(text: str) -> int:
    value = int(text)
    if not 1 <= value <= 100:
        raise argparse.ArgumentTypeError(f"JPEG quality must be 1-100, got {text}")
    return value


DIRECTIONS = ("cw", "ccw", "mixed")  # gauged.synth.sampling.DIRECTIONS, not imported so the CLI starts fast
DIRECTION_HELP = ("which way the printed values rise: cw = clockwise (default; a seed renders what it always did), "
                  "ccw = counter-clockwise, min at the clockwise-last end (vacuum, compound, negative and decimal "
                  "ranges, e.g. 0..30 inHg, -1..0 bar, -0.1..0 MPa), mixed = each gauge ccw with probability 0.3")


def _direction(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--direction", choices=DIRECTIONS, default="cw", help=DIRECTION_HELP)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "synth", help="render synthetic gauges, recordings and contact sheets with ground truth",
        description="Render synthetic analog gauges with complete ground truth (see docs/synth.md).")
    sub = parser.add_subparsers(dest="synth_command", metavar="{images,recording,sheet,demo,plant-demo}")
    sub.required = True

    images = sub.add_parser("images", help="write rendered images and labels.jsonl",
                            description="Write N renders as DIR/NNNNNN.jpg and their ground truth as DIR/labels.jsonl.")
    images.add_argument("--count", type=positive_int, required=True, help="number of images")
    images.add_argument("--seed", type=int, default=0, help="seed of the batch (image i uses seed [S, i])")
    images.add_argument("--out", type=Path, required=True, help="output directory")
    images.add_argument("--kind", choices=("scene", "crop"), default="scene",
                        help="scene: full frames with several gauges; crop: square crops of one gauge")
    images.add_argument("--width", type=positive_int, default=1280, help="scene width in px")
    images.add_argument("--height", type=positive_int, default=720, help="scene height in px")
    images.add_argument("--size", type=positive_int, default=448, help="crop side in px")
    images.add_argument("--masks", action="store_true", help="also write needle label maps DIR/masks/NNNNNN.png (crops)")
    images.add_argument("--clean", action="store_true", help="no glass, shadows, blur, noise or compression")
    images.add_argument("--quality", type=_quality, default=95, help="JPEG quality of the written files")
    images.add_argument("--workers", type=positive_int, default=1, help="worker processes")
    _direction(images)

    rec = sub.add_parser("recording", help="write a moving scene as an MCAP recording",
                         description="Render one camera looking at K gauges whose values move, as MCAP "
                                     "(foxglove.CompressedImage JSON, or ROS 2 CDR with --ros2), with the truth on /<camera>/truth.")
    rec.add_argument("--seconds", type=positive_float, default=60.0, help="duration in seconds")
    rec.add_argument("--fps", type=positive_float, default=2.0, help="frames per second")
    rec.add_argument("--gauges", type=positive_int, default=3, help="number of gauges in view")
    rec.add_argument("--seed", type=int, default=0, help="seed of the scene and its timelines")
    rec.add_argument("--out", type=Path, required=True, help="output .mcap file")
    rec.add_argument("--ros2", action="store_true", help="write sensor_msgs/msg/CompressedImage (ros2msg + cdr)")
    rec.add_argument("--camera", default="cam1", help="camera id (topics /<camera>/image and /<camera>/truth)")
    rec.add_argument("--width", type=positive_int, default=960, help="frame width in px")
    rec.add_argument("--height", type=positive_int, default=540, help="frame height in px")
    rec.add_argument("--quality", type=_quality, default=80, help="JPEG quality of the frames")
    _direction(rec)

    sheet = sub.add_parser("sheet", help="write a contact sheet of 48 random renders",
                           description="Write a PNG grid of random renders (crops, every sixth a full scene).")
    sheet.add_argument("--out", type=Path, required=True, help="output image (.png)")
    sheet.add_argument("--seed", type=int, default=0, help="seed")
    sheet.add_argument("--count", type=positive_int, default=48, help="number of tiles")
    sheet.add_argument("--tile", type=positive_int, default=256, help="tile side in px")
    sheet.add_argument("--workers", type=positive_int, default=1, help="worker processes")
    _direction(sheet)

    demo = sub.add_parser("demo", help="rebuild the bundled demo recording (four moving dials, one camera)",
                          description="Rebuild recordings/demo.mcap byte for byte (gauged.synth.moving_dials; "
                                      "see recordings/README.md).")
    demo.add_argument("--out", type=Path, default=Path("recordings/demo.mcap"), help="output .mcap file")
    demo.add_argument("--ros2", action="store_true", help="write sensor_msgs/msg/CompressedImage (ros2msg + cdr)")

    plant = sub.add_parser("plant-demo", help="rebuild the plant demo recording (two cameras, five gauges)",
                           description="Rebuild recordings/plant-demo.mcap byte for byte with the full renderer "
                                       "(gauged.synth.demo; see recordings/README.md).")
    plant.add_argument("--out", type=Path, default=Path("recordings/plant-demo.mcap"), help="output .mcap file")
    plant.add_argument("--ros2-out", type=Path, default=None, help="also write the ROS 2 flavour to this file")
    parser.set_defaults(func=run)


def _parent_ok(path: Path) -> bool:
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        log.error("directory %s does not exist", parent)
        return False
    return True


def _images(args: argparse.Namespace) -> int:
    from gauged.synth.dataset import write_images

    if args.out.exists() and not args.out.is_dir():
        log.error("--out %s exists and is not a directory", args.out)
        return 2
    labels = write_images(args.out, args.kind, args.seed, args.count, width=args.width, height=args.height,
                          size=args.size, clean=args.clean, workers=args.workers, quality=args.quality, masks=args.masks,
                          direction=args.direction)
    print(f"wrote {args.count} {args.kind} images and {labels}")
    return 0


def _recording(args: argparse.Namespace) -> int:
    from gauged.synth.recording import write_foxglove, write_ros2
    from gauged.synth.sequence import random_sequence

    if not _parent_ok(args.out):
        return 2
    seq = random_sequence(np.random.default_rng(args.seed), camera=args.camera, seconds=args.seconds, fps=args.fps,
                          gauges=args.gauges, width=args.width, height=args.height, direction=args.direction)
    meta = {"command": "gauged synth recording", "seed": str(args.seed), "seconds": f"{args.seconds:g}",
            "fps": f"{args.fps:g}", "gauges": str(args.gauges)}
    if args.direction != "cw":  # a cw recording keeps the metadata, and so the bytes, it always had
        meta["direction"] = args.direction
    write = write_ros2 if args.ros2 else write_foxglove
    summary = write(args.out, [seq], quality=args.quality, metadata=meta)
    print(f"wrote {summary.frames} frames of {args.camera} to {summary.path} ({summary.bytes} bytes)")
    return 0


def _sheet(args: argparse.Namespace) -> int:
    from gauged.synth.dataset import contact_sheet

    if not _parent_ok(args.out):
        return 2
    img = contact_sheet(args.seed, args.count, args.tile, workers=args.workers, direction=args.direction)
    if not cv2.imwrite(str(args.out), img):
        log.error("could not write %s (unknown image extension?)", args.out)
        return 2
    print(f"wrote {args.out}")
    return 0


DIALS_DEMO = {"seconds": 60.0, "fps": 2.0, "seed": 7}


def _dials_demo(args: argparse.Namespace) -> int:
    from gauged.synth.moving_dials import demo_dials, write_recording

    if not _parent_ok(args.out):
        return 2
    seconds, fps = DIALS_DEMO["seconds"], DIALS_DEMO["fps"]
    step = max(1, int(seconds * fps) // 10)
    frames = write_recording(args.out, demo_dials(), seconds, fps, DIALS_DEMO["seed"], ros2=args.ros2,
                             progress=lambda i, n: i % step == 0 and log.info("frame %d/%d", i, n))
    print(f"wrote {frames} frames to {args.out} ({args.out.stat().st_size} bytes)")
    return 0


def _plant_demo(args: argparse.Namespace) -> int:
    from gauged.synth.demo import QUALITY, demo_sequences
    from gauged.synth.recording import write_foxglove, write_ros2

    for path in (args.out, args.ros2_out):
        if path is not None and not _parent_ok(path):
            return 2
    meta = {"command": "gauged synth demo", "description": "gauged demo: 2 cameras, 5 gauges, 60 s"}
    summary = write_foxglove(args.out, demo_sequences(), quality=QUALITY, metadata=meta)
    print(f"wrote {summary.frames} frames to {summary.path} ({summary.bytes} bytes)")
    if args.ros2_out is not None:
        summary = write_ros2(args.ros2_out, demo_sequences(), quality=QUALITY, metadata=meta)
        print(f"wrote {summary.frames} frames to {summary.path} ({summary.bytes} bytes)")
    return 0


def run(args: argparse.Namespace) -> int:
    handlers = {"images": _images, "recording": _recording, "sheet": _sheet, "demo": _dials_demo,
                "plant-demo": _plant_demo}
    try:
        return handlers[args.synth_command](args)
    except OSError as exc:
        log.error("synth %s failed: %s", args.synth_command, exc)
        return 1
