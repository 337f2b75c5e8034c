"""Where the crop model's major-notch misses are: weak peaks, misplaced peaks, or no response at all.

    python bench/investigations/notch_misses.py --shard data/synth-val-256 [--model gauged/models/crop.onnx]

``--shard`` is a crop shard of the synthetic engine (`python -m gauged.training.prerender crops
--seed 1000000 --count 500 --size 256 --out data/synth-val-256`, the held-out crops `gauged eval
models` scores). Tolerances are issue 4's 4 px at 448 px, scaled to the crop size. For every
labelled major notch it prints:

- the share with any heatmap cell of at least p (0.05 .. 0.3) within the tolerance (+1 px at the model's input, for the
  cell grid), i.e. whether the model responds there at all;
- the share whose nearest peak (:func:`gauged.reader.stages.keypoints.find_peaks`, at the reader's
  threshold 0.3 and at 0.1, neighbourhood 2 cells as the reader and 1) lies within 1x and 2x the tolerance;
- the peaks more than 2x the tolerance from every label (false peaks: medium ticks, numbers, the
  needle), as a share of all peaks.

Split by how the engine captured the crop (full size, or rendered small and upsampled).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # bench/, for common
import numpy as np  # noqa: E402
from common import header  # noqa: E402

from gauged.evaluation.models import render_scale  # noqa: E402
from gauged.reader.onnx_model import OnnxModel, to_model_input  # noqa: E402
from gauged.reader.stages.keypoints import CROP_CHANNELS, find_peaks, sigmoid  # noqa: E402
from gauged.training.shards import open_crop_shard  # noqa: E402

MAJOR = CROP_CHANNELS.index("major")
LEVELS = (0.05, 0.1, 0.2, 0.3)
PEAKS = ((0.3, 2), (0.3, 1), (0.1, 2), (0.1, 1))  # (threshold, neighbourhood in cells)


def crop_maps(model: OnnxModel, shard_dir: Path) -> list[tuple[np.ndarray, np.ndarray, str]]:
    """(major-notch probability map, labelled majors (N, 2), capture group) per crop of the shard."""
    shard = open_crop_shard(shard_dir)
    out = []
    for index in range(len(shard)):
        sample = shard.sample(index)
        if sample.image.shape[0] != model.input_size:
            raise SystemExit(f"{shard_dir} holds {sample.image.shape[0]} px crops; the model takes {model.input_size}")
        labels = np.asarray(sample.points.get("major") or [], float).reshape(-1, 2)
        captured = render_scale(sample.source, sample.image.shape[0])
        group = "full size" if captured == 1.0 else "upsampled" if captured is not None else "other"
        out.append((sigmoid(model(to_model_input(sample.image))[MAJOR]), labels, group))
    return out


def report(maps: list[tuple[np.ndarray, np.ndarray, str]], stride: int, tol: float) -> None:
    near_levels, nearest, false_peaks = [], {key: [] for key in PEAKS}, {key: [0, 0] for key in PEAKS}
    for prob, labels, _ in maps:
        rows, cols = np.indices(prob.shape)
        centres = np.stack([stride * (cols + 0.5), stride * (rows + 0.5)], axis=-1)
        for label in labels:
            near = np.linalg.norm(centres - label, axis=-1) <= tol + 1.0
            near_levels.append(prob[near].max() if near.any() else 0.0)
        for key in PEAKS:
            peaks = find_peaks(prob, stride, key[0], 64, key[1]).points
            if len(labels) and len(peaks):
                dist = np.linalg.norm(labels[:, None] - peaks[None], axis=2)
                nearest[key] += list(dist.min(axis=1))
                false_peaks[key][0] += int((dist.min(axis=0) > 2 * tol).sum())
            else:
                nearest[key] += [np.inf] * len(labels)
                false_peaks[key][0] += len(peaks)
            false_peaks[key][1] += len(peaks)
    levels = np.asarray(near_levels)
    print(f"  labelled majors {len(levels)}; a cell >= p within the tolerance: "
          + ", ".join(f"p {p}: {(levels >= p).mean():.1%}" for p in LEVELS))
    for key in PEAKS:
        d = np.asarray(nearest[key])
        wrong, total = false_peaks[key]
        print(f"  peaks at {key[0]} (neighbourhood {key[1]}): nearest within tol {(d <= tol).mean():.1%}, "
              f"within 2 tol {(d <= 2 * tol).mean():.1%}; peaks > 2 tol from every label {wrong}/{total} "
              f"({wrong / max(1, total):.1%})")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--shard", type=Path, required=True, help="crop shard of the synthetic engine")
    parser.add_argument("--model", type=Path, default=Path("gauged/models/crop.onnx"))
    args = parser.parse_args()
    if not (args.shard / "labels.jsonl").is_file():
        parser.error(f"{args.shard} is not a crop shard (no labels.jsonl); make one with gauged.training.prerender crops")
    header("where the major-notch misses are")
    model = OnnxModel(args.model, threads=2)
    size = model.input_size
    maps = crop_maps(model, args.shard)
    stride = size // maps[0][0].shape[0]
    tol = 4.0 * size / 448
    print(f"# {len(maps)} crops at {size} px, output stride {stride}, tolerance {tol:.2f} px (4 px at 448)")
    for group in ("all", "full size", "upsampled"):
        chosen = [m for m in maps if group == "all" or m[2] == group]
        if chosen:
            print(f"{group} ({len(chosen)} crops)")
            report(chosen, stride, tol)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
