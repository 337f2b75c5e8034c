"""How well do the minus look's dial rules tell scales of negatives from positive ones?

Reads each render of a synthetic set with the shipped reader and, wherever the minus look weighs the
widened lines (:func:`gauged.reader.ocr.minus_sign.summed_minus_signs`), records every unsigned number
other than 0 with both nets' log-odds of a minus before it (the number net's CTC, the minus net's),
whether its line faces the ticks, and the truth (printed with a minus when only "-" + digits is among
its scale's texts, without when only the digits are). Per dial whose numbers are all printed with or
all without (and two or more lines weighed), prints how many of each kind the rules sign: the shipped
one (the lesser of the two odds, clipped, summed over the lines), the sum of the two instead, and
each net alone, at a few thresholds.

    python bench/investigations/minus_evidence.py --data DEV_CW --data DEV_CCW [--count 400] [--out rows.json]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

import gauged.reader.ocr.minus_sign as minus_sign
from gauged.config.model import ReaderConfig
from gauged.reader.factory import build_reader
from gauged.reader.ocr.text import crop_quad

sys.path.insert(0, str(Path(__file__).resolve().parent))
from net_minus_odds import main, read_renders  # noqa: E402  (the same reading of renders and command line)


def collect(folder: Path, count: int) -> list[dict]:
    reader = build_reader(ReaderConfig(threads=1))
    dials: list[dict] = []
    current: dict = {}
    look = minus_sign.summed_minus_signs

    def recorded(texts, image, net_odds, minus_odds, circle):
        readable = minus_sign.readable_numbers(texts, circle)
        lines = [crop_quad(image, minus_sign.left_extended(texts[k].quad, minus_sign.LEFT_MARGIN)) for k in readable]
        digits = [texts[k].text.strip() for k in readable]
        numbers = [{"text": d, "plain": d in current["texts"], "signed": "-" + d in current["texts"],
                    "net": float(n), "minus": float(m)}
                   for d, n, m in zip(digits, net_odds(lines, digits) if lines else [], minus_odds(lines) if lines else [])]
        dials.append({"set": folder.name, "image": current["image"], "numbers": numbers})
        return look(texts, image, net_odds, minus_odds, circle)

    minus_sign.summed_minus_signs = recorded
    try:
        read_renders(reader, folder, count, current)
    finally:
        minus_sign.summed_minus_signs = look
    return dials


def report(dials: list[dict]) -> None:
    clip = minus_sign.ODDS_CLIP
    kinds = []
    for d in dials:
        known = [x for x in d["numbers"] if x["plain"] != x["signed"]]
        if len(d["numbers"]) >= 2 and known and (all(x["signed"] for x in known) or not any(x["signed"] for x in known)):
            kinds.append((all(x["signed"] for x in known), d["numbers"]))
    negatives = sum(k for k, _ in kinds)
    print(f"{len(kinds)} dials with two or more lines weighed: {negatives} scales of negatives, {len(kinds) - negatives} positive")
    rules = {"lesser (shipped)": np.minimum, "sum": np.add, "number net": lambda n, m: n, "minus net": lambda n, m: m}
    for name, combine in rules.items():
        for cut in (0.0, 1.0, 2.0, 3.0, 4.0):
            signed = {True: 0, False: 0}
            for negative, numbers in kinds:
                each = combine(np.clip([x["net"] for x in numbers], -clip, clip), np.clip([x["minus"] for x in numbers], -clip, clip))
                signed[negative] += bool(each.sum() > cut and (each > 0).sum() >= minus_sign.MIN_WIDENED)
            print(f"{name:17} sum > {cut:g}: {signed[True]} of {negatives} negative dials signed, "
                  f"{signed[False]} of {len(kinds) - negatives} positive")


if __name__ == "__main__":
    main(__doc__, collect, report, "per-dial rows")
