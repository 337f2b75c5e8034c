"""What the needle IoU line could get from the output grid, from flips, and from averaging crop models.

    python bench/investigations/needle_combos.py [--models gauged/models/crop.onnx runs/crop-r1/crop.onnx ...]

On the needle-polygons ``valid`` photos (and, where a choice would be made, on every third photo of
``train``, one copy per source photo), each photo given whole to the crop model as ``gauged eval
models`` gives it, mean mask IoU at the photo's resolution of:

- the output grid itself: each label drawn at the model's input, averaged to the output grid, and
  cut again after the evaluation's bilinear resize (``needle_mask_at``): the IoU a model whose logits
  were exactly its coverage would score, i.e. what the grid alone costs;
- each model, each model with a horizontal flip averaged in (two runs per read), and the logits of
  all the models averaged, with and without flips.
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
from gauged.reader.onnx_model import OnnxModel, to_model_input  # noqa: E402
from gauged.training.real_data import load_needle_split, photo_group  # noqa: E402
from gauged.training.targets import downsample_mask  # noqa: E402


def one_per_photo(samples, every: int):
    """Every ``every``-th source photo of a split, one augmented copy each."""
    seen, kept = set(), []
    for sample in samples:
        group = photo_group(sample.image_path)
        if group not in seen:
            seen.add(group)
            kept.append(sample)
    return kept[::every]


def needle_logits(model: OnnxModel, image: np.ndarray, flip: bool) -> np.ndarray:
    """The needle logits of the photo given whole, as ``gauged eval models`` gives it; with ``flip``, of
    its model input mirrored left to right, mirrored back."""
    if not flip:
        return whole_photo_needle_logits(model, image)
    size = model.input_size
    x = cv2.resize(image, (size, size), interpolation=cv2.INTER_AREA)
    return model(to_model_input(np.ascontiguousarray(x[:, ::-1])))[-1][:, ::-1]


def grid_iou(mask: np.ndarray, size: int, stride: int) -> float:
    """IoU of the label through the output grid: drawn at the model's input, averaged to the grid as the
    training targets are (``downsample_mask``), resized back and cut as the evaluation cuts."""
    truth = (mask > 0).astype(np.float32)
    coverage = downsample_mask(cv2.resize(truth, (size, size), interpolation=cv2.INTER_AREA), stride)
    return mask_iou(needle_mask_at(coverage - 0.5, mask.shape), truth > 0)


def scores(models: dict[str, OnnxModel], samples) -> dict[str, float]:
    names = list(models)
    size = models[names[0]].input_size
    combos = {name: [(name, False)] for name in names}
    combos.update({f"{name} + flip": [(name, False), (name, True)] for name in names})
    if len(names) > 1:
        combos["all averaged"] = [(name, False) for name in names]
        combos["all averaged + flips"] = [(name, flip) for name in names for flip in (False, True)]
    stride = size // models[names[0]](to_model_input(np.zeros((size, size, 3), np.uint8))).shape[-1]
    ious: dict[str, list[float]] = {"output grid (labels)": []}
    for sample in samples:
        image, mask = sample.load()
        truth = mask > 0
        ious["output grid (labels)"].append(grid_iou(mask, size, stride))
        logits = {(name, flip): needle_logits(model, image, flip) for name, model in models.items() for flip in (False, True)}
        for combo, parts in combos.items():
            averaged = np.mean([logits[part] for part in parts], axis=0)
            ious.setdefault(combo, []).append(mask_iou(needle_mask_at(averaged, truth.shape), truth))
    return {combo: float(np.mean(values)) for combo, values in ious.items()}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path("../shared/datasets/needle-polygons"))
    parser.add_argument("--models", type=Path, nargs="+", default=[Path("gauged/models/crop.onnx")],
                        help="crop model files (the same input size)")
    parser.add_argument("--train-every", type=int, default=3, help="score every N-th train photo too (0: valid only)")
    args = parser.parse_args()
    if not (args.data / "valid").is_dir():
        parser.error(f"no needle-polygons valid split under {args.data} (it lives in ../shared/datasets)")
    header("the needle IoU from the output grid, flips and averaged crop models")
    models = {str(path): OnnxModel(path, threads=2) for path in args.models}
    splits = {"valid": load_needle_split(args.data, "valid")}
    if args.train_every:
        splits[f"train (1 photo in {args.train_every})"] = one_per_photo(load_needle_split(args.data, "train"), args.train_every)
    for split, samples in splits.items():
        print(f"{split}, {len(samples)} photos")
        for combo, iou in scores(models, samples).items():
            print(f"  {combo}: {iou:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
