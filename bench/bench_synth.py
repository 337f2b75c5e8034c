"""Rendering speed of gauged.synth: 448x448 gauge crops and full 1280x720 scenes per second.

    python bench/bench_synth.py [--workers 2] [--crops 80] [--scenes 30] [--repeats 5]

Each figure is the median throughput over ``--repeats`` runs; a run renders a fresh batch (new
seeds) on ``--workers`` processes (OpenCV limited to one thread each, so processes share the
cores). Targets: >= 40 crops/s and >= 10 scenes/s on 2 cores. Crops include the needle mask.
The load average is printed because other work on the machine lowers the wall-clock figures; the
CPU time per item gives the rate on idle cores.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import header  # noqa: E402

from gauged.synth.dataset import _init_worker, render_item  # noqa: E402


def _crop(seed: int) -> float:
    start = time.process_time()
    render_item(("crop", 1000, seed, 0, 0, 448, False))
    return time.process_time() - start


def _scene(seed: int) -> float:
    start = time.process_time()
    render_item(("scene", 2000, seed, 1280, 720, 0, False))
    return time.process_time() - start


def throughput(pool: ProcessPoolExecutor, fn, count: int, repeats: int) -> tuple[float, list[float], float]:
    """Median wall-clock items/s over the runs, the runs, and the median CPU seconds per item."""
    rates, cpu = [], []
    for r in range(repeats):
        start = time.perf_counter()
        cpu += list(pool.map(fn, range(r * count, (r + 1) * count), chunksize=2))
        rates.append(count / (time.perf_counter() - start))
    return statistics.median(rates), rates, statistics.median(cpu)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--crops", type=int, default=80, help="crops per run")
    parser.add_argument("--scenes", type=int, default=30, help="scenes per run")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    header("gauged.synth rendering throughput")
    load0 = f"{os.getloadavg()[0]:.2f}"
    with ProcessPoolExecutor(args.workers, initializer=_init_worker) as pool:
        list(pool.map(_crop, range(10_000, 10_000 + 2 * args.workers)))  # warm up: imports, fonts, noise pool
        crops, crop_runs, crop_cpu = throughput(pool, _crop, args.crops, args.repeats)
        scenes, scene_runs, scene_cpu = throughput(pool, _scene, args.scenes, args.repeats)
    print(f"workers: {args.workers}; load average before/after: {load0} / {os.getloadavg()[0]:.2f}")
    print(f"448x448 crops per second: {crops:.1f} (target >= 40; runs {', '.join(f'{r:.1f}' for r in crop_runs)})")
    print(f"1280x720 scenes per second: {scenes:.1f} (target >= 10; runs {', '.join(f'{r:.1f}' for r in scene_runs)})")
    # CPU time per item does not depend on what else runs on the machine: it gives the rate the
    # workers would reach with their cores to themselves
    print(f"CPU per crop: {crop_cpu * 1000:.1f} ms -> {args.workers / crop_cpu:.1f} crops/s on {args.workers} idle cores")
    print(f"CPU per scene: {scene_cpu * 1000:.1f} ms -> {args.workers / scene_cpu:.1f} scenes/s on {args.workers} idle cores")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
