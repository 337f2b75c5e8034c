"""Refusals of a synthetic set split by what the renders show: legible numbers, a whole face, both scale ends.

    gauged eval readings --data data/held1000 --json > held1000.json
    python bench/investigations/refusals_by_visibility.py --data data/held1000 --result held1000.json

``--data`` is a set made by `gauged synth images` (its ``labels.jsonl`` holds the engine's truth);
``--result`` is `gauged eval readings --json` on it. Each image falls in one group by:

- the primary scale's numbers as the camera captured them (``captured_number_px``, under 5 px: no
  reader can make out their digits, docs/accuracy.md);
- whether the whole face is visible (``visible_fraction`` 1) or something lies over part of it
  (a pipe, the frame edge, another dial);
- whether both scale ends are visible (``start_visible`` and ``end_visible``).

It prints each group's size and refusal rate, and the refusal reasons of the legible, whole-face,
both-ends group: the renders a reader has every chance to read.
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


def group_of(record: dict, truth: dict) -> tuple[str, str, str]:
    gauge = truth["gauges"][0]
    primary = next((s for s in gauge["scales"] if s.get("role") == "primary"), gauge["scales"][0])
    return ("legible" if record["captured_number_px"] >= LEGIBLE_PX else "illegible",
            "face whole" if gauge.get("visible_fraction", 1.0) >= 0.999 else "face partly hidden",
            "both ends seen" if primary.get("start_visible", True) and primary.get("end_visible", True) else "an end hidden")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="a gauged synth images folder (labels.jsonl)")
    parser.add_argument("--result", type=Path, required=True, help="gauged eval readings --json on it")
    args = parser.parse_args()
    if not (args.data / "labels.jsonl").is_file():
        parser.error(f"{args.data} has no labels.jsonl: make the set with gauged synth images")
    header("refusals by what the renders show")
    truths = {}
    with (args.data / "labels.jsonl").open() as lines:
        for line in lines:
            record = json.loads(line)
            truths[record["image"]] = record
    records = json.loads(args.result.read_text())["images"]
    missing = [r["image"] for r in records if r["image"] not in truths]
    if missing:
        parser.error(f"{len(missing)} images of {args.result} are not in {args.data} (first: {missing[0]})")
    groups: dict[tuple[str, str, str], list[dict]] = {}
    for record in records:
        groups.setdefault(group_of(record, truths[record["image"]]), []).append(record)
    print(f"{'numbers':10} {'face':19} {'scale ends':15} {'images':>6} {'refused':>8}")
    for key in sorted(groups):
        members = groups[key]
        refused = sum(r["failure"] is not None for r in members)
        print(f"{key[0]:10} {key[1]:19} {key[2]:15} {len(members):6d} {refused / len(members):8.1%}")
    clean = groups.get(("legible", "face whole", "both ends seen"), [])
    reasons = Counter(f"{r['failure']['stage']}/{r['failure']['reason']}" for r in clean if r["failure"])
    print(f"legible, face whole, both ends seen: {sum(reasons.values())} of {len(clean)} refused: "
          + ", ".join(f"{k} {v}" for k, v in reasons.most_common()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
