"""How well the recogniser's log-odds of a minus sign (``ScaleMarker.minus_odds``) tell printed minus
signs from unprinted ones, on a labelled render set: each number read on a dial is matched to the
printed values by magnitude, and its odds are listed by the sign it truly has and whether its text
shows a minus.

    .venv/bin/python bench/investigations/minus_odds.py --data DIR [--limit 200] [--out odds.jsonl]

Numbers whose magnitude the dial prints with both signs (-40..40) or not at all are left out.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2
import numpy as np

from gauged.config.model import ReaderConfig
from gauged.reader.factory import build_reader
from gauged.reader.ocr.numbers import MINUS_LIKE


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="folder with labels.jsonl and the images")
    parser.add_argument("--limit", type=int, default=200)
    parser.add_argument("--out", type=Path, help="one JSON line per number (image, text, odds, sign, shown)")
    args = parser.parse_args()
    reader = build_reader(ReaderConfig(threads=1))
    rows = []
    labels = [json.loads(line) for line in (args.data / "labels.jsonl").read_text().splitlines()][: args.limit]
    for n, label in enumerate(labels):
        printed = {round(m["value"], 9) for s in label["gauges"][0]["scales"] if s["role"] == "primary" for m in s["majors"]}
        result = reader.read_image(cv2.imread(str(args.data / label["image"]), cv2.IMREAD_COLOR))
        for read in result if isinstance(result, list) else []:
            for m in read.markers:
                magnitude = round(abs(m.value), 9)
                if m.minus_odds is None or magnitude == 0 or (magnitude in printed) == (-magnitude in printed):
                    continue
                rows.append({"image": label["image"], "text": m.text, "odds": m.minus_odds,
                             "negative": -magnitude in printed, "shown": m.text.strip()[:1] in MINUS_LIKE})
        if (n + 1) % 50 == 0:
            print(f"{n + 1}/{len(labels)} images, {len(rows)} numbers", file=sys.stderr)
    if args.out:
        args.out.write_text("".join(json.dumps(r) + "\n" for r in rows))
    for negative in (True, False):
        for shown in (True, False):
            odds = np.array([r["odds"] for r in rows if r["negative"] == negative and r["shown"] == shown])
            if len(odds):
                q = np.percentile(odds, [10, 25, 50, 75, 90])
                print(f"printed {'negative' if negative else 'positive'}, minus {'read' if shown else 'not read'}: "
                      f"{len(odds)} numbers, odds p10/p25/p50/p75/p90 " + " ".join(f"{v:.1f}" for v in q))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
