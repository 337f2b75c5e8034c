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
PROGRESS_EVERY = 50  # images between progress lines on stderr


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("eval", help="measure reading accuracy or model quality on labelled data",
                                   description="Evaluate on labelled data; see the sub-commands.")
    sub = parser.add_subparsers(dest="what", metavar="WHAT", required=True)
    readings = sub.add_parser(
        "readings", help="end-to-end reading error on a folder with labels.json(l)",
        description="Read every labelled image (image, reading, min, max) and print the failure rate, mean and "
        "median relative error |pred - true| / (max - min) over attempted images and over all images (failures "
        "as 100%), failures by stage and reason, and the needle-at-rest subset separately. On synthetic sets "
        "(gauged synth images) the images are broken down by the printed numbers' height in px as well, and the "
        "units of the readings of dials that print theirs are counted right, wrong or missing.",
        epilog="example: gauged eval readings --data ../shared/datasets/gauge-readings-dev")
    readings.add_argument("--data", type=Path, required=True, help="folder with labels.json or labels.jsonl")
    readings.add_argument("--json", action="store_true", help="print the full result as JSON")
    readings.add_argument("--threads", type=int, default=2)
    readings.add_argument("--models", type=Path, help="folder with crop.onnx/detector.onnx to use instead of the shipped models "
                               "(and numbers.onnx/ocr_det_int8.onnx/notch_check.onnx, where it holds them)")
    readings.set_defaults(func=run_readings)
    models = sub.add_parser(
        "models", help="detector and crop-model metrics on the real sets (and synthetic crops)",
        description="Detector: box IoU and recall at IoU 0.5 on substation-dials. Crop model: needle mask IoU "
        "and direction on needle-polygons/valid; notch recall within 4 px at 448 px, unassigned peaks and ends found on "
        "a synthetic crop shard, after the notch check (notch_check.onnx) and of the crop model's peaks alone.",
        epilog="example: gauged eval models --data ../shared/datasets --synth data/crop-val")
    models.add_argument("--data", type=Path, required=True, help="the shared datasets folder")
    models.add_argument("--synth", type=Path, help="synthetic validation crop shard (notch metrics)")
    models.add_argument("--closeups", type=Path,
                        help="rendered close-ups with labels.jsonl (gauged synth images --kind crop): detector figures")
    models.add_argument("--json", action="store_true")
    models.add_argument("--threads", type=int, default=2)
    models.add_argument("--models", type=Path, help="folder with crop.onnx/detector.onnx to use instead of the shipped models "
                               "(and numbers.onnx/ocr_det_int8.onnx/notch_check.onnx, where it holds them)")
    models.set_defaults(func=run_models)
    recording = sub.add_parser(
        "recording", help="readings of a replay against a synthetic recording's truth channel",
        description="Compare the /gauged/readings of READINGS.mcap (from gauged replay) with the /<camera>/truth "
        "channel of the synthetic RECORDING.mcap: per gauge, failures and relative error of raw and smoothed values.",
        epilog="example: gauged replay recordings/demo.mcap --config recordings/demo.yaml --out /tmp/out.mcap && "
        "gauged eval recording recordings/demo.mcap /tmp/out.mcap")
    recording.add_argument("recording", type=Path)
    recording.add_argument("readings", type=Path)
    recording.add_argument("--json", action="store_true")
    recording.set_defaults(func=run_recording)


def run_readings(args: argparse.Namespace) -> int:
    from gauged.reader.evidence import evidence
    from gauged.reader.factory import build_reader

    try:
        labels = load_labels(args.data)
        reader = build_reader(ReaderConfig(threads=args.threads, models_dir=args.models))
    except FileNotFoundError as exc:
        print(exc, file=sys.stderr)
        return 2
    except ModelNotAvailable as exc:
        log.error("%s", exc)
        return 1

    done = {"images": 0, "failed": 0}

    def read(label):
        outcome = read_one(label)
        value = outcome[0]
        done["images"] += 1
        done["failed"] += value is None
        if done["images"] % PROGRESS_EVERY == 0 or done["images"] == len(labels):
            log.info("read %d/%d images, %d refused", done["images"], len(labels), done["failed"])
        return outcome

    def read_one(label):
        image = cv2.imread(str(image_path(args.data, label)), cv2.IMREAD_COLOR)
        if image is None:
            return None, StageFailure("decode", "unreadable", label.image), None
        reads = reader.read_image(image)
        if isinstance(reads, StageFailure):
            return None, reads, None
        best = reads[0]
        if best.value is None:
            return None, best.failure, None
        return best.value.value, None, best.unit, best.value.confidence, evidence(best)

    result = report(evaluate(labels, read))
    print(json.dumps(result, indent=1) if args.json else format_table(result))
    return 0


def run_models(args: argparse.Namespace) -> int:
    from gauged.evaluation.models import evaluate_models, format_models

    try:
        result = evaluate_models(args.data, args.synth, args.threads, args.models, args.closeups)
    except ModelNotAvailable as exc:
        log.error("%s", exc)
        return 1
    print(json.dumps(result, indent=1) if args.json else format_models(result))
    return 0


def run_recording(args: argparse.Namespace) -> int:
    from gauged.evaluation.recording import compare, format_comparison

    for path in (args.recording, args.readings):
        if not path.is_file():
            print(f"{path}: no such file", file=sys.stderr)
            return 2
    result = compare(args.recording, args.readings)
    print(json.dumps(result, indent=1) if args.json else format_comparison(result))
    return 0
