"""Cold read of one gauge: detect + every stage (crop model, ellipse, needle, OCR, scale, reading).

    python bench/bench_read.py [--images 30] [--repeats 3] [--threads 2] [--scene]

Renders ``--images`` synthetic images (seed 7,000,000+, never trained on) with ``gauged.synth``:
by default 448 x 448 crops of one gauge, each read with :meth:`GaugeReader.read_image` (the detector
runs when it is shipped, else the image is read as one gauge), or with ``--scene`` 1280 x 720 frames
holding one gauge. Models are loaded once and warmed up first; each image is read ``--repeats``
times and its median kept; the figure is the median over images, with the slowest quartile and the
per-stage medians. Refused images count too (a refusal costs time as well). CPU seconds per read
are printed beside wall time because other work on a shared machine slows wall-clock figures.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import header  # noqa: E402

import numpy as np  # noqa: E402

from gauged.config.model import ReaderConfig  # noqa: E402
from gauged.reader.factory import build_reader  # noqa: E402
from gauged.synth.crop import render_crop  # noqa: E402
from gauged.synth.scene import render_scene  # noqa: E402
from gauged.types import StageFailure  # noqa: E402

FIRST_SEED = 7_000_000


def images(count: int, scene: bool) -> list[np.ndarray]:
    if scene:
        return [render_scene(FIRST_SEED + i, 1280, 720, n_gauges=1).image for i in range(count)]
    return [render_crop(FIRST_SEED + i, 448).image for i in range(count)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--images", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--scene", action="store_true", help="1280x720 frames with one gauge instead of crops")
    parser.add_argument("--models", type=Path, help="folder with crop.onnx/detector.onnx instead of the shipped ones")
    parser.add_argument("--ocr-float", action="store_true",
                        help="run the OCR wheel's float text detector instead of the shipped int8 copy")
    args = parser.parse_args()
    header("cold read of one gauge (detect + all stages), models loaded")
    reader = build_reader(ReaderConfig(threads=args.threads, models_dir=args.models, ocr_int8_detector=not args.ocr_float))
    print(f"# detector: {'yes' if reader.detector else 'no (image read as one gauge)'}, "
          f"OCR: {reader.ocr.engine.model_files[0].name if reader.ocr else 'no'}, threads {args.threads}, load {os.getloadavg()[0]:.2f}")
    batch = images(args.images, args.scene)
    for image in batch[:3]:  # warm-up: first onnxruntime runs allocate
        reader.read_image(image)
    walls, cpus, outcomes, stages = [], [], {"read": 0, "refused": 0}, {}
    for image in batch:
        runs, cpu_runs = [], []
        for _ in range(args.repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            result = reader.read_image(image)
            runs.append(time.perf_counter() - t0)
            cpu_runs.append(time.process_time() - c0)
        walls.append(float(np.median(runs)))
        cpus.append(float(np.median(cpu_runs)))
        gauges = [] if isinstance(result, StageFailure) else result
        ok = any(g.failure is None for g in gauges)
        outcomes["read" if ok else "refused"] += 1
        for g in gauges[:1]:
            for stage, seconds in g.seconds.items():
                stages.setdefault(stage, []).append(seconds)
    w = 1000 * np.asarray(walls)
    print(f"images {len(batch)} ({outcomes['read']} read, {outcomes['refused']} refused)")
    print(f"cold read wall ms: median {np.median(w):.0f}, p75 {np.percentile(w, 75):.0f}, max {w.max():.0f}; "
          f"CPU s per read median {np.median(cpus):.3f}")
    print("per stage (median ms over images that reached it): "
          + ", ".join(f"{k} {1000 * np.median(v):.1f}" for k, v in stages.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
