"""The figures of one or more ``gauged eval readings --json`` outputs taken as one set: refusals over
all images and over the renders whose printed numbers are captured at >= 5 px (the rest are blurs
without digits), the median and mean error, and how many readings are more than 5% and 10% off.

    python bench/investigations/legible_failures.py held-ccw.json [more.json ...] [--merged OUT.json]

Several inputs (a set read in parts on several cores) are merged; ``--merged`` writes their images
as one JSON that ``python -m gauged.training.confidence check --evals`` reads.
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path

LEGIBLE_PX = 5.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("evals", type=Path, nargs="+")
    parser.add_argument("--merged", type=Path, help="write the merged images here")
    args = parser.parse_args()
    images = [image for path in args.evals for image in json.loads(path.read_text())["images"]]
    if args.merged:
        args.merged.write_text(json.dumps({"images": images}))
    read = [i for i in images if i["value"] is not None]
    errors = [i["relative_error"] for i in read]
    small = [i for i in images if i.get("captured_number_px") is not None and i["captured_number_px"] < LEGIBLE_PX]
    legible = [i for i in images if i not in small]
    refused = len(images) - len(read)
    legible_refused = sum(i["value"] is None for i in legible)
    print(f"{len(images)} images, refused {refused} ({refused / len(images):.1%})")
    print(f"numbers >= {LEGIBLE_PX:g} px: {len(legible)} images, refused {legible_refused} "
          f"({legible_refused / max(1, len(legible)):.1%}); {len(small)} excluded")
    if errors:
        print(f"median {statistics.median(errors):.3%}, mean {statistics.mean(errors):.3%}, max {max(errors):.1%}; "
              f"{sum(e > 0.05 for e in errors)} readings > 5% off, {sum(e > 0.10 for e in errors)} > 10%")


if __name__ == "__main__":
    main()
