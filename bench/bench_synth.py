"""Rendering speed: 448x448 gauge crops and full 1280x720 scenes per second on all cores.

    python bench/bench_synth.py [--seconds 10]

Each figure is the median throughput of 5 repeated runs, each rendering a batch with one worker
process per core (the renderer is single-threaded numpy/cv2).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from multiprocessing import Pool
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import header  # noqa: E402

from gauged.training.dial_renderer import render_crop, render_scene  # noqa: E402


def _crop(seed: int) -> int:
    return render_crop(seed, 448)[0].shape[0]


def _scene(seed: int) -> int:
    return render_scene(seed, 1280, 720)[0].shape[0]


def throughput(pool: Pool, fn, count: int, repeats: int = 5) -> float:
    rates = []
    for r in range(repeats):
        start = time.perf_counter()
        pool.map(fn, range(r * count, (r + 1) * count), chunksize=4)
        rates.append(count / (time.perf_counter() - start))
    return statistics.median(rates)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--crops", type=int, default=80)
    parser.add_argument("--scenes", type=int, default=24)
    args = parser.parse_args()
    header("gauged synthetic rendering throughput")
    with Pool(os.cpu_count()) as pool:
        crops = throughput(pool, _crop, args.crops)
        scenes = throughput(pool, _scene, args.scenes)
    print(f"448x448 crops per second: {crops:.1f} (target >= 40)")
    print(f"1280x720 scenes per second: {scenes:.1f} (target >= 10)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
