"""Where a cold read's OCR time goes, image by image: which of the reader's OCR steps and looks ran on
each of bench_read.py's crops and what each cost (cProfile cumulative time, so nested steps overlap).

    .venv/bin/python bench/investigations/cold_read_profile.py [--images 30] [--top 7]

One line per image, slowest last: wall ms (with cProfile's overhead, about 10%), the look that read
it, its outcome, and the costliest steps. The steps are the functions named in STEPS; the totals
over all images follow. Read with docs/performance.md ("Where the time goes").
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench_read import images  # noqa: E402

from gauged.config.model import ReaderConfig  # noqa: E402
from gauged.reader.factory import build_reader  # noqa: E402
from gauged.types import StageFailure  # noqa: E402

STEPS = ("read_dial", "read_quick", "read_at_hints", "read_polar", "read_units_closer", "_texts_in_square",
         "_number_net_retry", "_hint_look", "read_face_texts", "reread_markers", "_about_pivot", "_reorient",
         "ring_texts", "detect", "recognize", "run_recogniser", "_run_detector")


def step_seconds(profile: cProfile.Profile) -> dict[str, float]:
    out: dict[str, float] = {}
    for (_, _, name), (_, _, _, cumulative, _) in pstats.Stats(profile).stats.items():
        if name in STEPS:
            out[name] = out.get(name, 0.0) + cumulative
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--images", type=int, default=30)
    parser.add_argument("--top", type=int, default=7, help="steps shown per image")
    args = parser.parse_args()
    reader = build_reader(ReaderConfig(threads=2))
    batch = images(args.images, False)
    reader.read_image(batch[0])  # warm the sessions
    rows, totals = [], {}
    for index, image in enumerate(batch):
        profile = cProfile.Profile()
        started = time.perf_counter()
        profile.enable()
        result = reader.read_image(image)
        profile.disable()
        wall = time.perf_counter() - started
        steps = step_seconds(profile)
        for name, seconds in steps.items():
            totals[name] = totals.get(name, 0.0) + seconds
        if isinstance(result, StageFailure):
            look, outcome = "-", f"{result.stage}/{result.reason}"
        else:
            read = result[0]
            look = read.look or "-"
            outcome = "read" if read.failure is None else f"{read.failure.stage}/{read.failure.reason}"
        rows.append((wall, index, look, outcome, steps))
    for wall, index, look, outcome, steps in sorted(rows):
        top = sorted(steps.items(), key=lambda kv: -kv[1])[: args.top]
        print(f"{1000 * wall:6.0f} ms  image {index:2d}  {look:<13} {outcome:<32} "
              + ", ".join(f"{name} {1000 * s:.0f}" for name, s in top))
    print("total per step over all images (s): "
          + ", ".join(f"{name} {s:.2f}" for name, s in sorted(totals.items(), key=lambda kv: -kv[1])))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
