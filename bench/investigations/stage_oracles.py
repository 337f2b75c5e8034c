"""Which stage costs the refusals? The reader re-run with one stage replaced by the ground truth.

    gauged eval readings --data data/held1000 --json > held.json
    python bench/investigations/stage_oracles.py --data data/held1000 --report held.json

A synthetic set (``gauged synth images``) labels each gauge's scale ellipse, ends, major notches,
printed numbers and unit. On every image the ``--report`` refused, the reader is run again with
- ``arc``: the scale arc built from the labels (ellipse, pivot as centre, start/end, majors) instead
  of the one fitted to the crop model's notches;
- ``ocr``: the labelled numbers (their centres and values) and unit as the OCR stage's markers;
- ``arc+ocr``: both.
It prints how many of the refused images each variant still refuses, and the largest error of what
it reads. What "ocr" recovers is the OCR's share of the refusals, what "arc" recovers the notch
model's and the ellipse fit's. An analysis tool, not a reader: the replaced stages come from labels.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
import cv2  # noqa: E402
import numpy as np  # noqa: E402
from common import header  # noqa: E402

import gauged.reader.pipeline as pipeline  # noqa: E402
from gauged.config.model import ReaderConfig  # noqa: E402
from gauged.evaluation.readings import evaluate, image_path, load_labels, report  # noqa: E402
from gauged.geometry.angles import wrap_angle  # noqa: E402
from gauged.geometry.dial_frame import dial_angle  # noqa: E402
from gauged.reader.factory import build_reader  # noqa: E402
from gauged.reader.stages.ellipse import ScaleArc  # noqa: E402
from gauged.types import Ellipse, ScaleMarker, StageFailure  # noqa: E402

VARIANTS = ("arc", "ocr", "arc+ocr")


class Truth:
    """The label of the image being read, and the crop the reader cut from it (set as it reads)."""

    def __init__(self) -> None:
        self.gauge: dict = {}
        self.crop = None

    def to_crop(self, points) -> np.ndarray:
        return (np.asarray(points, float).reshape(-1, 2) - self.crop.to_frame[:2, 2]) / self.crop.scale

    def arc(self, keypoints, crop_size) -> ScaleArc:
        """The primary scale's arc from the labels, in crop pixels (replaces ``fit_scale_arc``)."""
        scale, s = self.gauge["scales"][0], self.crop.scale
        e = scale["ellipse"]
        (cx, cy), = self.to_crop([[e["cx"], e["cy"]]])
        ellipse = Ellipse(float(cx), float(cy), e["a"] / s, e["b"] / s, e["theta"] % math.pi)
        pivot = tuple(float(v) for v in self.to_crop([self.gauge["pivot"]])[0])
        start = float(dial_angle(ellipse, self.to_crop([scale["start"]]), pivot)[0])
        end = float(dial_angle(ellipse, self.to_crop([scale["end"]]), pivot)[0])
        notches = self.to_crop([m["point"] for m in scale["majors"]])
        return ScaleArc(ellipse, pivot, start, end, wrap_angle(start, end), notches, 0.5, False)

    def markers(self) -> tuple[list[ScaleMarker], str]:
        """The primary scale's printed numbers as markers (crop-pixel boxes) and its unit."""
        scale = self.gauge["scales"][0]
        out = []
        for number in scale["numbers"]:
            if number.get("value") is None:
                continue
            quad = self.to_crop(number["quad"])
            (x0, y0), (x1, y1) = quad.min(axis=0), quad.max(axis=0)
            out.append(ScaleMarker(number["text"], float(number["value"]), (float(x0), float(y0), float(x1), float(y1))))
        return out, scale["unit"]


class TrueOcr:
    """The OCR stage answering with the labelled numbers (no number net: no retry, no last look)."""

    has_number_net = False

    def __init__(self, truth: Truth) -> None:
        self.truth = truth

    def read_markers(self, crop, arc, hints, detail=None):
        return self.truth.markers()

    def reread_markers(self, crop, arc, hints, detail=None):
        return None


def run(variant: str, data: Path, labels, records: dict, threads: int) -> dict:
    truth = Truth()
    reader = build_reader(ReaderConfig(threads=threads))
    if "ocr" in variant:
        reader.ocr = TrueOcr(truth)
    crop_and_keypoints = pipeline.GaugeReader._crop_and_keypoints
    fit_scale_arc = pipeline.fit_scale_arc

    def keep_crop(self, image, box, result, timer, require_notches):
        ok = crop_and_keypoints(self, image, box, result, timer, require_notches)
        truth.crop = result.crop if result.crop is not None else truth.crop
        return ok

    pipeline.GaugeReader._crop_and_keypoints = keep_crop
    if "arc" in variant:
        pipeline.fit_scale_arc = truth.arc
    try:
        def read(label):
            truth.gauge = records[label.image]
            reads = reader.read_image(cv2.imread(str(image_path(data, label)), cv2.IMREAD_COLOR))
            if isinstance(reads, StageFailure):
                return None, reads
            first = reads[0]
            return (first.value.value, None) if first.value is not None else (None, first.failure)

        return report(evaluate(labels, read))
    finally:
        pipeline.GaugeReader._crop_and_keypoints = crop_and_keypoints
        pipeline.fit_scale_arc = fit_scale_arc


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="a synthetic set (labels.jsonl from gauged synth images)")
    parser.add_argument("--report", type=Path, required=True, help="`gauged eval readings --json` output of that set")
    parser.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS))
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    header("The reader with stages replaced by the labels, on the images it refused")
    refused = {i["image"] for i in json.loads(args.report.read_text())["images"] if i["failure"] is not None}
    records = {}
    for line in (args.data / "labels.jsonl").read_text().splitlines():
        record = json.loads(line)
        if record.get("gauges"):
            # the gauge the labels are read for: the largest box, as gauged.evaluation.readings takes it
            records[record["image"]] = max(record["gauges"], key=lambda g: (g["box"][2] - g["box"][0]) * (g["box"][3] - g["box"][1]))
    labels = [label for label in load_labels(args.data) if label.image in refused]
    print(f"{len(labels)} refused images of {args.data}")
    print("| truth given for | still refused | read | largest error of those read | main refusals left |")
    print("|---|---|---|---|---|")
    for variant in args.variants:
        result = run(variant, args.data, labels, records, args.threads)
        summary = result["all"]
        reasons = Counter({k: v for k, v in summary["failures_by_reason"].items()}).most_common(3)
        largest = summary["max_relative_error"]
        largest = "-" if largest is None or summary["failures"] == summary["count"] else f"{largest:.1%}"
        print(f"| {variant} | {summary['failures']} | {summary['count'] - summary['failures']} | {largest} | "
              + ", ".join(f"{k} {v}" for k, v in reasons) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
