"""The reader's own recogniser lines on engine renders, each labelled from the render's truth.

The number net learnt from numbers cut at their true quads (:func:`gauged.training.number_lines.number_lines`).
The reader gives its recogniser something else: the text detector's boxes and the ink boxes at the
crop model's hints, cut from rectified views of the dial, upright or turned. On such lines of the
300 dev renders, PP-OCR reads 83.7% of the numbers captured 5 px tall or more and the first net 82.1%,
so the net lost dials when it replaced PP-OCR everywhere (docs/ocr.md). This module runs the reader on
renders and keeps every line it recognises, with the label the truth gives it:

* the printed number, when the line, mapped back to the frame, holds that number's whole true quad
  (:data:`MIN_COVER` of its area), reads in its direction (within :data:`MAX_TURN_DEG`) and is at most
  :data:`MAX_AREA` times its area;
* "" (nothing), when no printed text of any kind lies near it: a tick, a ghost box;
* no label (the line is left out) otherwise: a part of a number, a turned or upside-down reading, a
  box over two numbers, a maker's name.

The reader is observed, not changed: for the duration of :func:`observing_lines` the OCR module's
``crop_quad`` and ``_rectified`` and the pipeline's ``crop_gauge`` are wrapped to note each line and the
maps of the view it was cut from back to the frame. Lines cut from other images (the polar strip) are
not mapped and not kept. Training code only; the runtime never does this.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from multiprocessing import Pool
from pathlib import Path

import cv2
import numpy as np

MIN_COVER = 0.95  # share of the number's true quad the line must hold
MAX_AREA = 5.0  # line area / true quad area at most (more: a box over neighbours too)
MAX_TURN_DEG = 30.0  # the line's reading direction against the number's
NEAR_TEXT = 3.0  # a line within this many text heights of a printed text is not "nothing"
FIELDS = ("x", "t", "h", "ppocr_text", "ppocr_score", "ppocr_digits", "ppocr_digits_score", "image")


@dataclass
class _Observed:
    """What the wrapped functions note while the reader reads one image."""

    to_frame: np.ndarray | None = None  # the current gauge crop's crop px -> frame px
    views: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)  # data pointer -> (view, crop->view)
    lines: dict[tuple, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)  # line key -> (line, frame quad)
    readings: dict[tuple, object] = field(default_factory=dict)  # line key -> PP-OCR's Recognition

    def view_of(self, image: np.ndarray) -> tuple[int, int, np.ndarray] | None:
        """(row, column) of ``image`` in the rectified view it is a slice of, and that view's matrix."""
        root = image
        while isinstance(root.base, np.ndarray):
            root = root.base
        found = self.views.get(root.__array_interface__["data"][0])
        if found is None or found[0] is not root:
            return None
        view, matrix = found
        offset = image.__array_interface__["data"][0] - view.__array_interface__["data"][0]
        return offset // view.strides[0], (offset % view.strides[0]) // view.strides[1], matrix


@contextmanager
def observing_lines() -> Iterator[_Observed]:
    """Note every line the reader's OCR recognises, with its quad mapped back to the frame."""
    import gauged.reader.ocr.dial_reader as dial_reader
    import gauged.reader.ocr.engine as engine
    import gauged.reader.ocr.text as text
    import gauged.reader.pipeline as pipeline
    import gauged.reader.stages.ocr as ocr

    seen = _Observed()
    crop_gauge, rectified, crop_quad, recognize = pipeline.crop_gauge, ocr._rectified, text.crop_quad, engine.OcrEngine.recognize
    cutters = (ocr, dial_reader)  # the modules that cut lines out of a rectified dial

    def noted_crop(image, box, size, pad=0.08):
        crop = crop_gauge(image, box, size, pad)
        if pad != 0.0 and hasattr(crop, "to_frame"):  # the gauge crop (pad 0 cuts the detail image)
            seen.to_frame, seen.views = crop.to_frame, {}
        return crop

    def noted_view(crop, arc, detail, down):
        view, matrix, circle = rectified(crop, arc, detail, down)
        seen.views[view.__array_interface__["data"][0]] = (view, matrix)
        return view, matrix, circle

    def noted_line(image, quad):
        line = crop_quad(image, quad)
        where = seen.view_of(image)
        if where is not None and seen.to_frame is not None:
            row, col, matrix = where
            in_view = np.asarray(quad, np.float64) + (col, row)
            in_crop = cv2.perspectiveTransform(in_view.reshape(-1, 1, 2), np.linalg.inv(matrix)).reshape(-1, 2)
            seen.lines.setdefault(engine._line_key(line), (line, in_crop * seen.to_frame[0, 0] + seen.to_frame[:2, 2]))
        return line

    def noted_recognize(self, lines):
        out = recognize(self, lines)
        if not self.numbers_again:  # PP-OCR's own readings, not the number net's retry
            for line, reading in zip(lines, out, strict=True):
                seen.readings.setdefault(engine._line_key(line), reading)
        return out

    pipeline.crop_gauge, ocr._rectified, engine.OcrEngine.recognize = noted_crop, noted_view, noted_recognize
    for module in cutters:
        module.crop_quad = noted_line
    try:
        yield seen
    finally:
        pipeline.crop_gauge, ocr._rectified, engine.OcrEngine.recognize = crop_gauge, rectified, recognize
        for module in cutters:
            module.crop_quad = crop_quad


def _height(quad: np.ndarray) -> float:
    return 0.5 * float(np.linalg.norm(quad[3] - quad[0]) + np.linalg.norm(quad[2] - quad[1]))


def _cover(line: np.ndarray, number: np.ndarray) -> tuple[float, float]:
    """(share of ``number``'s area inside ``line``, line area / number area), both convex quads."""
    a = cv2.convexHull(line.astype(np.float32)).reshape(-1, 2)
    b = cv2.convexHull(number.astype(np.float32)).reshape(-1, 2)
    area = cv2.contourArea(b)
    if area <= 0:
        return 0.0, math.inf
    inter, _ = cv2.intersectConvexConvex(a, b)
    return inter / area, cv2.contourArea(a) / area


def label_line(quad: np.ndarray, texts: list[dict]) -> tuple[str | None, str, float]:
    """The label of a line whose quad (4, 2) lies at ``quad`` in the frame (``quad[0] -> quad[1]`` its
    reading direction), among the truth's printed ``texts`` (scale numbers, kind "number", and the
    face's other texts): (label, why, the number's height in frame px or 0). The label is None when
    the line is not to be learnt."""
    quad = np.asarray(quad, float)
    centre, height = quad.mean(axis=0), _height(quad)
    nearest, distance = None, math.inf
    for text in texts:
        tq = np.asarray(text["quad"], float)
        d = float(np.linalg.norm(centre - tq.mean(axis=0)))
        if d < 0.9 * max(_height(tq), height) and d < distance:
            nearest, distance = text, d
    if nearest is None:
        near = any(np.linalg.norm(centre - np.asarray(t["quad"], float).mean(axis=0)) < NEAR_TEXT * _height(np.asarray(t["quad"], float))
                   for t in texts)
        return (None, "near_text", 0.0) if near else ("", "nothing", 0.0)
    if nearest["kind"] != "number":
        return None, "other_text", 0.0
    tq = np.asarray(nearest["quad"], float)
    a, b = quad[1] - quad[0], tq[1] - tq[0]
    turn = math.degrees(math.acos(np.clip(np.dot(a, b) / (np.linalg.norm(a) * np.linalg.norm(b) + 1e-9), -1.0, 1.0)))
    if turn > MAX_TURN_DEG:
        return None, "turned", 0.0
    cover, area = _cover(quad, tq)
    if cover < MIN_COVER or area > MAX_AREA:
        return None, "partial", 0.0
    return nearest["text"], "number", _height(tq)


def _read_folder(job: tuple[str, int, int]) -> dict:
    """Run the reader on images ``start:stop`` of a ``gauged synth images`` folder and label its lines."""
    from gauged.config.model import ReaderConfig
    from gauged.reader.factory import build_reader
    from gauged.reader.ocr.number_net import to_line_input

    folder, start, stop = Path(job[0]), job[1], job[2]
    records = [json.loads(line) for line in (folder / "labels.jsonl").read_text().splitlines()][start:stop]
    reader = build_reader(ReaderConfig(threads=1))
    out: dict = {key: [] for key in FIELDS} | {"why": Counter()}
    for record in records:
        image = cv2.imread(str(folder / record["image"]))
        if image is None:
            raise FileNotFoundError(f"{folder / record['image']}: not an image")
        texts = [t for g in record["gauges"] for s in g["scales"] for t in s["numbers"]]
        texts += [t for g in record["gauges"] for t in g.get("texts", [])]
        with observing_lines() as seen:
            reader.read_image(image)
        for key, (line, quad) in seen.lines.items():
            label, why, height = label_line(quad, texts)
            out["why"][why] += 1
            if label is None:
                continue
            reading = seen.readings.get(key)
            out["x"].append(to_line_input(line))
            out["t"].append(label)
            out["h"].append(height * record.get("render_scale", 1.0))
            out["ppocr_text"].append(reading.text if reading is not None else "")
            out["ppocr_score"].append(reading.score if reading is not None else 0.0)
            out["ppocr_digits"].append(reading.digits if reading is not None else "")
            out["ppocr_digits_score"].append(reading.digits_score if reading is not None else 0.0)
            out["image"].append(record["image"])
    return out


def write_reader_lines(folder: Path, out: Path, workers: int = 2, chunk: int = 100, progress=print) -> Counter:
    """Every labelled line the reader recognises on ``folder``'s renders, to ``out`` (.npz, :data:`FIELDS`:
    ``x`` lines, ``t`` labels, ``h`` number heights as captured, PP-OCR's readings of the line, the
    image's name). Returns how many lines were seen of each kind (:func:`label_line`'s why)."""
    count = sum(1 for _ in (folder / "labels.jsonl").open())
    jobs = [(str(folder), s, min(s + chunk, count)) for s in range(0, count, chunk)]
    parts, why = [], Counter()
    with Pool(workers) as pool:
        for done, part in enumerate(pool.imap(_read_folder, jobs), start=1):
            parts.append(part)
            why.update(part["why"])
            progress(f"read {min(done * chunk, count)}/{count} images, {sum(len(p['t']) for p in parts)} lines kept")
    if not any(p["t"] for p in parts):
        raise ValueError(f"no labelled lines in {folder}")
    arrays = {k: np.concatenate([np.asarray(p[k]) for p in parts if p["t"]]) for k in FIELDS}
    for k in ("h", "ppocr_score", "ppocr_digits_score"):
        arrays[k] = arrays[k].astype(np.float32)
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out, **arrays)
    return why
