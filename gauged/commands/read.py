"""``gauged read IMAGE...``: read every gauge in photos, one line (or JSON object) per gauge."""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path
from typing import Any

import cv2

from gauged.config.model import ReaderConfig
from gauged.reader.gauge_read import GaugeRead, KnownScale
from gauged.reader.onnx_model import ModelNotAvailable
from gauged.types import StageFailure

log = logging.getLogger(__name__)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "read", help="read the gauges in photos",
        description="Detect and read every gauge in each IMAGE. One line per gauge: value, unit, scale and "
        "confidence, or the stage that refused and why. An image with no gauge still gets one line. A dial "
        "with two scales (bar and psi) is read on its main (outer) scale; the other scale's reading follows, "
        "in its own unit ('other_scales' in the JSON).",
        epilog="examples:\n  gauged read photo.jpg\n  gauged read --json --debug-dir /tmp/why *.jpg\n"
        "  gauged read --scale 0 10 bar panel.png      (known scale: no OCR)\n"
        "  gauged read --scale -1 0 bar ccw vac.png    (a vacuum dial rising counter-clockwise)",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("images", metavar="IMAGE", nargs="+", help="JPEG/PNG files")
    parser.add_argument("--json", action="store_true", help="one JSON object per line and gauge")
    parser.add_argument("--debug-dir", type=Path, help="write an annotated picture per gauge here")
    parser.add_argument("--scale", nargs="+", metavar=("MIN MAX", "UNIT"),
                        help="known scale: MIN MAX [UNIT] [cw|ccw] (ccw: values rising counter-clockwise)")
    parser.add_argument("--threads", type=int, default=2, help="onnxruntime threads (default 2)")
    parser.add_argument("--min-confidence", type=float, default=0.5, help="refuse readings below this (default 0.5)")
    parser.add_argument("--models", type=Path, help="folder with crop.onnx/detector.onnx to use instead of the shipped models "
                        "(and numbers.onnx/ocr_det_int8.onnx/notch_check.onnx, where it holds them)")
    parser.set_defaults(func=run)


def _known(values: list[str] | None) -> KnownScale | None:
    if not values:
        return None
    direction = 1
    if len(values) > 2 and values[-1] in ("cw", "ccw"):
        direction, values = (1 if values[-1] == "cw" else -1), values[:-1]
    if len(values) not in (2, 3):
        raise ValueError("--scale takes MIN MAX [UNIT] [cw|ccw]")
    low, high = float(values[0]), float(values[1])
    if not high > low:
        raise ValueError("--scale MAX must be greater than MIN")
    return KnownScale(low, high, values[2] if len(values) == 3 else None, direction)


def record(image: str, index: int, read: GaugeRead | None, failure: StageFailure | None) -> dict[str, Any]:
    """The JSON line of one gauge (the contract of ``--json``)."""
    scale = read.scale if read is not None else None
    value = read.value if read is not None else None
    if failure is None and read is not None:  # StageFailure is falsy: never `failure or ...`
        failure = read.failure
    return {
        "image": image,
        "gauge": index,
        "box": None if read is None else [round(v, 1) for v in read.box],
        "value": None if value is None else value.value,
        "unit": None if read is None else read.unit,
        "confidence": 0.0 if value is None else round(value.confidence, 3),
        "scale": None if scale is None else {"min": scale.min_value, "max": scale.max_value, "unit": scale.unit},
        "failure": None if failure is None else failure.to_dict(),
        "other_scales": [] if read is None else [
            {"value": v, "unit": s.unit, "scale": {"min": s.min_value, "max": s.max_value, "unit": s.unit}}
            for v, s in read.other_readings],
    }


def _line(rec: dict[str, Any]) -> str:
    head = f"{rec['image']} #{rec['gauge']}"
    if rec["failure"] is not None:
        f = rec["failure"]
        return f"{head}: refused at {f['stage']} ({f['reason']}): {f['detail']}"
    scale = rec["scale"]
    unit = rec["unit"] or ""
    others = "".join(f"; also {o['value']:.4g} {o['unit'] or ''} (scale {o['scale']['min']:g}..{o['scale']['max']:g})"
                     for o in rec["other_scales"])
    return (f"{head}: {rec['value']:.4g} {unit}  (scale {scale['min']:g}..{scale['max']:g} {scale['unit'] or ''}, "
            f"confidence {rec['confidence']:.2f}){others}")


def run(args: argparse.Namespace) -> int:
    from gauged.reader.factory import build_reader

    try:
        known = _known(args.scale)
    except ValueError as exc:
        print(exc, file=sys.stderr)
        return 2
    try:
        reader = build_reader(ReaderConfig(threads=args.threads, min_confidence=args.min_confidence, models_dir=args.models))
    except ModelNotAvailable as exc:
        log.error("%s", exc)
        return 1
    if args.debug_dir:
        args.debug_dir.mkdir(parents=True, exist_ok=True)
    for path in args.images:
        image = cv2.imread(path, cv2.IMREAD_COLOR)
        if image is None:
            recs = [record(path, 0, None, StageFailure("decode", "unreadable", f"cannot read {path} as an image"))]
        else:
            reads = reader.read_image(image, known)
            if isinstance(reads, StageFailure):
                recs = [record(path, 0, None, reads)]
            else:
                recs = [record(path, i, read, None) for i, read in enumerate(reads)]
                if args.debug_dir:
                    from gauged.reader.annotate import annotate

                    for i, read in enumerate(reads):
                        cv2.imwrite(str(args.debug_dir / f"{Path(path).stem}-{i}.png"), annotate(read))
        for rec in recs:
            print(json.dumps(rec) if args.json else _line(rec), flush=True)
    return 0
