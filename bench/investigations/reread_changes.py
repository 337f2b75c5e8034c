"""Re-read images of a finished ``gauged eval readings --json`` run with the current reader and count
what changed: wrong readings (> 5% of span) fixed or refused, right ones broken or refused.

    python bench/investigations/reread_changes.py --eval held.json --data data/held1000 [--right 150]

Reads every wrong reading of the run and ``--right`` of its right ones (every k-th), so a reader
change is checked on its targets and on a sample of what it must not break, in minutes.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import cv2

from gauged.config.model import ReaderConfig
from gauged.reader.factory import build_reader

WRONG = 0.05


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--eval", type=Path, required=True)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--right", type=int, default=150)
    parser.add_argument("--refused", type=int, default=0, help="also re-read this many refused images")
    args = parser.parse_args()
    images = json.loads(args.eval.read_text())["images"]
    labels = {json.loads(line)["image"]: json.loads(line) for line in (args.data / "labels.jsonl").read_text().splitlines()}
    wrong = [i for i in images if i["relative_error"] is not None and i["relative_error"] > WRONG]
    right = [i for i in images if i["relative_error"] is not None and i["relative_error"] <= WRONG]
    refused = [i for i in images if i["value"] is None]
    right = right[:: max(1, len(right) // args.right)][: args.right]
    refused = refused[:: max(1, len(refused) // args.refused)][: args.refused] if args.refused else []
    reader = build_reader(ReaderConfig(threads=1))
    counts: dict[str, int] = {}
    for group, items in (("wrong", wrong), ("right", right), ("refused", refused)):
        for item in items:
            gauge = max(labels[item["image"]]["gauges"], key=lambda g: g["box"][2] - g["box"][0])
            span = gauge["max"] - gauge["min"]
            reads = reader.read_image(cv2.imread(str(args.data / item["image"])))
            read = reads[0] if isinstance(reads, list) else None
            value = read.value.value if read is not None and read.value is not None else None
            now = "refused" if value is None else ("wrong" if abs(value - item["truth"]) / span > WRONG else "right")
            key = f"{group}->{now}"
            counts[key] = counts.get(key, 0) + 1
            if group != now:
                print(f"{item['image']}: {group} -> {now} (truth {item['truth']:g}, was {item['value']}, now {value})")
    print(json.dumps(counts, sort_keys=True))


if __name__ == "__main__":
    main()
