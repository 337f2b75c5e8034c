"""Needle mask IoU of crop models at several logit cuts, on the needle-polygons photos.

    python bench/investigations/needle_threshold.py gauged/models/crop.onnx [runs/crop-v9/crop.onnx ...]
        [--data ../shared/datasets/needle-polygons] [--cuts -1.5 -1 -0.5 0 0.25]

Each photo is given whole to the crop model (resized to its input, as `gauged eval models` does),
the needle logits are resized to the photo and cut at each value (0 is probability 0.5, the cut the
evaluation and the reader use), and the mean IoU with the labelled mask is printed for the `train`
split (where a cut would be chosen) and the `valid` split (where it is reported).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
import cv2  # noqa: E402
import numpy as np  # noqa: E402
from common import header  # noqa: E402

from gauged.evaluation.model_metrics import mask_iou  # noqa: E402
from gauged.evaluation.models import whole_photo_needle_logits  # noqa: E402
from gauged.reader.onnx_model import OnnxModel  # noqa: E402
from gauged.training.real_data import load_needle_split  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("models", nargs="+", type=Path, help="crop model ONNX files")
    parser.add_argument("--data", type=Path, default=Path("../shared/datasets/needle-polygons"))
    parser.add_argument("--cuts", nargs="+", type=float, default=[-1.5, -1.0, -0.5, 0.0, 0.25])
    args = parser.parse_args()
    if not (args.data / "valid").is_dir():
        parser.error(f"{args.data} holds no needle-polygons valid split")
    header("needle mask IoU by logit cut")
    for path in args.models:
        crop = OnnxModel(path, threads=2)
        for split in ("train", "valid"):
            ious: dict[float, list[float]] = {cut: [] for cut in args.cuts}
            for sample in load_needle_split(args.data, split):
                image, mask = sample.load()
                logits = np.asarray(whole_photo_needle_logits(crop, image), np.float32)
                up = cv2.resize(logits, (mask.shape[1], mask.shape[0]), interpolation=cv2.INTER_LINEAR)
                for cut in args.cuts:
                    ious[cut].append(mask_iou(up > cut, mask > 0))
            row = "  ".join(f"{cut:+.2f}: {np.mean(v):.4f}" for cut, v in ious.items())
            print(f"{path} {split} ({len(ious[args.cuts[0]])} photos)  {row}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
