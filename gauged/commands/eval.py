"""``gauged eval readings|models``: measure the reader and its models on labelled data."""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

import cv2

from gauged.config.model import ReaderConfig
from gauged.evaluation.readings import evaluate, format_table, image_path, load_labels, report
from gauged.reader.onnx_model import ModelNotAvailable
from gauged.types import StageFailure

log = logging.getLogger(__name__)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("eval", help="measure reading accuracy or model quality on labelled data",
                                   description="Evaluate on labelled data; see the sub-commands.")
    sub = parser.add_subparsers(dest="what", metavar="WHAT", required=True)
    readings = sub.add_parser(
        "readings", help="end-to-end reading error on a folder with labels.json(l)",
        description="Read every labelled image (image, reading, min, max) and print the failure rate, mean and "
        "median relative error |pred - true| / (max - min) over attempted images and over all images (failures "
        "as 100%%), failures by stage and reason, and the needle-at-rest subset separately.",
        epilog="example: gauged eval readings --data ../shared/datasets/gauge-readings-dev")
    readings.add_argument("--data", type=Path, required=True, help="folder with labels.json or labels.jsonl")
    readings.add_argument("--json", action="store_true", help="print the full result as JSON")
    readings.add_argument("--threads", type=int, default=2)
    readings.set_defaults(func=run_readings)
    models = sub.add_parser(
        "models", help="detector and crop-model metrics on the real sets (and synthetic crops)",
        description="Detector: box IoU and recall at IoU 0.5 on substation-dials. Crop model: needle mask IoU "
        "and direction on needle-polygons/valid; notch recall within 4 px at 448 px on a synthetic crop shard.",
        epilog="example: gauged eval models --data ../shared/datasets --synth data/crop-val")
    models.add_argument("--data", type=Path, required=True, help="the shared datasets folder")
    models.add_argument("--synth", type=Path, help="synthetic validation crop shard (notch metrics)")
    models.add_argument("--json", action="store_true")
    models.add_argument("--threads", type=int, default=2)
    models.set_defaults(func=run_models)


def run_readings(args: argparse.Namespace) -> int:
    from gauged.reader.factory import build_reader

    try:
        labels = load_labels(args.data)
        reader = build_reader(ReaderConfig(threads=args.threads))
    except FileNotFoundError as exc:
        print(exc, file=sys.stderr)
        return 2
    except ModelNotAvailable as exc:
        log.error("%s", exc)
        return 1

    def read(label):
        image = cv2.imread(str(image_path(args.data, label)), cv2.IMREAD_COLOR)
        if image is None:
            return None, StageFailure("decode", "unreadable", label.image)
        reads = reader.read_image(image)
        if isinstance(reads, StageFailure):
            return None, reads
        best = reads[0]
        return (best.value.value, None) if best.value is not None else (None, best.failure)

    result = report(evaluate(labels, read))
    print(json.dumps(result, indent=1) if args.json else format_table(result))
    return 0


def run_models(args: argparse.Namespace) -> int:
    from gauged.evaluation.models import evaluate_models, format_models

    try:
        result = evaluate_models(args.data, args.synth, args.threads)
    except ModelNotAvailable as exc:
        log.error("%s", exc)
        return 1
    print(json.dumps(result, indent=1) if args.json else format_models(result))
    return 0
