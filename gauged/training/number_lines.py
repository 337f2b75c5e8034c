"""A recogniser of scale numbers trained on the engine's renders: data, net and training.

The reader reads numbers with PP-OCR's recogniser (:mod:`gauged.reader.ocr.engine`), and reads a
dial again with this net (exported to ``gauged/models/numbers.onnx``, run by
:mod:`gauged.reader.ocr.number_net`) only when its first numbers gave no scale.
Cut at their true quads, PP-OCR reads 71.2% of the held-out numbers captured 5-10 px tall and 87.8%
of those 10-14 px; this net (its first, width-48 version), trained on number lines of other seeds
cut the same way, reads 85.9% and 93.5% (docs/ocr.md, "A recogniser of our own").

    python -m gauged.training.number_lines data --seed 2000000 --count 6000 --out data/num-train.npz
    python -m gauged.training.number_lines data --seed 2100000 --count 300 --out data/num-val.npz
    python -m gauged.training.number_lines train --data data/num-train.npz --val data/num-val.npz \\
        --epochs 10 --width 24 --out runs/numbers/best.pt   # the shipped net (defaults); 3-4 min an epoch
    python -m gauged.training.number_lines compare --data data/held1000 --weights runs/numbers/best.pt
    python -m gauged.training.number_lines export --weights runs/numbers/best.pt --out gauged/models/numbers.onnx

A line is the number's true quad widened by half its height each side and to 1.5 times its height
(jittered in training), warped upright, grey, resized to 32 px tall and padded to 128 px. The net is
a small CNN (to 2 x 32 cells) and a bidirectional GRU, read by CTC over ``0-9 . , -``.
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
import torch
from torch import nn
from torch.nn import functional as F

from gauged.reader.ocr.number_net import CHARS, LINE_HEIGHT, LINE_WIDTH, to_line_input
from gauged.reader.ocr.number_net import greedy_decode as decode_logits
from gauged.reader.ocr.text import crop_quad
from gauged.synth.crop import render_crop

log = logging.getLogger(__name__)

HEIGHT_BINS = ((0, 5), (5, 10), (10, 14), (14, 18), (18, 1e9))  # px as captured (docs/accuracy.md)


def number_lines(image: np.ndarray, gauge: dict, render_scale: float,
                 rng: np.random.Generator | None = None) -> list[tuple[np.ndarray, str, float]]:
    """(line image BGR, printed text, height as captured in px) of every scale number of a
    :mod:`gauged.synth.truth` gauge record; ``rng`` jitters each line's margin and centre."""
    out = []
    for scale in gauge["scales"]:
        for number in scale["numbers"]:
            quad = np.asarray(number["quad"], float)
            centre = quad.mean(axis=0)
            height = float(np.linalg.norm(quad[0] - quad[3]))
            width = max(1.0, float(np.linalg.norm(quad[0] - quad[1])))
            grow = np.array([1.0 + 0.5 * height / width, 1.5])
            if rng is not None:
                grow *= (rng.uniform(0.9, 1.15), rng.uniform(0.85, 1.2))
                centre = centre + rng.normal(0, 0.08 * height, 2)
            # Grown about its centre in image x and y, then moved.
            line = crop_quad(image, centre + (quad - quad.mean(axis=0)) * grow)
            out.append((line, number["text"], height * render_scale))
    return out


def encode(text: str) -> list[int]:
    """CTC labels (1-based; 0 is the blank) of the characters of ``text`` the net knows."""
    return [CHARS.index(c) + 1 for c in text.replace("\u2212", "-") if c in CHARS]


def _render_lines(seed: int) -> list[tuple[np.ndarray, str, float]]:
    sample = render_crop(seed, 448, masks=False)
    rng = np.random.default_rng(seed)
    return [(to_line_input(line), text, h)
            for line, text, h in number_lines(sample.image, sample.truth, 1.0 / sample.output_scale, rng)]


def write_lines(first_seed: int, count: int, out: Path, workers: int = 2) -> int:
    """Render ``count`` engine crops from ``first_seed`` and save their number lines to ``out`` (.npz)."""
    lines, texts, heights = [], [], []
    with Pool(workers) as pool:
        for i, items in enumerate(pool.imap(_render_lines, range(first_seed, first_seed + count), chunksize=8)):
            for line, text, h in items:
                lines.append(line), texts.append(text), heights.append(h)
            if (i + 1) % 500 == 0:
                log.info("rendered %d/%d crops, %d lines", i + 1, count, len(lines))
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out, x=np.stack(lines), t=np.asarray(texts), h=np.asarray(heights, np.float32))
    return len(lines)


SHIPPED_WIDTH = 24  # first-layer channels of the shipped net (48 in earlier versions); loaders read a checkpoint's own


class NumberNet(nn.Module):
    """(N, 1, 32, 128) grey in [0, 1] -> (N, 32, len(CHARS) + 1) CTC logits (blank first)."""

    def __init__(self, width: int = SHIPPED_WIDTH):
        super().__init__()

        def block(cin: int, cout: int) -> nn.Sequential:
            return nn.Sequential(nn.Conv2d(cin, cout, 3, padding=1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(inplace=True))

        w = width
        self.features = nn.Sequential(block(1, w), nn.MaxPool2d(2), block(w, 2 * w), nn.MaxPool2d(2),
                                      block(2 * w, 2 * w), block(2 * w, 4 * w), nn.MaxPool2d((2, 1)),
                                      block(4 * w, 4 * w), nn.MaxPool2d((2, 1)))  # -> (4w, 2, 32)
        self.rnn = nn.GRU(8 * w, 96, bidirectional=True, batch_first=True)
        self.out = nn.Linear(192, len(CHARS) + 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        f = self.features(x).flatten(1, 2).transpose(1, 2)  # (N, 32, 8w)
        return self.out(self.rnn(f)[0])


def width_of(state: dict[str, torch.Tensor]) -> int:
    """The ``width`` a :class:`NumberNet` checkpoint was built with (its first convolution's channels)."""
    return int(state["features.0.0.weight"].shape[0])


def greedy_decode(logits: torch.Tensor) -> list[str]:
    """Best path of (N, T, K) logits: repeats merged, blanks dropped (the runtime's decoding)."""
    return decode_logits(logits.detach().numpy())


def _augmented(line: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    x = line.astype(np.float32)
    if rng.random() < 0.15:
        x = 255.0 - x  # light numbers on a dark face
    x = x * rng.uniform(0.7, 1.3) + rng.uniform(-30, 30)
    if rng.random() < 0.3:
        x = x + rng.normal(0, rng.uniform(2, 10), x.shape)
    return np.clip(x, 0, 255)


def exact_by_height(net: NumberNet, lines: np.ndarray, texts: np.ndarray, heights: np.ndarray) -> dict[str, float]:
    """Share of lines read exactly, per captured-height bin and over all lines of 5 px or more."""
    net.eval()
    read = []
    with torch.no_grad():
        for i in range(0, len(lines), 256):
            read += greedy_decode(net(torch.from_numpy(lines[i:i + 256, None].astype(np.float32) / 255.0)))
    right = np.array([r == t.replace("\u2212", "-") for r, t in zip(read, texts)])
    out = {f"{lo:g}-{hi:g}" if hi < 1e9 else f">={lo:g}": float(right[(heights >= lo) & (heights < hi)].mean())
           for lo, hi in HEIGHT_BINS if ((heights >= lo) & (heights < hi)).any()}
    out["legible"] = float(right[heights >= 5].mean()) if (heights >= 5).any() else float("nan")
    return out


def train_number_net(data: list[Path], val: Path, epochs: int, out: Path, batch: int = 64, lr: float = 2e-3,
                     threads: int = 2, seed: int = 0, repeats: list[int] | None = None, init: Path | None = None,
                     empty_lines: bool = False, width: int = SHIPPED_WIDTH) -> dict[str, float]:
    """Train on the lines of every ``data`` file (file ``k`` taken ``repeats[k]`` times per epoch), keep
    the checkpoint best on ``val`` (legible share) at ``out``. ``init`` starts from a checkpoint;
    with ``empty_lines``, lines labelled "" (no number there: a tick, a ghost box) are learnt as
    reading nothing. ``width`` sets the net's channels (:class:`NumberNet`; its cost grows as the square)."""
    torch.set_num_threads(threads)
    torch.manual_seed(seed)
    val_set = np.load(val)
    parts = [np.load(path) for path in data]
    repeats = repeats or [1] * len(parts)
    lines = np.concatenate([np.repeat(part["x"], n, axis=0) for part, n in zip(parts, repeats, strict=True)])
    texts = np.concatenate([np.repeat(part["t"].astype(str), n) for part, n in zip(parts, repeats, strict=True)])
    keep = np.array([len(encode(t)) > 0 or (empty_lines and t == "") for t in texts])
    lines, texts = lines[keep], texts[keep]
    log.info("%d training lines (%d read as nothing)", len(lines), int(sum(t == "" for t in texts)))
    state = torch.load(init) if init is not None else None
    net = NumberNet(width_of(state) if state is not None else width)
    if state is not None:
        net.load_state_dict(state)
    optimiser = torch.optim.AdamW(net.parameters(), lr, weight_decay=1e-4)
    steps = epochs * (len(lines) // batch)
    schedule = torch.optim.lr_scheduler.OneCycleLR(optimiser, lr, total_steps=steps, pct_start=0.1)
    rng = np.random.default_rng(seed)
    best: dict[str, float] = {"legible": -1.0}
    out.parent.mkdir(parents=True, exist_ok=True)
    for epoch in range(epochs):
        net.train()
        started, total, count = time.monotonic(), 0.0, 0
        order = rng.permutation(len(lines))
        for i in range(0, len(order) - batch + 1, batch):
            pick = order[i:i + batch]
            x = torch.from_numpy(np.stack([_augmented(lines[j], rng) for j in pick])[:, None] / 255.0).float()
            labels = [encode(texts[j]) for j in pick]
            logp = net(x).log_softmax(-1).transpose(0, 1)  # (T, N, K)
            loss = F.ctc_loss(logp, torch.tensor([c for label in labels for c in label], dtype=torch.long),
                              torch.full((len(pick),), logp.shape[0], dtype=torch.long),
                              torch.tensor([len(label) for label in labels]), zero_infinity=True)
            optimiser.zero_grad()
            loss.backward()
            nn.utils.clip_grad_norm_(net.parameters(), 5.0)
            optimiser.step()
            schedule.step()
            total, count = total + loss.item(), count + 1
        metrics = exact_by_height(net, val_set["x"], val_set["t"], val_set["h"])
        log.info("epoch %d/%d loss %.3f (%.0f s) read exactly: %s", epoch + 1, epochs, total / max(1, count),
                 time.monotonic() - started, json.dumps({k: round(v, 3) for k, v in metrics.items()}))
        if metrics["legible"] > best["legible"]:
            best = metrics
            torch.save(net.state_dict(), out)
    return best


def compare_with_ppocr(folder: Path, weights: Path, limit: int | None = None) -> dict[str, dict[str, float]]:
    """Per captured-height bin: the share of the main scale's numbers of a ``gauged synth images``
    folder whose value PP-OCR's recogniser (the reader's) and this net read right, each number cut
    at its true quad the same way for both (no jitter)."""
    from gauged.reader.ocr.engine import OcrEngine
    from gauged.reader.ocr.numbers import parse_number
    from gauged.types import StageFailure

    def value(text: str) -> float | None:
        parsed = parse_number(text)
        return None if isinstance(parsed, StageFailure) else parsed.value

    state = torch.load(weights)
    engine, net = OcrEngine(threads=2), NumberNet(width_of(state))
    net.load_state_dict(state)
    net.eval()
    counts: dict[str, list[int]] = {}
    records = [json.loads(line) for line in (folder / "labels.jsonl").read_text().splitlines()][:limit]
    for record in records:
        gauge = max(record["gauges"], key=lambda g: (g["box"][2] - g["box"][0]) * (g["box"][3] - g["box"][1]))
        image = cv2.imread(str(folder / record["image"]))
        lines = number_lines(image, {"scales": gauge["scales"][:1]}, record.get("render_scale", 1.0))
        if not lines:
            continue
        ppocr = [value(r.text) for r in engine.recognize([line for line, _, _ in lines])]
        with torch.no_grad():
            x = torch.from_numpy(np.stack([to_line_input(line) for line, _, _ in lines])[:, None].astype(np.float32) / 255.0)
            ours = [value(text) for text in greedy_decode(net(x))]
        for (_, text, height), a, b in zip(lines, ppocr, ours):
            truth = value(text)
            lo, hi = next((lo, hi) for lo, hi in HEIGHT_BINS if height < hi)
            row = counts.setdefault(f"{lo:g}-{hi:g}" if hi < 1e9 else f">={lo:g}", [0, 0, 0])
            row[0] += 1
            row[1] += a is not None and truth is not None and abs(a - truth) < 1e-9
            row[2] += b is not None and truth is not None and abs(b - truth) < 1e-9
    names = [f"{lo:g}-{hi:g}" if hi < 1e9 else f">={lo:g}" for lo, hi in HEIGHT_BINS]
    return {k: {"numbers": n, "ppocr": a / n, "number_net": b / n}
            for k in names if k in counts for n, a, b in [counts[k]]}


def export_onnx(weights: Path, out: Path) -> None:
    """The trained net as ONNX (opset 17, any batch size) for :class:`gauged.reader.ocr.number_net.NumberNet`."""
    state = torch.load(weights)
    net = NumberNet(width_of(state))
    net.load_state_dict(state)
    net.eval()
    torch.onnx.export(net, torch.zeros(2, 1, LINE_HEIGHT, LINE_WIDTH), str(out), opset_version=17, input_names=["line"],
                      output_names=["logits"], dynamic_axes={"line": {0: "n"}, "logits": {0: "n"}}, dynamo=False)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="what", required=True)
    data = sub.add_parser("data", help="number lines of engine crops -> .npz")
    data.add_argument("--seed", type=int, required=True, help="first seed (keep clear of the evaluation sets' seeds)")
    data.add_argument("--count", type=int, required=True, help="crops to render")
    data.add_argument("--out", type=Path, required=True)
    reader = sub.add_parser("reader-lines", help="the reader's own recogniser lines of a synth images folder, "
                            "labelled from its truth -> .npz (gauged.training.reader_lines)")
    reader.add_argument("--data", type=Path, required=True, help="a gauged synth images folder (labels.jsonl)")
    reader.add_argument("--out", type=Path, required=True)
    reader.add_argument("--workers", type=int, default=2)
    fit = sub.add_parser("train", help="train the number net")
    fit.add_argument("--data", type=Path, nargs="+", required=True,
                     help="line files: `data`'s true-quad lines and/or `reader-lines`' lines of the reader's own views")
    fit.add_argument("--repeats", type=int, nargs="+", help="times each --data file is taken per epoch (default 1 each)")
    fit.add_argument("--val", type=Path, required=True)
    fit.add_argument("--init", type=Path, help="start from this checkpoint (fine-tuning)")
    fit.add_argument("--lr", type=float, default=2e-3)
    fit.add_argument("--empty-lines", action="store_true", help="learn lines labelled '' as reading nothing")
    fit.add_argument("--epochs", type=int, default=10)
    fit.add_argument("--out", type=Path, required=True, help="checkpoint of the best epoch")
    fit.add_argument("--threads", type=int, default=2)
    fit.add_argument("--width", type=int, default=SHIPPED_WIDTH, help="the net's first-layer channels (default %(default)s, the shipped net's; "
                     "the cost per line grows as its square; an --init checkpoint keeps its own)")
    compare = sub.add_parser("compare", help="PP-OCR's recogniser and the net on a synthetic set's true number quads")
    compare.add_argument("--data", type=Path, required=True, help="a gauged synth images folder (labels.jsonl)")
    compare.add_argument("--weights", type=Path, required=True)
    compare.add_argument("--limit", type=int, help="first N images only")
    export = sub.add_parser("export", help="the trained net as ONNX for the reader")
    export.add_argument("--weights", type=Path, required=True)
    export.add_argument("--out", type=Path, default=Path("gauged/models/numbers.onnx"))
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    if args.what == "export":
        export_onnx(args.weights, args.out)
        log.info("exported %s", args.out)
    elif args.what == "compare":
        for name, row in compare_with_ppocr(args.data, args.weights, args.limit).items():
            print(f"numbers {name:>6} px: {row['numbers']:5d}  PP-OCR {row['ppocr']:.1%}  number net {row['number_net']:.1%}")
    elif args.what == "reader-lines":
        from gauged.training.reader_lines import write_reader_lines

        why = write_reader_lines(args.data, args.out, args.workers, progress=log.info)
        log.info("lines seen: %s", json.dumps(dict(why)))
    elif args.what == "data":
        log.info("wrote %d number lines to %s", write_lines(args.seed, args.count, args.out), args.out)
    else:
        if args.repeats and len(args.repeats) != len(args.data):
            parser.error("--repeats needs one count per --data file")
        best = train_number_net(args.data, args.val, args.epochs, args.out, lr=args.lr, threads=args.threads,
                                repeats=args.repeats, init=args.init, empty_lines=args.empty_lines,
                                width=args.width)
        log.info("best: %s", json.dumps(best))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
