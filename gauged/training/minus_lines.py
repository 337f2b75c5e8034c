"""A minus-sign classifier trained on the lines the reader's minus look cuts: data, net and training.

PP-OCR's recogniser often decodes the thin, faint minus of a -X..0 dial as nothing, and the text
detector's box often starts at the first digit. The reader then reads each unsigned number's line
widened left (:func:`gauged.reader.ocr.minus_sign.left_extended`) again. The number net, trained to
read whole numbers, tells a minus there from a tick or a blur poorly (on 800 dev renders it read the
minus of 36 of 51 such numbers, and one before 49 of 1,632 numbers without). This net answers only
that question, trained on exactly those lines as the shipped reader cuts them from renders, labelled
by the render's truth.

    python -m gauged.training.minus_lines data --data DIR [--data DIR ...] --out data/minus-train.npz
    python -m gauged.training.minus_lines train --data data/minus-train.npz --val data/minus-val.npz \\
        --out runs/minus/best.pt
    python -m gauged.training.minus_lines export --weights runs/minus/best.pt --out gauged/models/minus.onnx

A sample is the left :data:`gauged.reader.ocr.minus_net.INPUT_WIDTH` columns of the number net's line
input (:func:`gauged.reader.ocr.number_net.to_line_input`, grey, 32 px tall) of the line widened left
by a margin around the reader's :data:`~gauged.reader.ocr.minus_sign.LEFT_MARGIN`; its label is whether
the render printed that number with a minus. Numbers whose line faces the ring's ticks are kept (the
hardest negatives), marked, so a report can leave them out.
"""

from __future__ import annotations

import argparse
import json
import logging
import time
from multiprocessing import Pool
from pathlib import Path

import cv2
import numpy as np

from gauged.reader.ocr import minus_sign
from gauged.reader.ocr.minus_net import INPUT_WIDTH, minus_input
from gauged.reader.ocr.text import crop_quad

log = logging.getLogger(__name__)

TRUTH_MARGINS = (0.05, 0.6)  # of the height: how far left of a true quad its cuts start
MARGINS = (0.3, 0.4, 0.5)  # of the box's height: each number's line is cut at each (the reader cuts at 0.4)


def _truth_texts(label: dict) -> set[str]:
    scale = next(s for s in label["gauges"][0]["scales"] if s["role"] == "primary")
    return {x["text"].replace("\u2212", "-") for x in scale["numbers"]}


_reader = None


def _read_one(job: tuple[str, str]) -> list[dict]:
    """The minus look's lines of one render: every unsigned number other than 0 whose sign the
    render's primary scale tells (printed either only with or only without a minus)."""
    global _reader
    folder, line = job
    label = json.loads(line)
    if _reader is None:
        from gauged.config.model import ReaderConfig
        from gauged.reader.factory import build_reader

        # The minus net off: the number net's look (number_net_reads) runs, on the same widened lines
        # the minus net is given, and no minus net is needed to make its own first data.
        _reader = build_reader(ReaderConfig(threads=1, ocr_minus_net=False))
    texts_true, rows = _truth_texts(label), []
    look = minus_sign.number_net_reads

    def recorded(texts, image, net, circle):
        for k in minus_sign.unsigned_numbers(texts):
            box, text = texts[k], texts[k].text.strip()
            plain, signed = text in texts_true, "-" + text in texts_true
            if plain == signed:
                continue
            cuts = [minus_input(crop_quad(image, minus_sign.left_extended(box.quad, m))) for m in MARGINS]
            rows.append({"x": np.stack(cuts), "minus": signed, "faces": bool(minus_sign.faces_ticks(box.quad, circle)),
                         "image": label["image"]})
        return look(texts, image, net, circle)

    minus_sign.number_net_reads = recorded
    try:
        _reader.read_image(cv2.imread(str(Path(folder) / label["image"])))
    finally:
        minus_sign.number_net_reads = look
    return rows


def write_data(folders: list[Path], out: Path, workers: int = 2) -> dict[str, int]:
    """Read every render of ``folders`` (``gauged synth images`` output) and save the minus look's lines."""
    jobs = [(str(f), line) for f in folders for line in (f / "labels.jsonl").read_text().splitlines()]
    x, minus, faces, images = [], [], [], []
    t0 = time.time()
    with Pool(workers) as pool:
        for i, rows in enumerate(pool.imap(_read_one, jobs, chunksize=4), 1):
            for r in rows:
                x.append(r["x"]), minus.append(r["minus"]), faces.append(r["faces"]), images.append(r["image"])
            if i % 200 == 0 or i == len(jobs):
                log.info("read %d/%d renders, %d lines (%d with a minus), %.0f s", i, len(jobs), len(x), sum(minus),
                         time.time() - t0)
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out, x=np.stack(x), minus=np.asarray(minus), faces=np.asarray(faces), image=np.asarray(images))
    return {"lines": len(x), "minus": int(sum(minus)), "faces": int(sum(faces))}


def _truth_cuts(job: tuple[str, str, int]) -> list[dict]:
    """Every primary-scale number of one render cut at its true quad, its left edge moved out by
    three random margins of :data:`TRUTH_MARGINS` x its height: the minus, when printed, stands inside."""
    folder, line, seed = job
    label = json.loads(line)
    image = cv2.imread(str(Path(folder) / label["image"]))
    rng = np.random.default_rng(seed)
    rows = []
    for gauge in label["gauges"]:
        for scale in gauge["scales"]:
            for number in scale["numbers"]:
                text = number["text"].replace("\u2212", "-")
                if not minus_sign.UNSIGNED_NUMBER.fullmatch(text.lstrip("-")) or float(text.lstrip("-").replace(",", ".")) == 0:
                    continue
                quad = np.asarray(number["quad"], np.float32)
                centre = quad.mean(axis=0)
                grown = centre + (quad - centre) * np.float32([1.0, rng.uniform(1.2, 1.6)])  # the detector's box is taller than the ink
                cuts = [minus_input(crop_quad(image, minus_sign.left_extended(grown, float(m))))
                        for m in rng.uniform(*TRUTH_MARGINS, len(MARGINS))]
                rows.append({"x": np.stack(cuts), "minus": text.startswith("-"), "faces": False, "image": label["image"]})
    return rows


def write_truth_data(folders: list[Path], out: Path, workers: int = 2) -> dict[str, int]:
    """The numbers of ``folders``' renders cut at their true quads (:func:`_truth_cuts`): every printed
    minus, not only those the reader's boxes leave out, so the net sees many more of them."""
    jobs = [(str(f), line, k) for f in folders for k, line in enumerate((f / "labels.jsonl").read_text().splitlines())]
    x, minus, images = [], [], []
    with Pool(workers) as pool:
        for rows in pool.imap(_truth_cuts, jobs, chunksize=16):
            for r in rows:
                x.append(r["x"]), minus.append(r["minus"]), images.append(r["image"])
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out, x=np.stack(x), minus=np.asarray(minus), faces=np.zeros(len(x), bool), image=np.asarray(images))
    return {"lines": len(x), "minus": int(sum(minus))}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser("data", help="read renders with the shipped reader and save the minus look's lines")
    d.add_argument("--data", type=Path, action="append", required=True, help="a `gauged synth images` folder (repeatable)")
    d.add_argument("--out", type=Path, required=True)
    d.add_argument("--workers", type=int, default=2)
    d.add_argument("--truth", action="store_true", help="cut every number at its true quad instead of reading the renders")
    t = sub.add_parser("train", help="train the classifier, keep the checkpoint best on --val")
    t.add_argument("--data", type=Path, action="append", required=True)
    t.add_argument("--val", type=Path, required=True)
    t.add_argument("--out", type=Path, required=True)
    t.add_argument("--epochs", type=int, default=12)
    t.add_argument("--threads", type=int, default=2)
    e = sub.add_parser("export", help="export a checkpoint to ONNX")
    e.add_argument("--weights", type=Path, required=True)
    e.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)-7s %(name)s: %(message)s", datefmt="%H:%M:%S")
    if args.cmd == "data":
        write = write_truth_data if args.truth else write_data
        print(json.dumps(write(args.data, args.out, args.workers)))
    elif args.cmd == "train":
        from gauged.training.minus_train import train

        print(json.dumps(train(args.data, args.val, args.out, args.epochs, args.threads)))
    else:
        from gauged.training.minus_train import export_onnx

        export_onnx(args.weights, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
