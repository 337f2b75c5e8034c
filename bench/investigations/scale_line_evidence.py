"""How far do a reading's own agreeing numbers lie past its scale's fitted ends, and how many are distinct?

    python bench/investigations/scale_line_evidence.py --data data/held1000 [--out rows.json] [--top 12]

Reads every image of a labelled folder (labels.json or labels.jsonl, as ``gauged eval readings``)
and, for each attempted reading, takes the primary scale's agreeing numbers read as digits: how far
the farthest lies past an end of the fitted range (as a share of that range), and how many distinct
values they are, beside the reading's relative error. Session 14 ran it at e89aa88, before
:mod:`gauged.reader.stages.scale` had its checks ``numbers_past_ends`` and distinct values, on dev300,
fresh300, the held-out 1,000 and the 21 real photos, and chose ``PAST_END`` (0.5) from the rows:
right readings <= 0.35 past an end, the wild 000516 1.58. At later commits it shows the margin the
readings that pass keep. An analysis tool: the truth comes from the labels.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2

from gauged.config.model import ReaderConfig
from gauged.evaluation.readings import image_path, load_labels
from gauged.reader.factory import build_reader
from gauged.reader.stages.scale_checks import agreeing_digit_values


def evidence(folder: Path, threads: int) -> list[dict]:
    labels = load_labels(folder)
    reader = build_reader(ReaderConfig(threads=threads))
    rows = []
    for i, label in enumerate(labels, 1):
        image = cv2.imread(str(image_path(folder, label)), cv2.IMREAD_COLOR)
        reads = reader.read_image(image) if image is not None else []
        if isinstance(reads, list) and reads and reads[0].value is not None and reads[0].scale is not None:
            scale = reads[0].scale
            values = sorted(set(agreeing_digit_values(scale)))
            low, high = sorted((scale.min_value, scale.max_value))
            past = max(low - values[0], values[-1] - high, 0.0) if values else 0.0
            rows.append({"image": label.image, "error": abs(reads[0].value.value - label.reading) / (label.max - label.min),
                         "past_share": past / max(high - low, 1e-12), "distinct": len(values), "values": values,
                         "min": scale.min_value, "max": scale.max_value})
        if i % 100 == 0:
            print(f"# read {i}/{len(labels)}, {len(rows)} attempted", file=sys.stderr, flush=True)
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="labelled folder")
    parser.add_argument("--out", type=Path, help="write every row as JSON")
    parser.add_argument("--top", type=int, default=12, help="rows to print, farthest past an end first")
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    rows = evidence(args.data, args.threads)
    if args.out:
        args.out.write_text(json.dumps(rows, indent=1))
    print(f"# {args.data}: {len(rows)} attempted readings")
    for row in sorted(rows, key=lambda r: -r["past_share"])[: args.top]:
        print(f"{row['image']:28s} error {100 * row['error']:8.2f}%  past an end {row['past_share']:.3f} of the range  "
              f"{row['distinct']} distinct: {row['values']}  scale {row['min']:.4g}..{row['max']:.4g}")
    few = [r for r in rows if r["distinct"] < 3]
    print(f"# fewer than 3 distinct agreeing values: {len(few)}", *(f"{r['image']} ({100 * r['error']:.2f}%)" for r in few))
    return 0


if __name__ == "__main__":
    sys.exit(main())
