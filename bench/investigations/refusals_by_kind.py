"""Refusals of synthetic sets by the kind of scale the renders print: positive (0..X), negative
(-X..0) or mixed (-X..Y), with whole or decimal numbers; and what one set's refusal rate would be
at another set's rate per kind (is a gap between two sets the reader's weakness with a direction,
or that the sets print other kinds of scale in other shares?).

    gauged eval readings --data data/held1000 --json > held-cw.json
    gauged eval readings --data data/held1000-ccw --json > held-ccw.json
    python bench/investigations/refusals_by_kind.py data/held1000 held-cw.json data/held1000-ccw held-ccw.json

Arguments come in pairs: a set made by `gauged synth images` (its ``labels.jsonl``) and
`gauged eval readings --json` on it. Only renders whose numbers are captured at >= 5 px count, as in
issue 35's failure figure. With two or more sets, each later set's refusals are also given as
expected at the first set's rate per kind.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
from common import header  # noqa: E402

LEGIBLE_PX = 5.0


def scale_kind(scale: dict) -> str:
    sign = "negative" if scale["max"] <= 0 else "mixed" if scale["min"] < 0 else "positive"
    decimal = any("." in n["text"] or "," in n["text"] for n in scale["numbers"])
    return f"{sign}, {'decimal' if decimal else 'whole'}"


def tally(data: Path, result: Path) -> tuple[Counter, Counter]:
    kinds = {}
    for line in (data / "labels.jsonl").read_text().splitlines():
        if line.strip():
            label = json.loads(line)
            kinds[label["image"]] = scale_kind(label["gauges"][0]["scales"][0])
    rows = json.loads(result.read_text())["images"]
    total, refused = Counter(), Counter()
    for row in rows:
        if (row.get("captured_number_px") or 0.0) < LEGIBLE_PX or row["image"] not in kinds:
            continue
        kind = kinds[row["image"]]
        total[kind] += 1
        refused[kind] += row.get("value") is None
    return total, refused


def _expected(total: Counter, base_total: Counter, base_refused: Counter, group) -> float:
    """Refusals of a set of ``total`` renders per kind at the base set's rate per ``group`` of kinds
    (a coarser grouping when the base set holds few renders of some kind)."""
    gt, gr = Counter(), Counter()
    for kind in base_total:
        gt[group(kind)] += base_total[kind]
        gr[group(kind)] += base_refused[kind]
    return sum(n * gr[group(k)] / gt[group(k)] for k, n in total.items() if gt[group(k)])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("pairs", nargs="+", type=Path, help="DATA_DIR RESULT.json [DATA_DIR RESULT.json ...]")
    args = parser.parse_args()
    if len(args.pairs) % 2:
        parser.error("give each set as a pair: its folder and its eval JSON")
    header("refusals_by_kind.py " + " ".join(map(str, args.pairs)))
    sets = [(args.pairs[i], *tally(args.pairs[i], args.pairs[i + 1])) for i in range(0, len(args.pairs), 2)]
    _, base_total, base_refused = sets[0]
    for data, total, refused in sets:
        n, r = sum(total.values()), sum(refused.values())
        print(f"\n{data}: {r} of {n} legible renders refused ({r / max(n, 1):.1%})")
        for kind in sorted(total):
            print(f"  {kind:20s} {refused[kind]:4d} of {total[kind]:4d} ({refused[kind] / total[kind]:.0%})")
        if data != sets[0][0]:
            for name, group in (("kind", lambda k: k), ("sign alone", lambda k: k.split(",")[0])):
                expected = _expected(total, base_total, base_refused, group)
                print(f"  at {sets[0][0]}'s rate per {name}: {expected:.0f} refused ({expected / max(n, 1):.1%})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
