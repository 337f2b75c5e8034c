"""Train the gauge detector (CenterNet on an EfficientNet-Lite0 encoder) and export ONNX.

    python -m gauged.training.train_detector --synth data/det-synth-320 [data/det-closeup-320 ...] \
        --real ../shared/datasets/substation-dials --real-fold A --run runs/det --export runs/det/detector.onnx \
        [--init gauged/models/detector.onnx]

Real substation frames are split into two folds by frame number (A: first half, B: second half, so
neighbouring frames of one camera stay together); the model trains on synthetic scenes plus one fold
and is validated on the other, so the figure it reports is on frames it never saw.
"""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

import cv2
import numpy as np
import torch

from gauged.evaluation.model_metrics import best_iou
from gauged.reader.stages.detect import Letterbox, decode_detections
from gauged.training.augment import photometric
from gauged.training.loop import TrainSettings, train
from gauged.training.losses import detector_loss
from gauged.training.nets import DetNet, count_parameters
from gauged.training.real_data import DialSample, load_substation_dials
from gauged.training.shards import open_detector_shard
from gauged.training.targets import detector_targets

log = logging.getLogger(__name__)
STRIDE = 8


def fold(samples: list[DialSample], name: str) -> list[DialSample]:
    half = len(samples) // 2
    return samples[:half] if name == "A" else samples[half:]


def real_example(sample: DialSample, image: np.ndarray, size: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A random zoom window of a real frame that keeps the dial whole, letterboxed to ``size``."""
    h, w = image.shape[:2]
    x0, y0, x1, y1 = sample.box
    zoom = rng.uniform(1.0, 2.5)
    win_w, win_h = w / zoom, h / zoom
    win_w, win_h = max(win_w, (x1 - x0) * 1.1), max(win_h, (y1 - y0) * 1.1)
    left = rng.uniform(max(0, x1 - win_w), max(0, min(x0, w - win_w)) + 1e-6)
    top = rng.uniform(max(0, y1 - win_h), max(0, min(y0, h - win_h)) + 1e-6)
    crop = image[int(top):int(top + win_h), int(left):int(left + win_w)]
    box = np.array([[x0 - int(left), y0 - int(top), x1 - int(left), y1 - int(top)]], float)
    if rng.random() < 0.5:
        crop = crop[:, ::-1]
        box = np.array([[crop.shape[1] - box[0, 2], box[0, 1], crop.shape[1] - box[0, 0], box[0, 3]]])
    letterbox = Letterbox.fit(crop.shape[1], crop.shape[0], size)
    boxed = letterbox.apply(np.ascontiguousarray(crop))
    return photometric(boxed, rng), box * letterbox.scale + [letterbox.dx, letterbox.dy, letterbox.dx, letterbox.dy]


def to_tensor(image: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(image[:, :, ::-1].astype(np.float32).transpose(2, 0, 1) / 255.0)


def make_batches(shards, real: list[tuple[DialSample, np.ndarray]], size: int, batch: int, seed: int, real_repeats: int):
    def batches(epoch: int):
        rng = np.random.default_rng(seed * 1000 + epoch)
        entries = [(k, i) for k, shard in enumerate(shards) for i in range(len(shard))]
        entries += [("r", i) for i in range(len(real)) for _ in range(real_repeats)]
        order = rng.permutation(len(entries))
        for start in range(0, len(order) - batch + 1, batch):
            xs, ms, ws = [], [], []
            for kind, index in (entries[k] for k in order[start:start + batch]):
                if kind != "r":
                    sample = shards[kind].sample(index)
                    image = photometric(sample.image, rng) if rng.random() < 0.5 else sample.image
                    boxes = np.asarray(sample.boxes, float).reshape(-1, 4)
                else:
                    image, boxes = real_example(real[index][0], real[index][1], size, rng)
                maps, weight = detector_targets(boxes, size, STRIDE)
                xs.append(to_tensor(image)), ms.append(maps), ws.append(weight)
            x = torch.from_numpy(np.stack(xs)).contiguous(memory_format=torch.channels_last)
            yield x, torch.from_numpy(np.stack(ms)), torch.from_numpy(np.stack(ws))
    return batches


def validate_detector(model, frames: list[tuple[DialSample, np.ndarray]], size: int) -> dict[str, float]:
    ious = []
    with torch.no_grad():
        for sample, image in frames:
            letterbox = Letterbox.fit(image.shape[1], image.shape[0], size)
            maps = model(torch.from_numpy(to_tensor(letterbox.apply(image))[None]))[0].numpy()
            boxes, _ = decode_detections(maps, STRIDE)
            ious.append(best_iou(sample.box, letterbox.boxes_to_frame(boxes)))
    ious_arr = np.asarray(ious)
    mean_iou, recall = float(ious_arr.mean()), float((ious_arr >= 0.5).mean())
    return {"mean_box_iou": mean_iou, "recall_iou50": recall, "score": (mean_iou + recall) / 2}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--synth", type=Path, nargs="+", required=True,
                        help="synthetic detector shards (scenes, close-ups)")
    parser.add_argument("--real", type=Path, help="substation-dials folder")
    parser.add_argument("--real-fold", choices=("A", "B", "all"), default="A", help="real fold to train on")
    parser.add_argument("--real-repeats", type=int, default=8, help="times each real frame appears per epoch")
    parser.add_argument("--run", type=Path, required=True)
    parser.add_argument("--size", type=int, default=320)
    parser.add_argument("--epochs", type=int, default=8)
    parser.add_argument("--batch", type=int, default=16)
    parser.add_argument("--lr", type=float, default=2e-3)
    parser.add_argument("--scratch", action="store_true")
    parser.add_argument("--init", type=Path, help="start from this checkpoint's weights, or from a shipped ONNX "
                        "export of the same architecture (gauged/models/detector.onnx)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--export", type=Path)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    torch.set_num_threads(args.threads)
    shards = [open_detector_shard(path) for path in args.synth]
    real_train, real_val = [], []
    if args.real:
        dials = load_substation_dials(args.real)
        load = lambda samples: [(s, cv2.imread(str(s.image_path), cv2.IMREAD_COLOR)) for s in samples]  # noqa: E731
        if args.real_fold == "all":
            real_train, real_val = load(dials), load(dials)
        else:
            real_train, real_val = load(fold(dials, args.real_fold)), load(fold(dials, "B" if args.real_fold == "A" else "A"))
    # Any --init sets every weight, so the ImageNet ones are not loaded first.
    model = DetNet(args.size, pretrained=not (args.scratch or args.init)).to(memory_format=torch.channels_last)
    if args.init:
        from gauged.training.from_onnx import initialise

        log.info(initialise(model, args.init, lambda: torch.from_numpy(np.stack(
            [to_tensor(shards[0].sample(i).image) for i in range(min(48, len(shards[0])))]))))
    synthetic = sum(len(shard) for shard in shards)
    log.info("detector: %d parameters; %d synthetic + %d real frames (x%d), %d validation frames",
             count_parameters(model), synthetic, len(real_train), args.real_repeats, len(real_val))
    steps = (synthetic + len(real_train) * args.real_repeats) // args.batch
    best = train(model, make_batches(shards, real_train, args.size, args.batch, 0, args.real_repeats), steps,
                 lambda m, b: detector_loss(m(b[0]), b[1], b[2]), lambda m: validate_detector(m, real_val, args.size),
                 TrainSettings(epochs=args.epochs, lr=args.lr), args.run)
    log.info("best: %s", json.dumps(best))
    if args.export:
        from gauged.training.train_crop import export_onnx

        state = torch.load(args.run / "best.pt", map_location="cpu", weights_only=False)
        model.load_state_dict(state["model"])
        export_onnx(model, args.size, args.export, {"kind": "detector", "size": args.size, "stride": STRIDE,
                                                    "metrics": best, "real_fold": args.real_fold,
                                                    "synth": [str(path) for path in args.synth],
                                                    "init": str(args.init) if args.init else ("scratch" if args.scratch else "imagenet")})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
