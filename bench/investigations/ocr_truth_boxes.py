"""Is an OCR refusal a failure to find the numbers or to read them? The recogniser on the true boxes.

    gauged eval readings --data data/dev300 --json > dev300.json
    python bench/investigations/ocr_truth_boxes.py --data data/dev300 --report dev300.json

A synthetic set (``gauged synth images``) labels every printed number with its quad. This script
gives the OCR recogniser each number of the main scale cut at its true quad (grown by a quarter, as
the reader's own boxes are), so no text detection, hint or rectification is involved, and counts the
numbers read right (the exact value, score >= the reader's ``min_score``), grouped by what the reader made of
the image in ``--report`` (read, or the reason it refused). Numbers read right at their true boxes
on a refused image were lost to localisation; numbers not read even there, to recognition.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
import cv2  # noqa: E402
import numpy as np  # noqa: E402
from common import header  # noqa: E402

from gauged.reader.ocr.text import crop_quad  # noqa: E402
from gauged.reader.ocr.numbers import parse_number  # noqa: E402
from gauged.reader.stages.ocr import ScaleTextReader  # noqa: E402

GROUPS = ("read", "ocr/no_text", "scale/too_few_markers", "scale/too_few_inliers")
MARGIN = 1.25  # quads grown about their centre by this factor


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="a synthetic set (labels.jsonl with number quads)")
    parser.add_argument("--report", type=Path, required=True, help="`gauged eval readings --json` output of that set")
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    header("OCR recogniser on the true number boxes, by reader outcome")
    outcome = {}
    for image in json.loads(args.report.read_text())["images"]:
        failure = image["failure"]
        outcome[image["image"]] = "read" if failure is None else f"{failure['stage']}/{failure['reason']}"
    reader = ScaleTextReader(threads=args.threads)  # its engine and its score threshold
    engine = reader.engine
    counts: dict[str, list[int]] = defaultdict(lambda: [0, 0, 0])  # images, numbers, read right
    for line in (args.data / "labels.jsonl").read_text().splitlines():
        record = json.loads(line)
        if record["image"] not in outcome or not record.get("gauges"):
            continue
        gauge = max(record["gauges"], key=lambda g: g["diameter_px"])
        numbers = [n for s in gauge["scales"] if s["role"] == "primary" for n in s.get("numbers", ()) if n.get("quad")]
        if not numbers:
            continue
        image = cv2.imread(str(args.data / record["image"]), cv2.IMREAD_COLOR)
        lines = []
        for number in numbers:
            quad = np.asarray(number["quad"], np.float32)
            centre = quad.mean(axis=0)
            lines.append(crop_quad(image, centre + (quad - centre) * MARGIN))
        right = 0
        for rec, number in zip(engine.recognize(lines), numbers, strict=True):
            parsed = parse_number(rec.text)
            right += bool(parsed) and rec.score >= reader.min_score and abs(parsed.value - number["value"]) < 1e-9
        group = outcome[record["image"]] if outcome[record["image"]] in GROUPS else "other refusals"
        entry = counts[group]
        entry[0] += 1
        entry[1] += len(numbers)
        entry[2] += right
    print("| reader outcome | images | numbers | read right at their true boxes |")
    print("|---|---|---|---|")
    for group in (*GROUPS, "other refusals"):
        if group in counts:
            images, total, right = counts[group]
            print(f"| {group} | {images} | {total} | {right} ({right / total:.0%}) |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
