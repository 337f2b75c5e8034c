"""``gauged commission SOURCE``: find a camera's gauges, write the config that reads them and a contact sheet."""

from __future__ import annotations

import argparse
import logging
import re
import shlex
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from gauged.commands.argtypes import non_negative, positive_int

if TYPE_CHECKING:
    from gauged.commissioning.survey import GaugeFinding

log = logging.getLogger(__name__)

DESCRIPTION = """\
Commission a camera: find every gauge that SOURCE shows, read each one's scale, unit and direction on
several frames, and write a config with one gauge per dial found (id, camera, ROI, scale, the alarm
limits suggested but commented out) and a contact sheet PNG of every gauge annotated with what was read.
Before the config is written, each gauge's ROI and scale are read on every frame the way the daemon will
read them. A gauge that could not be read (no scale, the frames disagree, the daemon's read of its ROI
fails) is still written, with its ROI and a '# TODO:' naming the reason; fill in its scale from the dial.

SOURCE is one of
  a photo (JPEG or PNG)       one frame; the camera's Zenoh key is left as a TODO
  an MCAP recording           every image topic is a camera (--topic picks some); the config replays it
  zenoh:<key expression>      a live camera, e.g. zenoh:plant/cam1/image (--connect to reach a router)
The kind of file is told by its first bytes, not its name; anything else is refused (exit 2).

Check the gauges against the contact sheet, rename the ids (cam1-gauge-1, ...) to your tag names, fix
every TODO and set your process's alarm limits, then validate with 'gauged check-config'."""

EPILOG = """\
examples:
  gauged commission recordings/plant-demo.mcap --out cfg.yaml
      5 gauges of two cameras; the contact sheet goes to cfg-sheet.png
  gauged replay recordings/plant-demo.mcap --config cfg.yaml --out /tmp/readings.mcap
      read the whole recording with the config written
  gauged commission panel.jpg --camera boiler-room --out boiler.yaml --sheet /tmp/boiler.png
  gauged commission zenoh:plant/cam1/image --connect tcp/10.0.0.5:7447 --frames 10 --every 3 --out cam1.yaml
      ten frames at least 3 s apart from a live camera (waits up to --timeout s)
  gauged commission recordings/demo.mcap --frames 3 --every 10
      print the config on stdout (the sheet goes to gauged-commission.png)

exit codes: 0 config written (TODOs included), 1 no gauge found, no frame arrived or no model,
2 SOURCE is no photo or recording, or --out exists (see --force)."""

DEFAULT_SHEET = Path("gauged-commission.png")  # when the config goes to stdout


def _config_id(text: str) -> str:
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", text):
        raise argparse.ArgumentTypeError(f"letters, digits, '_', '.' and '-' only (a config id), got {text!r}")
    return text


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "commission", help="find a camera's gauges and write their config and a contact sheet",
        description=DESCRIPTION, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("source", metavar="SOURCE", help="photo (JPEG/PNG), MCAP recording, or zenoh:<key expression>")
    parser.add_argument("-o", "--out", metavar="CFG.yaml", type=Path,
                        help="write the config here (default: print it on stdout)")
    parser.add_argument("--force", action="store_true", help="overwrite --out when it exists")
    parser.add_argument("--sheet", metavar="PNG", type=Path,
                        help=f"contact sheet to write (default: CFG-sheet.png beside --out, else {DEFAULT_SHEET})")
    parser.add_argument("-n", "--frames", type=positive_int, default=6, metavar="N",
                        help="frames read per camera of a recording or live key (default 6); more frames make "
                        "the scale vote surer and take about 2-5 s each")
    parser.add_argument("--every", type=non_negative, default=5.0, metavar="SECONDS",
                        help="at least this much frame time between the frames read (default 5), so the "
                        "needle is seen in several places")
    parser.add_argument("--topic", action="append", metavar="TOPIC",
                        help="image topic of the recording to commission (repeat for several; default: all)")
    parser.add_argument("--camera", metavar="ID", type=_config_id, help="camera id for a photo or a Zenoh key (default: cam1 for "
                        "a photo, the key's name for a key); a recording's cameras are named after their topics")
    parser.add_argument("--site", metavar="NAME", type=_config_id, help="site: of the config (default: the source's name)")
    parser.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                        help="Zenoh endpoint to connect to, e.g. tcp/10.0.0.5:7447 (repeatable); written to the config")
    parser.add_argument("--mode", choices=("peer", "client"), default="peer", help="Zenoh session mode (default peer)")
    parser.add_argument("--timeout", type=non_negative, metavar="SECONDS",
                        help="how long to wait for a live key's frames (default: frames x every + 10 s)")
    parser.add_argument("--threads", type=int, default=2, help="onnxruntime threads (default 2)")
    parser.add_argument("--models", type=Path, help="folder with crop.onnx/detector.onnx to use instead of the "
                        "shipped models (and numbers.onnx/ocr_det_int8.onnx/notch_check.onnx, where it holds them)")
    parser.set_defaults(func=run)


def _site(args: argparse.Namespace) -> str:
    from gauged.commissioning.frames import ZENOH_PREFIX, camera_id

    if args.site:
        return args.site
    if args.source.startswith(ZENOH_PREFIX):
        return args.camera or camera_id(args.source[len(ZENOH_PREFIX):], "gauged")
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", Path(args.source).stem).strip("-.") or "gauged"


def _sheet_path(args: argparse.Namespace) -> Path:
    if args.sheet is not None:
        return args.sheet
    return args.out.with_name(f"{args.out.stem}-sheet.png") if args.out is not None else DEFAULT_SHEET


def _summary(gauge: GaugeFinding) -> str:
    scale = "no scale" if gauge.scale is None else gauge.scale.describe()
    state = f"TODO: {gauge.todo}" if gauge.todo is not None else f"read {gauge.checked}/{gauge.frames}"
    return f"  {gauge.id:<16} roi {list(gauge.roi)}  {scale}  {state}"


def run(args: argparse.Namespace) -> int:
    import cv2

    from gauged import __version__
    from gauged.commissioning.config_text import config_text
    from gauged.commissioning.frames import BadSource, NoFrames, source_frames
    from gauged.commissioning.sheet import contact_sheet
    from gauged.commissioning.survey import survey_camera
    from gauged.config import ConfigError, parse_config
    from gauged.config.model import ReaderConfig, ZenohConfig
    from gauged.reader.factory import build_reader
    from gauged.reader.onnx_model import ModelNotAvailable

    if args.out is not None and args.out.exists() and not args.force:
        print(f"{args.out} exists: give --force to overwrite it, or another --out", file=sys.stderr)
        return 2
    zenoh = ZenohConfig(mode=args.mode, connect=args.connect, multicast_scouting=not args.connect)
    timeout = args.timeout if args.timeout is not None else args.frames * args.every + 10.0
    try:
        cameras = source_frames(args.source, args.frames, args.every, topics=args.topic, camera=args.camera,
                                timeout_s=timeout, zenoh=zenoh)
    except BadSource as exc:
        print(f"gauged commission: {exc}", file=sys.stderr)
        return 2
    except NoFrames as exc:
        print(f"gauged commission: {exc}", file=sys.stderr)
        return 1
    try:
        reader = build_reader(ReaderConfig(threads=args.threads, models_dir=args.models))
    except ModelNotAvailable as exc:
        log.error("%s", exc)
        return 1
    gauges, dropped = {}, {}
    for camera in cameras:
        log.info("camera %s: reading %d frame(s)", camera.camera, len(camera.frames))
        gauges[camera.camera], dropped[camera.camera] = survey_camera(reader, camera.camera, camera.frames)
    found = [g for camera in cameras for g in gauges[camera.camera]]
    todo = sum(g.todo is not None for g in found)
    no_unit = sum(g.todo is None and g.scale is not None and g.scale.unit is None for g in found)
    todos = ", ".join(([f"{todo} unread"] if todo else []) + ([f"{no_unit} with no unit read"] if no_unit else []))
    sheet_path = _sheet_path(args)
    command = f"gauged commission {shlex.quote(args.source)} --frames {args.frames} --every {args.every:g}"
    header = [f"Written by: {command}  (gauged {__version__})",
              f"{len(found)} gauge(s) on {len(cameras)} camera(s): " + (f"{todos}, see each TODO." if todos else "all read."),
              f"Check each gauge against the contact sheet {sheet_path}, rename the ids to your tag names,",
              "fix every TODO and set the alarm limits your process needs, then: gauged check-config FILE",
              "Outputs, state and reader settings are the defaults: every option is in config/gauged.example.yaml."]
    zenoh_block = {"mode": args.mode, **({"connect": args.connect} if args.connect else {}),
                   "multicast_scouting": zenoh.multicast_scouting}
    text = config_text(_site(args), cameras, gauges, dropped, zenoh_block, header)
    try:
        parse_config(text, str(args.out or "<stdout>"))
    except ConfigError as exc:  # a bug of commissioning: say so rather than write a config that will not load
        for issue in exc.issues:
            log.error("the written config would not load: %s", issue)
        return 1
    sheet, _tiles = contact_sheet(cameras, gauges, dropped)
    sheet_path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(sheet_path), sheet):
        log.error("cannot write the contact sheet %s", sheet_path)
        return 1
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)
    else:
        sys.stdout.write(text)
    print(f"{len(found)} gauge(s) found ({todos or 'all read'}); config "
          f"{args.out if args.out is not None else 'on stdout'}, contact sheet {sheet_path}", file=sys.stderr)
    for gauge in found:
        print(_summary(gauge), file=sys.stderr)
    if not found:
        print("gauged commission: no gauge found: see the contact sheet for what the camera shows", file=sys.stderr)
        return 1
    return 0
