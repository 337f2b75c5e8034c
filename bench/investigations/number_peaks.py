"""Where the OCR reads nothing, does the crop model still know where the numbers are?

    gauged eval readings --data data/held1000 --json > held.json
    python bench/investigations/number_peaks.py --data data/held1000 --report held.json

On the renders the report refused at the given reasons (default ``ocr/no_text`` and
``scale/too_few_markers``) whose numbers were captured at least 5 px tall, it counts the main
scale's printed numbers that have a number peak of the crop model on them (within 0.6 of their
height), and the peaks. Then, at each peak on a number, it reads the windows the last look tries
(:mod:`gauged.reader.ocr.hint_numbers`: every orientation and height) with the number net and counts
the peaks where some window reads the printed value: what the look can find at best, before it
chooses one guess per dial. An analysis tool: the truth comes from the labels.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
import cv2  # noqa: E402
import numpy as np  # noqa: E402
from common import header  # noqa: E402

from gauged.config.model import ReaderConfig  # noqa: E402
from gauged.reader.factory import NUMBER_NET_MODEL, build_reader  # noqa: E402
from gauged.reader.ocr.text import crop_quad  # noqa: E402
from gauged.reader.ocr.hint_numbers import (  # noqa: E402
    HEIGHTS,
    ORIENTATIONS,
    WIDTHS,
    WINDOW_HEIGHT,
    window_quad,
)
from gauged.reader.ocr.number_net import NumberNet  # noqa: E402
from gauged.reader.ocr.numbers import parse_number  # noqa: E402
from gauged.reader.onnx_model import packaged_model_path  # noqa: E402
from gauged.types import StageFailure  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="a synthetic set (labels.jsonl from gauged synth images)")
    parser.add_argument("--report", type=Path, required=True, help="`gauged eval readings --json` output of that set")
    parser.add_argument("--reasons", nargs="+", default=["ocr/no_text", "scale/too_few_markers"])
    args = parser.parse_args()
    header("Number peaks of the crop model on the numbers the OCR did not read")
    chosen = [i["image"] for i in json.loads(args.report.read_text())["images"]
              if i["failure"] and f"{i['failure']['stage']}/{i['failure']['reason']}" in args.reasons
              and (i.get("captured_number_px") or 0) >= 5]
    labels = {}
    for line in (args.data / "labels.jsonl").read_text().splitlines():
        record = json.loads(line)
        if record.get("gauges"):
            labels[record["image"]] = max(record["gauges"], key=lambda g: (g["box"][2] - g["box"][0]) * (g["box"][3] - g["box"][1]))
    reader = build_reader(ReaderConfig(threads=2))
    net = NumberNet(packaged_model_path(NUMBER_NET_MODEL), threads=2)
    numbers = covered = peaks = on_numbers = readable = 0
    for name in chosen:
        image = cv2.imread(str(args.data / name), cv2.IMREAD_COLOR)
        read = reader.read_image(image)
        read = None if isinstance(read, StageFailure) else read[0]
        printed = [(np.asarray(n["quad"], float), n["value"]) for n in labels[name]["scales"][0]["numbers"] if n.get("value") is not None]
        numbers += len(printed)
        if read is None or read.keypoints is None or read.arc is None or not len(read.keypoints.numbers):
            continue
        at = read.crop.points_to_frame(read.keypoints.numbers.points)
        peaks += len(at)
        near = [[np.linalg.norm(p - q.mean(axis=0)) <= max(0.6 * np.linalg.norm(q[0] - q[3]), 3.0) for p in at] for q, _ in printed]
        covered += sum(any(row) for row in near)
        centre = read.crop.points_to_frame(np.asarray([read.arc.centre], float))[0]
        radius = math.sqrt(read.arc.ellipse.a * read.arc.ellipse.b) * read.crop.scale
        for k, p in enumerate(at):
            values = [v for (_, v), row in zip(printed, near) if row[k]]
            if not values:
                continue
            on_numbers += 1
            outward = (p - centre) / max(float(np.linalg.norm(p - centre)), 1e-9)
            lines = [crop_quad(image, window_quad(p, WINDOW_HEIGHT * f * radius, w * f * radius,
                                                  outward if o == "radial" else np.array([0.0, -1.0])))
                     for o in ORIENTATIONS for f in HEIGHTS for w in WIDTHS]
            parsed = [parse_number(t) for t in net.read(lines)]
            readable += any(not isinstance(n, StageFailure) and n.value == values[0] for n in parsed)
    print(f"{len(chosen)} refused renders ({', '.join(args.reasons)}), numbers captured >= 5 px")
    print(f"printed numbers: {numbers}; with a number peak on them: {covered} ({covered / max(1, numbers):.0%}); peaks: {peaks}")
    print(f"peaks on a number: {on_numbers}; some window read its value: {readable} ({readable / max(1, on_numbers):.0%})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
