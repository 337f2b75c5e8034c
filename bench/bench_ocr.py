"""Speed and accuracy of the OCR stage.

    python bench/bench_ocr.py [--threads 1 2] [--runs 15] [--models auto rapidocr rapidocr_onnxruntime]
    python bench/bench_ocr.py --accuracy [--models ...]     # real photos and synthetic dials

Accuracy (``--accuracy``): ``read_markers`` on (a) the 21 real photos of
``../shared/datasets/gauge-readings-dev`` (skipped when absent), each given a by-eye scale circle with
the gap at the bottom in place of the fitted ellipse, against hand labels of the printed scale numbers
(:data:`REAL`; 161 numbers on the scale the label's min/max name; numbers of a second scale are
neither right nor wrong), and (b) 40 dials of the training renderer (seeds 100-139, 295 numbers, a
quarter printed radially) with the true number centres as hints, and without hints. A number is right
when its value is printed on the dial (and, on renders, at that place).

On a rendered 448 x 448 dial crop (gauged.training.dial_renderer, seed 107: seven numbers and a
unit): ``det+rec 448`` is one detector pass with the longer side at 448 px plus recognition of every
detected box in one batch; ``rec/patch`` is recognition of one number patch (batch of one) and
``rec/patch in 8`` the per-patch time of a batch of eight; ``read_markers`` is the whole pipeline
stage (rectify to 512 px, ring detection, re-reads, hints, polar fallback, parsing, progression
filter) without and with hint points. Figures are medians of ``--runs`` calls after warm-up, per
onnxruntime intra-op thread count; the load average is printed because other work on the machine
slows wall-clock figures, and CPU seconds per call show the cost on idle cores.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cv2  # noqa: E402
import numpy as np  # noqa: E402
from common import header, median_s  # noqa: E402

from gauged.geometry.angles import wrap_angle  # noqa: E402
from gauged.geometry.dial_frame import dial_angle  # noqa: E402
from gauged.geometry.ellipse_fit import fit_ellipse  # noqa: E402
from gauged.reader.ocr.engine import MODEL_SETS, OcrUnavailable, find_model_files  # noqa: E402
from gauged.reader.ocr.text import crop_quad  # noqa: E402
from gauged.reader.stages.ellipse import ScaleArc  # noqa: E402
from gauged.reader.stages.ocr import ScaleTextReader  # noqa: E402
from gauged.training.dial_renderer import render_crop  # noqa: E402
from gauged.types import Ellipse  # noqa: E402


def cpu_ms(fn, runs: int) -> float:
    start = time.process_time()
    for _ in range(runs):
        fn()
    return (time.process_time() - start) / runs * 1000


def _r(a: float, b: float, step: float) -> list[float]:
    return [round(a + i * step, 6) for i in range(int(round((b - a) / step)) + 1)]


REAL_DIR = Path(__file__).resolve().parents[2] / "shared" / "datasets" / "gauge-readings-dev" / "images"
# Per photo, in file-name order: (main-scale numbers, second-scale numbers, scale circle (cx, cy, r) in
# units of the photo resized to 480 x 480), labelled by eye.
REAL = [
    (_r(140, 280, 20), [], (205, 240, 135)), ([-0.1, 0, 0.2, 0.4, 0.6, 0.8, 0.9], [20], (255, 235, 175)),
    (_r(0, 100, 20), [], (230, 235, 200)), (_r(8, 18, 2), [], (240, 220, 185)),
    (_r(-60, 140, 20), [], (215, 245, 190)), (_r(30, 300, 30), _r(0, 21, 3), (295, 165, 140)),
    (_r(10, 100, 10), [], (225, 230, 115)), (_r(0, 300, 50), _r(0, 20, 5), (235, 235, 200)),
    ([0, 5, 10, 15, 16], [], (240, 205, 170)), (_r(-40, 140, 20), _r(-40, 60, 10), (235, 235, 215)),
    (_r(0, 600, 200), [], (310, 340, 210)), (_r(0, 60, 10), _r(10, 110, 10), (235, 235, 190)),
    (_r(0, 100, 10), [], (210, 230, 115)), (_r(0, 50, 10), [], (240, 245, 190)), (_r(0, 9, 1), [], (222, 180, 110)),
    (_r(20, 160, 20), [], (240, 265, 170)), (_r(0, 10, 1), [], (240, 240, 165)), (_r(0, 60, 10), [], (235, 240, 215)),
    (_r(0, 6, 1), [], (240, 240, 215)), ([-2, -0.5, 1, 2.5, 4], [], (225, 250, 200)),
    ([0, 2.5, 5, 7.5, 10], [], (250, 250, 215)),
]


def score_values(values, main, other) -> tuple[int, int]:
    """(right, wrong): each value matches one unused main (or second-scale) number, else is wrong."""
    main, other, right, wrong = list(main), list(other), 0, 0
    for v in values:
        for pool in (main, other):
            hit = next((x for x in pool if abs(x - v) < 1e-6), None)
            if hit is not None:
                pool.remove(hit)
                right += pool is main
                break
        else:
            wrong += 1
    return right, wrong


def accuracy_real(reader: ScaleTextReader) -> str:
    files = sorted(REAL_DIR.glob("*")) if REAL_DIR.is_dir() else []
    if len(files) != len(REAL):
        return f"real photos: skipped ({REAL_DIR} absent or changed)"
    right = wrong = dials = 0
    times = []
    for path, (main, other, (cx, cy, r)) in zip(files, REAL, strict=True):
        image = cv2.imread(str(path))
        h, w = image.shape[:2]
        e = Ellipse(cx * w / 480, cy * h / 480, r * (w + h) / 960, r * (w + h) / 960, 0.0)
        arc = ScaleArc(e, e.center, 0.75 * np.pi, 0.25 * np.pi, 0.5 * np.pi, np.zeros((0, 2)), 0.0, False)
        start = time.perf_counter()
        read = reader.read_markers(image, arc, np.zeros((0, 2)))
        times.append(time.perf_counter() - start)
        values = [m.value for m in read[0]] if isinstance(read, tuple) else []
        ok, bad = score_values(values, main, other)
        right, wrong, dials = right + ok, wrong + bad, dials + (ok >= 3)
    total = sum(len(m) for m, _, _ in REAL)
    return (f"real photos: {right}/{total} right, {wrong} wrong, {dials}/{len(REAL)} photos with >= 3 right; "
            f"median {np.median(times) * 1e3:.0f} ms")


def accuracy_synth(reader: ScaleTextReader, hints: bool) -> str:
    right = wrong = dials = total = 0
    for seed in range(100, 140):
        image, labels = render_crop(seed, 448)
        arc = _arc(labels)
        centres = labels.points["numbers"]
        truth = np.linspace(labels.min_value, labels.max_value, len(labels.points["major"]))
        total += len(truth)
        read = reader.read_markers(image, arc, centres if hints else centres[:0])
        if not isinstance(read, tuple):
            continue
        used: set[int] = set()
        ok = 0
        for m in read[0]:
            c = np.array([(m.box[0] + m.box[2]) / 2, (m.box[1] + m.box[3]) / 2])
            k = int(np.argmin(np.linalg.norm(centres - c, axis=1)))
            if k not in used and np.linalg.norm(centres[k] - c) < 0.15 * arc.ellipse.a and abs(truth[k] - m.value) < 1e-6:
                used.add(k)
                ok += 1
            else:
                wrong += 1
        right, dials = right + ok, dials + (ok >= 3)
    return (f"renders {'with' if hints else 'without'} hints: {right}/{total} right ({100 * right / total:.0f}%), "
            f"{wrong} wrong, {dials}/40 dials with >= 3 right")


def _arc(labels) -> ScaleArc:
    majors = labels.points["major"]
    ellipse = fit_ellipse(majors, shape="auto")
    start = float(dial_angle(ellipse, labels.points["start"])[0])
    end = float(dial_angle(ellipse, labels.points["end"])[0])
    return ScaleArc(ellipse, ellipse.center, start, end, wrap_angle(start, end), majors, 0.0, False)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--runs", type=int, default=15)
    parser.add_argument("--models", nargs="+", default=["auto"], choices=["auto", *MODEL_SETS])
    parser.add_argument("--accuracy", action="store_true", help="measure accuracy instead of speed")
    args = parser.parse_args()
    if args.accuracy:
        header("OCR stage accuracy")
        for models in args.models:
            reader = ScaleTextReader(threads=args.threads[0], models=models)
            for line in (accuracy_real(reader), accuracy_synth(reader, True), accuracy_synth(reader, False)):
                print(f"{models}: {line}")
        return
    header("OCR stage speed")
    print(f"# load average at start: {os.getloadavg()[0]:.2f}")
    image, labels = render_crop(107, 448)
    arc = _arc(labels)
    hints = labels.points["numbers"]
    print("| models | threads | det 448 ms | det+rec 448 ms (boxes) | rec/patch ms | rec/patch in 8 ms "
          "| read_markers ms | with hints ms | CPU ms det+rec |")
    print("|---|---|---|---|---|---|---|---|---|")
    for models in args.models:
        try:
            det_path, _ = find_model_files(models)
        except OcrUnavailable as exc:
            print(f"| {models} | not installed: {exc} |")
            continue
        for threads in args.threads:
            reader = ScaleTextReader(threads=threads, models=models)
            engine = reader.engine
            quads = [q.quad for q in engine.detect(image, max_side=448)]
            patches = [crop_quad(image, q) for q in quads] or [image[:48, :96]]
            eight = (patches * 8)[:8]

            def det_rec() -> None:
                found = engine.detect(image, max_side=448)
                engine.run_recogniser([crop_quad(image, q.quad) for q in found])

            det = median_s(lambda: engine.detect(image, max_side=448), args.runs)
            full = median_s(det_rec, args.runs)
            rec1 = median_s(lambda: engine.run_recogniser(patches[:1]), args.runs * 3)
            rec8 = median_s(lambda: engine.run_recogniser(eight), args.runs) / 8
            stage = median_s(lambda: reader.read_markers(image, arc, hints[:0]), max(3, args.runs // 3), warmup=1)
            hinted = median_s(lambda: reader.read_markers(image, arc, hints), max(3, args.runs // 3), warmup=1)
            cpu = cpu_ms(det_rec, max(3, args.runs // 3))
            name = f"{models} ({det_path.parent.parent.name})" if models == "auto" else models
            print(f"| {name} | {threads} | {det * 1e3:.0f} | {full * 1e3:.0f} ({len(quads)}) | {rec1 * 1e3:.1f} "
                  f"| {rec8 * 1e3:.1f} | {stage * 1e3:.0f} | {hinted * 1e3:.0f} | {cpu:.0f} |")
    print(f"# load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
