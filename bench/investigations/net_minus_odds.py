"""How well does the number net tell a minus the text box left out from a tick or a blur beside a number?

Reads each render of a synthetic set with the shipped reader (its minus net off) and, wherever the minus look
(:func:`gauged.reader.ocr.minus_sign.number_net_reads`) runs, scores every unsigned number other than
0 in its line widened left: the net's greedy string, and its CTC log-odds log P("-" + digits) -
log P(digits). The truth is the label's primary scale: the number is printed with a minus when only
"-" + digits is among its texts, without when only the digits are (mixed cases are left out). Prints
the odds' percentiles by truth and by whether the line faces the ring's ticks, per-number hit rates
at a few thresholds, and per dial how often a share rule signs a dial of negatives or a positive one.

    python bench/investigations/net_minus_odds.py --data DIR [--data DIR2] [--count 400] [--out rows.json]
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import cv2
import numpy as np

import gauged.reader.ocr.minus_sign as minus_sign
from gauged.config.model import ReaderConfig
from gauged.reader.factory import build_reader
from gauged.reader.ocr.text import crop_quad


def collect(folder: Path, count: int) -> list[dict]:
    reader = build_reader(ReaderConfig(ocr_minus_net=False))  # the number net alone looks for the minus (the rule before the minus net)
    number_net = reader.ocr.engine.number_net
    rows: list[dict] = []
    current: dict = {}
    look = minus_sign.number_net_reads

    def scored(texts, image, net, circle):
        for k in minus_sign.unsigned_numbers(texts):
            box, text = texts[k], texts[k].text.strip()
            plain, signed = text in current["texts"], "-" + text in current["texts"]
            if plain == signed:
                continue
            line = [crop_quad(image, minus_sign.left_extended(box.quad, minus_sign.LEFT_MARGIN))]
            rows.append({"set": folder.name, "image": current["image"], "text": text, "minus": signed,
                         "odds": float(number_net.minus_log_odds(line, [text])[0]), "read": number_net.read(line)[0],
                         "faces": bool(minus_sign.faces_ticks(box.quad, circle))})
        return look(texts, image, net, circle)

    minus_sign.number_net_reads = scored
    try:
        read_renders(reader, folder, count, current)
    finally:
        minus_sign.number_net_reads = look
    return rows


def read_renders(reader, folder: Path, count: int, current: dict) -> None:
    """Read the first ``count`` renders of ``folder`` with ``reader``, with ``current`` holding each one's
    image name and its primary scale's texts while it is read."""
    labels = [json.loads(line) for line in (folder / "labels.jsonl").read_text().splitlines()][:count]
    for n, label in enumerate(labels, 1):
        scale = next(s for s in label["gauges"][0]["scales"] if s["role"] == "primary")
        current.update(image=label["image"], texts={x["text"].replace("\u2212", "-") for x in scale["numbers"]})
        reader.read_image(cv2.imread(str(folder / label["image"])))
        if n % 50 == 0:
            print(f"{folder.name}: {n}/{len(labels)} renders", flush=True)


def report(rows: list[dict]) -> None:
    for faces in (False, True):
        for minus in (True, False):
            odds = np.array([r["odds"] for r in rows if r["minus"] == minus and r["faces"] == faces])
            if len(odds):
                greedy = sum(r["read"] == "-" + r["text"] for r in rows if r["minus"] == minus and r["faces"] == faces)
                print(f"faces ticks {faces!s:5} minus printed {minus!s:5}: {len(odds):5} numbers, odds p5/p25/p50/p75/p95 "
                      f"{np.percentile(odds, [5, 25, 50, 75, 95]).round(1).tolist()}, net's string '-' + digits {greedy}")
    readable = [r for r in rows if not r["faces"]]
    for cut in (0.0, 2.0, 4.0, 6.0):
        hit = sum(r["minus"] and r["odds"] > cut for r in readable)
        false = sum(not r["minus"] and r["odds"] > cut for r in readable)
        print(f"odds > {cut:g}: {hit} of {sum(r['minus'] for r in readable)} printed minus signs, "
              f"{false} of {sum(not r['minus'] for r in readable)} numbers without")
    dials = defaultdict(list)
    for r in rows:
        dials[(r["set"], r["image"])].append(r)
    negative = [k for k, rs in dials.items() if all(r["minus"] for r in rs)]
    positive = [k for k, rs in dials.items() if not any(r["minus"] for r in rs)]
    rules = {"net's string, share 0.75": lambda r: r["read"] == "-" + r["text"],
             "odds > 2, share 0.75": lambda r: r["odds"] > 2.0}
    for name, seen in rules.items():
        def signs(rs):
            hits = sum(seen(r) for r in rs if not r["faces"])
            return sum(not r["faces"] for r in rs) >= 2 and hits >= max(2, 0.75 * len(rs))
        print(f"{name}: {sum(signs(dials[k]) for k in negative)} of {len(negative)} dials of negatives signed, "
              f"{sum(signs(dials[k]) for k in positive)} of {len(positive)} positive dials")


def main(doc: str = __doc__, collect=collect, report=report, rows: str = "per-number rows") -> None:
    """The command line of this script, and of others that collect rows from renders and report them."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, action="append", required=True, help="a `gauged synth images` folder (repeatable)")
    parser.add_argument("--count", type=int, default=400, help="renders read from each folder")
    parser.add_argument("--out", type=Path, help=f"write the {rows} here as JSON")
    args = parser.parse_args()
    found = [row for folder in args.data for row in collect(folder, args.count)]
    if args.out:
        args.out.write_text(json.dumps(found))
    report(found)


if __name__ == "__main__":
    main()
