"""Where a crop model's needle mask IoU is lost on the needle-polygons photos: at the edge or far from it.

    python bench/investigations/needle_errors.py [gauged/models/crop.onnx] [--data ../shared/datasets/needle-polygons]

Each photo is given whole to the crop model, as `gauged eval models` does, and the needle logits
are resized to the photo and cut at 0. Every wrong pixel is then sorted:

- *at the edge*: a missed label pixel within half the labelled needle's width of the predicted
  mask, or a predicted pixel within that distance of the label. The outline is drawn a pixel or
  so off, on a needle that is a few pixels wide.
- *far*: every other wrong pixel. These are whole parts of the needle missed (a tip, the end at the
  hub, a needle not seen) or strokes taken for it.

Per split, the script prints the mean IoU; the wrong pixels of each kind; the pooled IoU with
either kind put right (an upper bound on what fixing it could give); and the mean IoU by
labelled needle width. The `train` split holds three augmented copies of each photo.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
import cv2  # noqa: E402
import numpy as np  # noqa: E402
from common import header  # noqa: E402

from gauged.evaluation.model_metrics import mask_iou, needle_mask_at  # noqa: E402
from gauged.evaluation.models import whole_photo_needle_logits  # noqa: E402
from gauged.reader.onnx_model import OnnxModel  # noqa: E402
from gauged.training.real_data import load_needle_split  # noqa: E402

WIDTH_BINS = ((0.0, 3.0), (3.0, 4.5), (4.5, 6.0), (6.0, np.inf))  # labelled needle width, photo px


def needle_width(mask: np.ndarray) -> float:
    """Twice the median distance of the mask's pixels to its outline: the needle's typical width."""
    inside = cv2.distanceTransform(mask.astype(np.uint8), cv2.DIST_L2, 3)
    return 2.0 * float(np.median(inside[mask > 0])) if mask.any() else 0.0


def error_kinds(predicted: np.ndarray, labelled: np.ndarray, width: float) -> dict[str, int]:
    """Right, and wrong pixels at the edge or far from it (see the module docstring); ``width`` is
    the labelled needle's (:func:`needle_width`)."""
    predicted, labelled = predicted.astype(np.uint8), labelled.astype(np.uint8)
    edge = max(width / 2.0, 1.0)
    to_label = cv2.distanceTransform(1 - labelled, cv2.DIST_L2, 3)
    to_prediction = cv2.distanceTransform(1 - predicted, cv2.DIST_L2, 3)
    extra = (predicted == 1) & (labelled == 0)
    missed = (predicted == 0) & (labelled == 1)
    return {"right": int((predicted & labelled).sum()),
            "extra at edge": int((to_label[extra] <= edge).sum()), "extra far": int((to_label[extra] > edge).sum()),
            "missed at edge": int((to_prediction[missed] <= edge).sum()), "missed far": int((to_prediction[missed] > edge).sum())}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("model", nargs="?", type=Path, default=Path("gauged/models/crop.onnx"))
    parser.add_argument("--data", type=Path, default=Path("../shared/datasets/needle-polygons"))
    args = parser.parse_args()
    if not (args.data / "valid").is_dir():
        parser.error(f"{args.data} holds no needle-polygons valid split")
    header("needle mask IoU: errors at the edge and far from it")
    crop = OnnxModel(args.model, threads=2)
    for split in ("train", "valid"):
        ious, widths = [], []
        totals = dict.fromkeys(("right", "extra at edge", "extra far", "missed at edge", "missed far"), 0)
        for sample in load_needle_split(args.data, split):
            image, labelled = sample.load()
            predicted = needle_mask_at(whole_photo_needle_logits(crop, image), labelled.shape)
            ious.append(mask_iou(predicted, labelled))
            widths.append(needle_width(labelled))
            for kind, count in error_kinds(predicted, labelled, widths[-1]).items():
                totals[kind] += count
        ious_a, widths_a = np.array(ious), np.array(widths)
        right = totals["right"]
        edge, far = totals["extra at edge"] + totals["missed at edge"], totals["extra far"] + totals["missed far"]
        print(f"{split} ({len(ious)} photos): mean IoU {ious_a.mean():.3f}, median {np.median(ious_a):.3f}")
        print("  wrong pixels: " + ", ".join(f"{kind} {totals[kind]}" for kind in list(totals)[1:]))
        print(f"  pooled IoU {right / (right + edge + far):.3f}; with the edge errors put right "
              f"{(right + totals['missed at edge']) / (right + totals['missed at edge'] + far):.3f}, "
              f"with the far ones {(right + totals['missed far']) / (right + totals['missed far'] + edge):.3f}")
        for low, high in WIDTH_BINS:
            chosen = (widths_a >= low) & (widths_a < high)
            if chosen.any():
                print(f"  needles {low:g}-{high:g} px wide: {chosen.sum()} photos, mean IoU {ious_a[chosen].mean():.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
